//! `foxhunt track`'s tracks: each channel of a capture ([`crate::track::updates`]) tracked
//! with the moving-emitter tracker ([`crate::track::moving`]), every update's point placed in
//! latitude and longitude when the capture (or the anchors file's origin) gives a frame.

use crate::estimate::stations::{StationSetup, station_setup};
use crate::inputs::stations::Network;
use crate::track::capture::Measured;
use crate::track::indoor::AnchorsFile;
use crate::track::moving::{Settings, TrackPoint};
use crate::track::noise::{SourceNoise, Unstated, track_estimating};
use crate::track::updates::{Channel, channels};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::Method;
use foxhunt_core::fix::bias::BiasPrior;
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

/// Prior sd of a station's offset where nothing states it, degrees.
pub const OFFSET_SD_DEG: f32 = 2.0;
/// Channel width for grouping bearings by frequency, MHz (as `locate`'s default).
pub const WIDTH_MHZ: f32 = 0.025;

impl Options {
    /// The offset prior of a station nothing states: `--offset-sd`'s, centred on zero.
    pub fn fallback(&self) -> BiasPrior {
        BiasPrior {
            mean: 0.0,
            sd: self.offset_sd,
        }
    }
}

impl Default for Options {
    /// `foxhunt track`'s defaults: the default tracker, each record's own noise (estimated),
    /// no stations file.
    fn default() -> Self {
        Self {
            method: crate::track::moving::DEFAULT_METHOD,
            particles: crate::track::moving::PARTICLES,
            offset_sd: OFFSET_SD_DEG.to_radians(),
            motion: None,
            accel_sd: None,
            memory_s: None,
            sigma: None,
            width_mhz: WIDTH_MHZ,
            seed: 1,
            network: None,
            smooth: false,
        }
    }
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
    /// Each DF station's noise, for the stations with enough bearings.
    pub noise: Vec<StationNoise>,
}

/// A DF station's bearing noise on a track ([`crate::track::noise`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StationNoise {
    /// The station's id.
    pub id: String,
    /// Its bearings about the track (its source number the capture's station index).
    pub noise: SourceNoise,
    /// Whether the user stated its noise (else its records' was estimated).
    pub stated: bool,
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
    s.memory_s = memory_s(o);
    s.smooth = o.smooth;
    s.offsets = c
        .sources
        .iter()
        .map(|k| offset_prior(setup, usize::from(*k)))
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

/// Seconds in which a track's offsets forget: the user's, else the shortest of the stations
/// file's device classes' ([`DeviceClass::track`](foxhunt_core::fix::device::DeviceClass::track)),
/// else the tracker's own. The file's, not a channel's sources': a live line starts its
/// trackers before it has heard every station.
pub fn memory_s(o: &Options) -> Option<f32> {
    let n = o.network.as_ref();
    let classes = n
        .into_iter()
        .flat_map(|n| n.stations.iter().map(|s| s.antenna))
        .chain(n.map(|n| n.default_antenna));
    o.memory_s.or(classes
        .flatten()
        .filter_map(|c| c.track().memory_s)
        .reduce(f32::min))
}

/// Station `s`'s offset prior on a track: its own where stated, else the default widened to
/// its class's ([`DeviceClass::track`](foxhunt_core::fix::device::DeviceClass::track)).
pub fn offset_prior(setup: &StationSetup, s: usize) -> BiasPrior {
    let prior = setup.priors.of(s);
    match setup.track_traits(s).offset_sd {
        Some(sd) if !setup.own_prior(s) => BiasPrior {
            sd: prior.sd.max(sd),
            ..prior
        },
        _ => prior,
    }
}

/// What no one stated of station `s` (`noise`: whether its noise is, [`track_noise`]).
pub fn unstated_of(setup: &StationSetup, noise: bool, s: usize) -> Unstated {
    let class = setup.classes.get(s).copied().flatten();
    match (noise, class.is_some() || setup.own_prior(s)) {
        (true, _) => Unstated::Nothing,
        (false, true) => Unstated::Noise,
        (false, false) => Unstated::Everything,
    }
}

/// Station `s`'s noise on a track: `sigma` (every station's, stated), else its stations
/// file's or class's, times its class's factor ([`DeviceClass::track`](
/// foxhunt_core::fix::device::DeviceClass::track)); `None`: the records' own, estimated.
pub fn track_noise(setup: &StationSetup, sigma: Option<f32>, s: usize) -> Option<f32> {
    let stated = sigma.or(setup.noise.get(s).copied().flatten())?;
    Some(stated * setup.track_traits(s).report_sd_factor)
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
    let fallback = o.fallback();
    let ids = m.decoded.stations.iter().map(|s| s.id.as_str());
    let setup = station_setup(ids, o.network.as_ref(), fallback, false);
    // `--sigma` over the stations file's noise over each record's own.
    let given: Vec<Option<f32>> = (0..m.decoded.stations.len())
        .map(|s| track_noise(&setup, o.sigma, s))
        .collect();
    let found = channels(m, anchors, o.width_mhz, &given, &setup.priors)?;
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
                noise: Vec::new(),
            });
            continue;
        }
        let unstated: Vec<Unstated> = c
            .sources
            .iter()
            .map(|k| {
                let k = usize::from(*k);
                unstated_of(&setup, given.get(k).is_some_and(Option::is_some), k)
            })
            .collect();
        let (run, found) =
            track_estimating(&c.updates, &settings(c, anchors, o, &setup), &unstated).map_err(
                |e| {
                    let what = c
                        .freq_mhz
                        .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
                    format!("cannot track{what}: {e}")
                },
            )?;
        let noise = found
            .into_iter()
            .filter_map(|mut n| {
                let k = usize::from(n.source);
                n.source = *c.sources.get(k)?;
                Some(StationNoise {
                    id: m.decoded.stations.get(usize::from(n.source))?.id.clone(),
                    noise: n,
                    stated: !unstated[k].noise(),
                })
            })
            .collect();
        out.push(ChannelTrack {
            freq_mhz: c.freq_mhz,
            points: if o.smooth { run.smoothed } else { run.points },
            left_out: c.left_out,
            untracked: None,
            noise,
        });
    }
    let frame = m.decoded.frame.or(anchors.and_then(AnchorsFile::frame));
    Ok(Tracks {
        tracks: out,
        frame,
        first_ms: m.decoded.first_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_indoor_array_class_widens_its_reports_and_its_offset_and_shortens_the_memory() {
        let dir = std::env::temp_dir().join(format!("foxhunt-class-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch");
        let path = dir.join("stations.toml");
        std::fs::write(
            &path,
            "[[station]]\nid = \"a\"\nantenna = \"indoor-aoa\"\n\n\
             [[station]]\nid = \"b\"\nantenna = \"indoor-aoa\"\noffset_deg = 1\n\
             offset_sd_deg = 2\nnoise_deg = 10\n\n\
             [[station]]\nid = \"c\"\nantenna = \"uca\"\n",
        )
        .expect("write");
        let network = Network::load(&path).expect("a stations file");
        std::fs::remove_dir_all(&dir).ok();
        let deg = |x: f32| x.to_radians();
        let fallback = BiasPrior {
            mean: 0.0,
            sd: deg(2.0),
        };
        let setup = station_setup(
            ["a", "b", "c", "d"].into_iter(),
            Some(&network),
            fallback,
            false,
        );
        let close = |x: Option<f32>, want: f32| x.is_some_and(|x| (x - deg(want)).abs() < 1e-5);
        // Twice the class's 13 degrees, twice the stated 10; a UCA as its class says; an
        // unlisted station its records' own.
        assert!(close(track_noise(&setup, None, 0), 26.0));
        assert!(close(track_noise(&setup, None, 1), 20.0));
        assert!(close(track_noise(&setup, None, 2), 2.0));
        assert_eq!(track_noise(&setup, None, 3), None);
        assert!(close(track_noise(&setup, Some(deg(5.0)), 0), 10.0));
        // The class's offset prior where none is stated; a stated one kept.
        assert!(close(Some(offset_prior(&setup, 0).sd), 7.2));
        assert!(close(Some(offset_prior(&setup, 1).sd), 2.0));
        assert!(close(Some(offset_prior(&setup, 1).mean), 1.0));
        assert!(close(Some(offset_prior(&setup, 2).sd), 2.0));
        let mut o = Options {
            method: Method::SirRobust,
            particles: 1000,
            offset_sd: fallback.sd,
            motion: None,
            accel_sd: None,
            memory_s: None,
            sigma: None,
            width_mhz: 0.025,
            seed: 1,
            network: Some(network),
            smooth: false,
        };
        assert_eq!(memory_s(&o), Some(10.0));
        o.memory_s = Some(30.0);
        assert_eq!(memory_s(&o), Some(30.0));
        o.memory_s = None;
        o.network = None;
        assert_eq!(memory_s(&o), None);
    }
}
