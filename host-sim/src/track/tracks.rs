//! `foxhunt track`'s tracks: each channel of a capture ([`crate::track::updates`]) tracked
//! with the moving-emitter tracker ([`crate::track::moving`]), every update's point placed in
//! latitude and longitude when the capture (or the anchors file's origin) gives a frame.

use crate::estimate::stations::{StationSetup, station_setup};
use crate::inputs::stations::Network;
use crate::track::capture::Measured;
use crate::track::indoor::AnchorsFile;
use crate::track::moving::{Settings, TrackPoint, Update, track};
use crate::track::updates::{Channel, channels};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::Method;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::model::bearing::wrap;
use foxhunt_core::track::{Layout, Motion};

/// What the user chose of the tracker.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// The estimator.
    pub method: Method,
    /// Particles.
    pub particles: usize,
    /// Prior sd of each DF source's offset, radians.
    pub offset_sd: f32,
    /// How the emitter moves (none: outdoors, or indoors for RSSI alone from an anchors file).
    pub motion: Option<Motion>,
    /// Acceleration sd of the moving model, m/s^2 (none: the motion's own).
    pub accel_sd: Option<f32>,
    /// Seconds in which the stations' offsets forget what they learned (none: the method's
    /// own).
    pub memory_s: Option<f32>,
    /// Every bearing's noise, radians (none: each record's own).
    pub sigma: Option<f32>,
    /// Channel width for grouping bearings by frequency, MHz.
    pub width_mhz: f32,
    /// Seed.
    pub seed: u64,
    /// The stations file: each station's noise and offset prior (none: `sigma` or each
    /// record's own noise, and `offset_sd` for every station).
    pub network: Option<Network>,
    /// Give the fixed-lag smoother's points ([`crate::track::moving::LAG`] updates) instead
    /// of the filter's (recordings).
    pub smooth: bool,
}

/// One channel's track.
#[derive(Debug, Clone)]
pub struct ChannelTrack {
    /// Its frequency, MHz (none for bearings without one, or RSSI alone).
    pub freq_mhz: Option<f32>,
    /// Every update's point.
    pub points: Vec<TrackPoint>,
    /// DF stations whose bearings were left out (the state holds
    /// [`max_sources`](crate::track::moving::max_sources)) and their bearings.
    pub left_out: (usize, usize),
    /// Why the channel has no track (its points are then empty): [`one_station`].
    pub untracked: Option<String>,
    /// Stations whose bearings scatter about the track by more than their stated noise
    /// allows ([`scatter`]): the capture's station index, the scatter in stated sds and that
    /// noise, degrees.
    pub too_noisy: Vec<(u16, f32, f32)>,
}

/// Bearings fewer than this from a station say nothing of its scatter.
const SCATTER_MIN_BEARINGS: usize = 30;
/// A station's bearings scatter about the track by more than this many of their stated sds:
/// the noise it states is too small. The filtered track has seen each bearing, so its
/// residuals are smaller than the noise (a stated noise that is right scatters at most 1);
/// 1.5 leaves room for heavy tails and an error that changes with direction.
const SCATTER_LIMIT: f32 = 1.5;

/// Each DF source's bearings in `updates` about the track `points` (one point an update):
/// the residuals over their stated sigma, centred on their median (the source's offset), and
/// their robust scale (1.4826 x the median absolute deviation): by source number, the scale
/// and the median stated noise (radians), for the sources with enough bearings.
pub fn scatter(updates: &[Update], points: &[TrackPoint]) -> Vec<(u16, f32, f32)> {
    let mut by: std::collections::BTreeMap<u16, (Vec<f32>, Vec<f32>)> = Default::default();
    for (u, p) in updates.iter().zip(points).filter(|(u, p)| u.t_s == p.t_s) {
        for o in u.epoch.bearings() {
            let b = &o.bearing;
            let seen = (p.position[1] - b.vehicle[1]).atan2(p.position[0] - b.vehicle[0]);
            let r = wrap(b.theta - seen);
            let e = by.entry(o.station).or_default();
            e.0.push(r / b.sigma);
            e.1.push(b.sigma);
        }
    }
    let median = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    by.into_iter()
        .filter(|(_, (z, _))| z.len() >= SCATTER_MIN_BEARINGS)
        .map(|(s, (mut z, mut sigma))| {
            let centre = median(&mut z);
            let mut dev: Vec<f32> = z.iter().map(|x| (x - centre).abs()).collect();
            (s, 1.4826 * median(&mut dev), median(&mut sigma))
        })
        .collect()
}

/// Why a channel heard by one DF station alone (bearings, no RSSI) is not tracked: from one
/// station's bearings a moving emitter's range is not observable. Any copy of its path
/// scaled along the lines of bearing (moving with the station, outward) fits the bearings as
/// well, and the tracker's particles settle on one of the copies: measured on one vehicle
/// watching a drone (`bench --scenario moving/move-vehicle-turning`), the default tracker's
/// 95 % ellipses held the drone 36 % of the time, 3.6x the bound off; watching a hovering one,
/// 44 %, and it called the still drone moving (docs/src/tracking.md).
pub fn one_station(station: &str) -> String {
    format!(
        "heard by one DF station only ({station}): from one station's bearings a moving \
         emitter's range is not observable (any copy of its path scaled along the bearings \
         fits them), so no track is given; `foxhunt locate` fixes it if it stands still, a \
         second station (or RSSI anchors) tracks it"
    )
}

/// Whether a channel of these sources can be tracked: two DF stations, or RSSI.
pub fn observable(sources: usize, rssi: bool) -> bool {
    sources >= 2 || rssi
}

/// Every channel's track and the frame that places them on the earth.
#[derive(Debug, Clone)]
pub struct Tracks {
    /// One per channel.
    pub tracks: Vec<ChannelTrack>,
    /// The frame of the points' metres (none: the anchors file's metres, unplaced).
    pub frame: Option<LocalFrame>,
    /// Bridge time of the track's t = 0, ms (the capture's first bearing, or first fix).
    pub first_ms: Option<i64>,
}

impl Tracks {
    /// Latitude and longitude of local metres `p`, if the tracks are placed.
    pub fn geodetic(&self, p: [f32; 2]) -> Option<LatLon> {
        let f = self.frame.as_ref()?;
        f.to_geodetic([f64::from(p[0]), f64::from(p[1])]).ok()
    }
}

/// The settings of one channel: an offset for each of its DF sources, RSSI terms as the
/// anchors file says, the room and a start region for RSSI alone.
pub(crate) fn settings(
    c: &Channel,
    anchors: Option<&AnchorsFile>,
    o: &Options,
    setup: &StationSetup,
) -> Settings {
    let indoor = anchors.filter(|_| c.sources.is_empty());
    let mut motion = match (o.motion, indoor) {
        (Some(m), _) => m,
        (None, Some(f)) => Motion {
            accel_sd: file_accel_sd(f),
            ..Motion::INDOOR
        },
        (None, None) => Motion::OUTDOOR,
    };
    if let Some(a) = o.accel_sd {
        motion.accel_sd = a;
    }
    let layout = Layout {
        sources: c.sources.len() as u8,
        rssi: c.rssi,
    };
    let mut s = Settings::new(layout, motion);
    s.method = o.method;
    s.particles = o.particles;
    s.seed = o.seed;
    s.memory_s = o.memory_s;
    s.smooth = o.smooth;
    s.offsets = c
        .sources
        .iter()
        .map(|k| setup.priors.of(usize::from(*k)))
        .collect();
    if let Some(f) = anchors.filter(|_| c.rssi) {
        s.power_sd = f.power_sd_db;
        s.exponent_sd = f.exponent_sd;
        if indoor.is_some() {
            s.room = f.room;
        }
        s.region = Some(start_region(s.room, &c.anchors));
    }
    s
}

/// The acceleration sd of the nearly-constant-velocity model that moves at least as the
/// anchors file's model does: its `process_q` adds variance q_x to a position and q_v to a
/// velocity every `dt_s`, the white-noise acceleration q dt^3 / 3 and q dt (module
/// [`foxhunt_core::track::motion`]), so q = max(3 q_x / dt^3, q_v / dt). Measured on
/// `rssi-sim` and `rssi-lab` (docs/src/tracking.md): the indoor default of 0.5 m/s^2 is far
/// smoother than those nodes and trails them (4.0 m rmse against 0.6 m).
fn file_accel_sd(f: &AnchorsFile) -> f32 {
    let [qx, qvx, qy, qvy] = f.process_q;
    let dt = f.dt_s;
    let q = (3.0 * qx.max(qy) / (dt * dt * dt)).max(qvx.max(qvy) / dt);
    q.sqrt()
}

/// Where a track whose first update holds readings alone starts: the room's middle, else the
/// centre of the anchors `at` (in the track's frame), spread over a third of the room or the
/// anchors' reach.
pub(crate) fn start_region(room: Option<[f32; 2]>, at: &[[f32; 2]]) -> ([f32; 2], f32) {
    if let Some([w, d]) = room {
        return ([w / 2.0, d / 2.0], w.max(d) / 3.0);
    }
    let n = at.len().max(1) as f32;
    let c = [
        at.iter().map(|a| a[0]).sum::<f32>() / n,
        at.iter().map(|a| a[1]).sum::<f32>() / n,
    ];
    let reach = at
        .iter()
        .map(|a| (a[0] - c[0]).hypot(a[1] - c[1]))
        .fold(1.0, f32::max);
    (c, reach)
}

/// Track every channel of `m`.
pub fn tracks(m: &Measured, anchors: Option<&AnchorsFile>, o: &Options) -> Result<Tracks, String> {
    let fallback = BiasPrior {
        mean: 0.0,
        sd: o.offset_sd,
    };
    let ids = m.decoded.stations.iter().map(|s| s.id.as_str());
    let setup = station_setup(ids, o.network.as_ref(), fallback, false);
    // `--sigma` over the stations file's noise over each record's own.
    let noise: Vec<Option<f32>> = match o.sigma {
        Some(s) => vec![Some(s); m.decoded.stations.len()],
        None => setup.noise.clone(),
    };
    let found = channels(m, anchors, o.width_mhz, &noise)?;
    if found.is_empty() {
        return Err(if anchors.is_some() {
            "no bearing and no RSSI reading of a listed anchor in the capture: nothing to track"
                .into()
        } else {
            "no bearing in the capture: nothing to track (RSSI needs --anchors)".into()
        });
    }
    let mut out = Vec::with_capacity(found.len());
    for c in &found {
        if !observable(c.sources.len(), c.rssi) {
            let station = c
                .sources
                .first()
                .and_then(|k| m.decoded.stations.get(usize::from(*k)))
                .map_or("no station", |s| s.id.as_str());
            out.push(ChannelTrack {
                freq_mhz: c.freq_mhz,
                points: Vec::new(),
                left_out: c.left_out,
                untracked: Some(one_station(station)),
                too_noisy: Vec::new(),
            });
            continue;
        }
        let run = track(&c.updates, &settings(c, anchors, o, &setup)).map_err(|e| {
            let what = c
                .freq_mhz
                .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
            format!("cannot track{what}: {e}")
        })?;
        let too_noisy = scatter(&c.updates, &run.points)
            .into_iter()
            .filter(|(_, z, _)| *z > SCATTER_LIMIT)
            .filter_map(|(k, z, sigma)| {
                let station = *c.sources.get(usize::from(k))?;
                Some((station, z, sigma.to_degrees()))
            })
            .collect();
        out.push(ChannelTrack {
            freq_mhz: c.freq_mhz,
            points: if o.smooth { run.smoothed } else { run.points },
            left_out: c.left_out,
            untracked: None,
            too_noisy,
        });
    }
    let frame = m.decoded.frame.or(anchors.and_then(AnchorsFile::frame));
    Ok(Tracks {
        tracks: out,
        frame,
        first_ms: m.decoded.first_ms,
    })
}
