//! A capture's measurements as the tracker's updates, one list per channel: bearings grouped
//! by frequency as `locate` groups them, each channel's bearings within [`WINDOW_S`] of each
//! other one update, its DF sources numbered from 0, and the anchors' RSSI readings placed by
//! their time (after the GPS fix before them) or, in a capture without GPS, one reading per
//! anchor per epoch as the indoor tracker has always taken them.

use crate::estimate::Priors;
use crate::track::capture::{Measured, Reading};
use crate::track::direction::Directions;
use crate::track::indoor::AnchorsFile;
use crate::track::moving::{K, Update, max_sources};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::channel::{NO_CHANNEL, group};
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::track::{Epoch, Level};

/// Bearings no more than this many seconds after an update's first belong to it (stations
/// reporting "once a second" are rarely in step to the millisecond).
pub const WINDOW_S: f32 = 0.25;
/// Channels a capture may hold.
const CHANNELS: usize = 16;

/// One channel's updates.
#[derive(Debug, Clone)]
pub struct Channel {
    /// Its frequency, MHz (none for bearings without one, or RSSI alone).
    pub freq_mhz: Option<f32>,
    /// The updates, in time order.
    pub updates: Vec<Update>,
    /// DF stations with bearings here, by their number in the updates (the capture's own
    /// station index of each).
    pub sources: Vec<u16>,
    /// Whether RSSI readings are in the updates.
    pub rssi: bool,
    /// With RSSI: the anchors, in the track's frame (where a track that starts from readings
    /// starts: about them).
    pub anchors: Vec<[f32; 2]>,
    /// Stations left out (beyond [`max_sources`], the fewest bearings first) and their
    /// bearings.
    pub left_out: (usize, usize),
}

/// Where the anchors are in the track's frame, and that frame: the capture's GPS frame when it
/// has one (the anchors file then needs its origin), else the anchors file's own metres.
pub fn anchor_positions(
    file: &AnchorsFile,
    frame: Option<&LocalFrame>,
) -> Result<Vec<[f32; 2]>, String> {
    let local: Vec<[f32; 2]> = file.anchor.iter().map(|a| [a.x, a.y]).collect();
    let Some(frame) = frame else {
        return Ok(local);
    };
    let Some([lat, lon]) = file.origin else {
        return Err(
            "the capture has GPS positions: give the anchors file an `origin = [lat, lon]` so \
             its anchors can be placed beside them"
                .into(),
        );
    };
    let own = LocalFrame::new(LatLon { lat, lon }, 0.0)
        .map_err(|_| format!("the anchors file's origin {lat}, {lon} is out of range"))?;
    local
        .iter()
        .map(|p| {
            let g = own
                .to_geodetic([f64::from(p[0]), f64::from(p[1])])
                .map_err(|_| "an anchor is out of range".to_string())?;
            let l = frame
                .to_local(g)
                .map_err(|_| "an anchor is out of range".to_string())?;
            Ok([l[0] as f32, l[1] as f32])
        })
        .collect()
}

/// The measurements of `m` as updates, one list per channel. `noise`: by station index, the
/// noise (radians) of that station's bearings instead of their own; then each station's
/// direction-dependent error as `priors` state it taken out ([`Directions`]), in time order
/// as a live line takes them.
pub fn channels(
    m: &Measured,
    anchors: Option<&AnchorsFile>,
    width_mhz: f32,
    noise: &[Option<f32>],
    priors: &Priors,
) -> Result<Vec<Channel>, String> {
    let mut obs = m.decoded.observations.clone();
    obs.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut directions = Directions::default();
    for o in obs.iter_mut() {
        if let Some(Some(s)) = noise.get(usize::from(o.station)) {
            o.bearing.sigma = *s;
        }
        directions.correct(o, priors);
    }
    let obs = &obs;
    let n = obs.len();
    // Readings may join a channel's bearings, and their terms then take room in the state.
    let rssi_may_join = anchors.is_some() && !m.readings.is_empty();
    let mut order = vec![0u32; n];
    let mut of = vec![NO_CHANNEL; n];
    let groups = group::<CHANNELS>(n, |i| Some(obs[i].freq_mhz), width_mhz, &mut order, &mut of)
        .map_err(|e| format!("cannot group the bearings by frequency: {e}"))?;
    let mut out = Vec::new();
    // Each channel's bearings as its updates hold them (renumbered), for RSSI to join.
    let mut kept: Vec<Vec<Observation>> = Vec::new();
    for c in 0..groups.len() {
        let mut mine: Vec<Observation> = obs
            .iter()
            .zip(&of)
            .filter(|(_, k)| usize::from(**k) == c)
            .map(|(o, _)| *o)
            .collect();
        mine.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let (sources, left_out) = most_heard(&mut mine, max_sources(rssi_may_join));
        out.push(Channel {
            freq_mhz: groups.freq(c).flatten(),
            updates: bearing_updates(&mine),
            sources,
            rssi: false,
            anchors: Vec::new(),
            left_out,
        });
        kept.push(mine);
    }
    if let Some(file) = anchors
        && !m.readings.is_empty()
    {
        let at = anchor_positions(file, m.decoded.frame.as_ref())?;
        let timed = m.readings.iter().all(|r| r.after_fix_ms.is_some());
        match (timed, out.len()) {
            (true, 1) => {
                let first = m.decoded.first_ms.unwrap_or(0);
                let timed: Vec<(f32, Level)> = m
                    .readings
                    .iter()
                    .map(|r| {
                        let ms = r.after_fix_ms.unwrap_or(first);
                        ((ms - first) as f32 / 1000.0, level(file, &at, r))
                    })
                    .collect();
                let c = &mut out[0];
                c.updates = merge(&kept[0], &timed);
                c.rssi = true;
                c.anchors = at;
            }
            (true, _) | (false, 0) => {
                let mut epochs = AnchorEpochs::new(file, at.clone());
                let mut updates: Vec<Update> =
                    m.readings.iter().filter_map(|r| epochs.push(*r)).collect();
                updates.extend(epochs.close());
                out.push(Channel {
                    freq_mhz: None,
                    updates,
                    sources: Vec::new(),
                    rssi: true,
                    anchors: at,
                    left_out: (0, 0),
                });
            }
            (false, _) => {
                return Err(
                    "the capture has bearings and RSSI without GPS times to put them in \
                     one order: track them from separate captures"
                        .into(),
                );
            }
        }
    }
    out.retain(|c| !c.updates.is_empty());
    Ok(out)
}

/// The stations of a channel's bearings `mine`, numbered from 0 as the tracker's offsets are
/// (each bearing's `station` renumbered so): at most `max` of them, those with the most
/// bearings (a state holds that many offsets); the others' bearings are taken out of `mine`.
/// The capture's station index of each kept, and how many stations and bearings were left out.
fn most_heard(mine: &mut Vec<Observation>, max: usize) -> (Vec<u16>, (usize, usize)) {
    let mut counts: std::collections::BTreeMap<u16, usize> = Default::default();
    for o in mine.iter() {
        *counts.entry(o.station).or_default() += 1;
    }
    let mut ranked: Vec<(u16, usize)> = counts.into_iter().collect();
    ranked.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let left_out = ranked.get(max..).unwrap_or(&[]);
    let left_out = (left_out.len(), left_out.iter().map(|(_, n)| n).sum());
    let mut sources: Vec<u16> = ranked.iter().take(max).map(|(s, _)| *s).collect();
    sources.sort_unstable();
    mine.retain(|o| sources.contains(&o.station));
    for o in mine.iter_mut() {
        o.station = sources.iter().position(|s| *s == o.station).unwrap_or(0) as u16;
    }
    (sources, left_out)
}

/// Bearings (in time order) as updates: each update the bearings within [`WINDOW_S`] of its
/// first, at most [`K`].
pub fn bearing_updates(obs: &[Observation]) -> Vec<Update> {
    let mut window = Window::default();
    let mut out: Vec<Update> = obs.iter().filter_map(|o| window.push(*o)).collect();
    out.extend(window.close());
    out
}

/// Bearings and timed RSSI readings grouped into updates as they arrive (in time order, a
/// recorded capture's and a live line's alike): a bearing joins the open update when it comes
/// within [`WINDOW_S`] of the update's time, a bearing opened it and its bearings have room; a
/// reading joins when it comes within [`WINDOW_S`] and the update has room. Anything else
/// closes the open update and opens the next (an update a reading opened takes no bearing, so
/// the bearings' updates are those of the bearings alone).
#[derive(Debug, Clone, Default)]
pub struct Window {
    open: Option<Update>,
    /// Whether a bearing opened the open update.
    by_bearing: bool,
    /// Time of the last update opened, seconds.
    previous: Option<f32>,
}

impl Window {
    /// Add bearing `o`; the update it closed, if any.
    pub fn push(&mut self, o: Observation) -> Option<Update> {
        let room = self
            .open
            .as_ref()
            .is_some_and(|u| u.epoch.bearings().len() < K);
        let joins = self.by_bearing && room && self.within(o.time_s);
        let closed = if joins {
            None
        } else {
            self.open_at(o.time_s, true)
        };
        if let Some(u) = self.open.as_mut() {
            let _ = u.epoch.push_bearing(o);
        }
        closed
    }

    /// Add the RSSI reading `l` taken at `t_s`; the update it closed, if any.
    pub fn push_level(&mut self, t_s: f32, l: Level) -> Option<Update> {
        let room = self.open.as_ref().is_some_and(|u| !u.epoch.is_full());
        let closed = if room && self.within(t_s) {
            None
        } else {
            self.open_at(t_s, false)
        };
        if let Some(u) = self.open.as_mut() {
            let _ = u.epoch.push_level(l);
        }
        closed
    }

    /// Close the open update (the line went quiet, or ended).
    pub fn close(&mut self) -> Option<Update> {
        self.open.take()
    }

    /// Whether `t` is within the open update's window.
    fn within(&self, t: f32) -> bool {
        self.open.as_ref().is_some_and(|u| t - u.t_s <= WINDOW_S)
    }

    /// Close the open update and open one at `t`; the closed one.
    fn open_at(&mut self, t: f32, by_bearing: bool) -> Option<Update> {
        let dt = self.previous.map_or(0.0, |p| (t - p).max(0.0));
        self.previous = Some(t);
        self.by_bearing = by_bearing;
        self.open.replace(Update {
            t_s: t,
            epoch: Epoch::new(dt),
        })
    }
}

/// A channel's bearings (in time order) and timed RSSI readings as one time order's updates
/// ([`Window`]; at equal times a bearing first).
fn merge(bearings: &[Observation], levels: &[(f32, Level)]) -> Vec<Update> {
    let mut all: Vec<(f32, Option<&Observation>, Option<&Level>)> = bearings
        .iter()
        .map(|o| (o.time_s, Some(o), None))
        .chain(levels.iter().map(|(t, l)| (*t, None, Some(l))))
        .collect();
    // Stable: at equal times the bearings first, each kind in its own order.
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut window = Window::default();
    let mut out: Vec<Update> = all
        .into_iter()
        .filter_map(|(t, o, l)| match (o, l) {
            (Some(o), _) => window.push(*o),
            (None, Some(l)) => window.push_level(t, *l),
            (None, None) => None,
        })
        .collect();
    out.extend(window.close());
    out
}

/// Reading `r` of an anchor at `at` (by anchor index) as the tracker's measurement.
pub fn level(file: &AnchorsFile, at: &[[f32; 2]], r: &Reading) -> Level {
    Level {
        anchor: at.get(r.anchor).copied().unwrap_or_default(),
        dbm: r.dbm,
        sigma_db: file.sigma_db,
        law: file.law(r.anchor),
    }
}

/// Readings without times grouped into updates as they arrive, one reading per anchor: a
/// second reading from an anchor already heard closes the epoch and opens the next
/// (unit-free, whatever the receiver's timestamp ticks are); epochs are the anchors file's
/// `dt_s` apart, the first at 0.
#[derive(Debug, Clone)]
pub struct AnchorEpochs {
    file: AnchorsFile,
    /// Each anchor's position in the track's frame, by index.
    at: Vec<[f32; 2]>,
    open: Option<Update>,
    heard: Vec<bool>,
    /// Epochs opened so far.
    count: usize,
}

impl AnchorEpochs {
    /// Epochs of `file`'s anchors, standing at `at` ([`anchor_positions`]).
    pub fn new(file: &AnchorsFile, at: Vec<[f32; 2]>) -> Self {
        Self {
            heard: vec![false; file.anchor.len()],
            file: file.clone(),
            at,
            open: None,
            count: 0,
        }
    }

    /// Add reading `r`; the update it closed, if any.
    pub fn push(&mut self, r: Reading) -> Option<Update> {
        let repeats = self.heard.get(r.anchor).copied().unwrap_or(false);
        let closed = if repeats || self.open.as_ref().is_some_and(|u| u.epoch.is_full()) {
            self.close()
        } else {
            None
        };
        let (k, dt) = (self.count, self.file.dt_s);
        let open = self.open.get_or_insert_with(|| Update {
            t_s: k as f32 * dt,
            epoch: Epoch::new(if k == 0 { 0.0 } else { dt }),
        });
        let _ = open.epoch.push_level(level(&self.file, &self.at, &r));
        if let Some(h) = self.heard.get_mut(r.anchor) {
            *h = true;
        }
        closed
    }

    /// Close the open epoch (the line went quiet, or ended).
    pub fn close(&mut self) -> Option<Update> {
        let u = self.open.take()?;
        self.heard.iter_mut().for_each(|h| *h = false);
        self.count += 1;
        Some(u)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use foxhunt_core::model::bearing::Bearing;

    fn at(t: f32) -> Observation {
        Observation::new(
            Bearing {
                vehicle: [0.0, 0.0],
                theta: 0.0,
                sigma: 0.03,
            },
            t,
        )
    }

    #[test]
    fn bearings_within_the_window_share_an_update() {
        let u = bearing_updates(&[at(0.0), at(0.1), at(0.2), at(1.0), at(1.3), at(3.0)]);
        let counts: Vec<usize> = u.iter().map(|u| u.epoch.bearings().len()).collect();
        assert_eq!(counts, [3, 1, 1, 1]);
        for (u, dt) in u.iter().zip([0.0, 1.0, 0.3, 1.7]) {
            assert!((u.epoch.dt - dt).abs() < 1e-5, "{} {dt}", u.epoch.dt);
        }
        // More than K at once start a new update.
        let many: Vec<Observation> = (0..K + 1).map(|_| at(5.0)).collect();
        let u = bearing_updates(&many);
        assert_eq!(u.len(), 2);
        assert_eq!(u[1].epoch.dt, 0.0);
    }

    /// A reading of `dbm` at an anchor at `anchor` (-30 dBm at 1 m, exponent 2, 4 dB).
    pub(crate) fn reading(anchor: [f32; 2], dbm: f32) -> Level {
        Level {
            anchor,
            dbm,
            sigma_db: 4.0,
            law: foxhunt_core::model::rssi::PathLoss {
                p0: -30.0,
                d0: 1.0,
                eta: 2.0,
            },
        }
    }

    #[test]
    fn readings_join_the_bearings_update_they_fall_in_and_open_their_own() {
        let level = reading([0.0, 0.0], -60.0);
        let levels: Vec<(f32, Level)> = [0.05, 0.9, 0.95, 1.2].map(|t| (t, level)).to_vec();
        let u = merge(&[at(0.0), at(0.1), at(1.0)], &levels);
        let counts: Vec<(usize, usize)> = u
            .iter()
            .map(|u| (u.epoch.bearings().len(), u.epoch.levels().len()))
            .collect();
        // A reading's update takes no bearing: the bearing at 1.0 opens its own, and the
        // reading at 1.2 joins it.
        assert_eq!(counts, [(2, 1), (0, 2), (1, 1)]);
        let times: Vec<(f32, f32)> = u.iter().map(|u| (u.t_s, u.epoch.dt)).collect();
        assert_eq!(times, [(0.0, 0.0), (0.9, 0.9), (1.0, 1.0 - 0.9)]);
        // Fed one by one, as a live line delivers them, the same updates.
        let mut w = Window::default();
        let mut live: Vec<Update> = Vec::new();
        live.extend(w.push(at(0.0)));
        live.extend(w.push_level(0.05, level));
        live.extend(w.push(at(0.1)));
        for t in [0.9, 0.95] {
            live.extend(w.push_level(t, level));
        }
        live.extend(w.push(at(1.0)));
        live.extend(w.push_level(1.2, level));
        live.extend(w.close());
        assert_eq!(live, u);
    }

    #[test]
    fn a_channel_keeps_the_most_heard_stations_its_state_holds() {
        // Station 10 + k heard k + 1 times, k = 0..8: the six most heard are 12..=17.
        let mut mine: Vec<Observation> = (0..8u16)
            .flat_map(|k| {
                (0..=k).map(move |_| {
                    let mut o = at(0.0);
                    o.station = 10 + k;
                    o
                })
            })
            .collect();
        assert_eq!(max_sources(false), 6);
        assert_eq!(max_sources(true), 4);
        let (sources, left_out) = most_heard(&mut mine, 6);
        assert_eq!(sources, [12, 13, 14, 15, 16, 17]);
        assert_eq!(
            left_out,
            (2, 1 + 2),
            "stations 10 and 11, one and two bearings"
        );
        assert_eq!(mine.len(), (3..=8).sum::<usize>());
        assert!(mine.iter().all(|o| o.station < 6), "renumbered from 0");
    }

    #[test]
    fn a_second_reading_of_an_anchor_starts_an_epoch() {
        let r = |anchor| Reading {
            anchor,
            dbm: -60.0,
            after_fix_ms: None,
        };
        let file = AnchorsFile::from_toml(
            "anchor = [{ addr = 1, x = 0, y = 0 }, { addr = 2, x = 5, y = 0 }, \
             { addr = 3, x = 0, y = 5 }]",
        )
        .unwrap();
        let mut epochs = AnchorEpochs::new(&file, vec![[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]]);
        let mut e: Vec<Update> = [r(0), r(1), r(2), r(1), r(0), r(0)]
            .into_iter()
            .filter_map(|r| epochs.push(r))
            .collect();
        e.extend(epochs.close());
        let sizes: Vec<usize> = e.iter().map(|u| u.epoch.levels().len()).collect();
        assert_eq!(sizes, [3, 2, 1]);
        let times: Vec<(f32, f32)> = e.iter().map(|u| (u.t_s, u.epoch.dt)).collect();
        assert_eq!(times, [(0.0, 0.0), (0.5, 0.5), (1.0, 0.5)], "dt_s apart");
    }
}
