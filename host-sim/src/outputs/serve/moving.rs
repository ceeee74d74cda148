//! The live map's moving emitters: every channel tracked as the bearings arrive (the live
//! tracker of `foxhunt track -`, [`crate::track::live`]), each track drawn with its current
//! 95 % ellipse and a velocity arrow on the channels whose bearings the field pipeline finds
//! moving (where it gives a fix, the emitter stands still and the fix is drawn instead).

use crate::estimate::stations::station_setup;
use crate::inputs::capture::Decoded;
use crate::inputs::stations::Network;
use crate::locate::report::geodetic;
use crate::outputs::maps::ellipse_ring;
use crate::track::live::{LiveChannels, Ready};
use crate::track::moving::TrackPoint;
use crate::track::tracks::{Options, WIDTH_MHZ, offset_prior};
use foxhunt_bridge::geo::LocalFrame;
use serde::Serialize;

/// Track points kept per channel for the line (thinned to every other beyond).
const TRACK_POINTS: usize = 2000;
/// The velocity arrow shows where the emitter will be this many seconds on.
pub const ARROW_S: f32 = 60.0;

/// A moving emitter on the map.
#[derive(Debug, Clone, Serialize)]
pub struct MapTrack {
    /// Its channel's frequency, MHz.
    pub freq_mhz: Option<f32>,
    /// The track so far (thinned evenly beyond `TRACK_POINTS`).
    pub line: Vec<[f64; 2]>,
    /// Where it is now.
    pub at: [f64; 2],
    /// The current 95 % ellipse (closed ring; empty when the covariance gives none).
    pub ellipse: Vec<[f64; 2]>,
    /// From where it is to where its velocity takes it in [`ARROW_S`] seconds.
    pub arrow: [[f64; 2]; 2],
    /// Speed, m/s.
    pub speed_mps: f32,
    /// Heading, degrees clockwise from north.
    pub heading_deg: f32,
    /// P(moving).
    pub p_moving: f32,
}

/// One channel's points.
#[derive(Debug, Clone, Default)]
struct Line {
    freq_mhz: Option<f32>,
    points: Vec<TrackPoint>,
    /// Keep every `stride`-th point.
    stride: usize,
    seen: usize,
    last: Option<TrackPoint>,
}

impl Line {
    fn push(&mut self, p: TrackPoint) {
        self.stride = self.stride.max(1);
        if self.seen.is_multiple_of(self.stride) {
            self.points.push(p);
        }
        self.seen += 1;
        self.last = Some(p);
        if self.points.len() >= TRACK_POINTS {
            // Every other point, and half as many from now on: bounded however long.
            let mut k = 0;
            self.points.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
        }
    }
}

/// Every channel tracked as its bearings arrive, as `foxhunt track -` tracks them with the
/// same stations file: each station's stated noise and class, its offset prior, its stated
/// direction-dependent error.
pub struct MapTracker {
    live: LiveChannels,
    lines: Vec<Line>,
    /// Observations already handed to the trackers.
    taken: usize,
    options: Options,
}

impl Default for MapTracker {
    fn default() -> Self {
        Self::new(None)
    }
}

impl MapTracker {
    /// Trackers at `track`'s defaults, each station as `network` (a stations file) states it.
    pub fn new(network: Option<&Network>) -> Self {
        let options = Options {
            network: network.cloned(),
            ..Options::default()
        };
        Self {
            live: LiveChannels::for_options(&options),
            lines: Vec::new(),
            taken: 0,
            options,
        }
    }

    /// Track the bearings `d` gained since the last call; `end`: the input ended, so the
    /// open updates close.
    pub fn update(&mut self, d: &Decoded, end: bool) {
        let mut new = d.observations[self.taken.min(d.observations.len())..].to_vec();
        self.taken = d.observations.len();
        new.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let fallback = self.options.fallback();
        let ids = d.stations.iter().map(|s| s.id.as_str());
        let setup = station_setup(ids, self.options.network.as_ref(), fallback, false);
        // A channel or station beyond the live tracker's is left off the map's tracks (the
        // field pipeline still has its bearings); an unstated station's noise is estimated.
        let mut ready: Vec<Ready> = new
            .into_iter()
            .filter_map(|o| self.live.push_stated(o, None, &setup).ok().flatten())
            .collect();
        if end {
            ready.extend(self.live.close());
        }
        let prior_of = |s: u16| offset_prior(&setup, usize::from(s));
        for r in ready {
            let Ok(Some(p)) = self.live.step(r, &prior_of) else {
                continue;
            };
            if self.lines.len() <= r.channel {
                self.lines.resize_with(r.channel + 1, Line::default);
            }
            let line = &mut self.lines[r.channel];
            line.freq_mhz = r.freq_mhz;
            line.push(p);
        }
    }

    /// The tracks of the channels at `freqs` (MHz; `None`: the channel without one), placed
    /// by `frame`.
    pub fn tracks(&self, frame: &LocalFrame, freqs: &[Option<f32>]) -> Vec<MapTrack> {
        let ll = |p: [f32; 2]| {
            let g = geodetic(frame, p);
            [g.lat, g.lon]
        };
        let same = |a: Option<f32>, b: Option<f32>| match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= WIDTH_MHZ,
            (None, None) => true,
            _ => false,
        };
        self.lines
            .iter()
            .filter(|l| freqs.iter().any(|f| same(*f, l.freq_mhz)))
            .filter_map(|l| {
                let p = l.last?;
                let ahead = [
                    p.position[0] + ARROW_S * p.velocity[0],
                    p.position[1] + ARROW_S * p.velocity[1],
                ];
                Some(MapTrack {
                    freq_mhz: l.freq_mhz,
                    line: l
                        .points
                        .iter()
                        .chain(l.last.as_ref())
                        .map(|q| ll(q.position))
                        .collect(),
                    at: ll(p.position),
                    ellipse: p
                        .ellipse()
                        .map(|e| ellipse_ring(p.position, &e).into_iter().map(ll).collect())
                        .unwrap_or_default(),
                    arrow: [ll(p.position), ll(ahead)],
                    speed_mps: p.velocity[0].hypot(p.velocity[1]),
                    heading_deg: p.velocity[0]
                        .atan2(p.velocity[1])
                        .to_degrees()
                        .rem_euclid(360.0),
                    p_moving: p.p_moving,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runs::moving::MovingScenario;
    use crate::track::capture::measure;
    use crate::track::tracks::tracks;

    #[test]
    fn the_map_tracks_each_station_as_the_stations_file_states_it() {
        // Four wall anchors' arrays watching a walker; the file states their class alone
        // (twice their noise, a wider offset prior, a short memory: `DeviceClass::track`).
        let scenario = MovingScenario::named("move-indoor-aoa").unwrap();
        let run = crate::runs::moving::capture(&scenario, 1, crate::runs::simulate::DEFAULT_ORIGIN)
            .unwrap();
        let m = measure(&run.bytes, None);
        let class = Network::from_text("[default]\nantenna = \"indoor-aoa\"\n").unwrap();
        let o = Options {
            network: Some(class.clone()),
            ..Options::default()
        };
        let recorded = tracks(&m, None, &o).unwrap();
        let want = &recorded.tracks[0].points;
        let mut map = MapTracker::new(Some(&class));
        map.update(&m.decoded, true);
        let got = &map.lines[0];
        println!(
            "{} map points, {} recorded; last {:?} against {:?}",
            got.seen,
            want.len(),
            got.last.map(|p| p.position),
            want.last().map(|p| p.position)
        );
        // `foxhunt track --stations`'s track, point for point: the map's trackers are track's.
        assert_eq!(got.seen, want.len());
        assert_eq!(got.last.as_ref(), want.last());
        // Without the file the class is not known and the track is another.
        let mut plain = MapTracker::default();
        plain.update(&m.decoded, true);
        assert_ne!(plain.lines[0].last, got.last);
    }
}
