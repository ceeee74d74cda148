//! Indoor RSSI tracking from a ZigBee coordinator's capture: `foxhunt track`.
//!
//! AF_INCOMING_MSG frames carry each anchor's link quality; an anchors file says where each
//! short address sits. Readings are grouped into epochs, one reading per anchor: a second
//! reading from an anchor already heard starts the next epoch (unit-free, so it works
//! whatever the receiver's timestamp ticks are). Each epoch is one step of the constant-
//! velocity tracker, run by the registry's `sir-wide` (the bench's tracking SIR, N = 1000).

use crate::estimate::Steps;
use foxhunt_bridge::bridge::{Bridge, BridgeConfig, Event, RssiReading};
use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_core::estimator::with_particle_filter;
use foxhunt_core::{Estimate, Method, ParticleSet, PathLoss, RssiMeasurement, RssiTracker, random};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fmt::Write;

/// Anchors an anchors file may list.
pub const MAX_ANCHORS: usize = 16;

/// Particles of the tracker.
pub const PARTICLES: usize = 1000;

/// One anchor of the anchors file.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Anchor {
    /// ZigBee short address (TOML takes 0x1a2b).
    pub addr: u16,
    /// East, metres.
    pub x: f32,
    /// North, metres.
    pub y: f32,
    /// Its own RSSI at the reference distance, dBm (default: the file's `path_loss`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p0_dbm: Option<f32>,
    /// Its own path-loss exponent (default: the file's `path_loss`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta: Option<f32>,
}

/// The log-distance path loss of the anchors file.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathLossEntry {
    /// RSSI at the reference distance, dBm.
    pub p0_dbm: f32,
    /// Reference distance, metres.
    pub d0_m: f32,
    /// Path-loss exponent.
    pub eta: f32,
}

fn default_dt() -> f32 {
    0.5
}
fn default_sigma() -> f32 {
    0.5
}
fn default_q() -> [f32; 4] {
    [0.5, 1.0, 0.5, 1.0]
}
fn default_path_loss() -> PathLossEntry {
    PathLossEntry {
        p0_dbm: -37.8,
        d0_m: 1.0,
        eta: 2.3,
    }
}

/// The anchors file (TOML).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AnchorsFile {
    /// The room, [width, depth] metres from (0, 0), if the node stays inside it.
    pub room: Option<[f32; 2]>,
    /// Seconds per epoch.
    #[serde(default = "default_dt")]
    pub dt_s: f32,
    /// RSSI noise, dB.
    #[serde(default = "default_sigma")]
    pub sigma_db: f32,
    /// Process noise [x, vx, y, vy] of the constant-velocity model.
    #[serde(default = "default_q")]
    pub process_q: [f32; 4],
    /// Path loss.
    #[serde(default = "default_path_loss")]
    pub path_loss: PathLossEntry,
    /// Latitude and longitude of the file's (0, 0), degrees: places the anchors beside GPS
    /// positions and gives the track latitudes and longitudes. Without it a track is in the
    /// file's metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 2]>,
    /// `foxhunt track`: how unsure the emitter's power is, dB; 0 (the default) takes the
    /// path loss as known, more lets the tracker learn a power offset.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub power_sd_db: f32,
    /// `foxhunt track`: how unsure the path-loss exponent is; 0 (the default) takes it as
    /// known, more lets the tracker learn a correction to every anchor's exponent.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub exponent_sd: f32,
    /// The anchors.
    pub anchor: Vec<Anchor>,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

impl AnchorsFile {
    /// Parse and check an anchors file: every number finite, every scale positive, the
    /// error naming the key.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let f: Self = crate::inputs::files::parse_toml(text)?;
        if !(3..=MAX_ANCHORS).contains(&f.anchor.len()) {
            return Err(format!(
                "give 3 to {} anchors, not {}",
                MAX_ANCHORS,
                f.anchor.len()
            ));
        }
        let addrs: BTreeSet<u16> = f.anchor.iter().map(|a| a.addr).collect();
        if addrs.len() != f.anchor.len() {
            return Err("two anchors share an address".into());
        }
        for a in &f.anchor {
            if !(a.x.is_finite() && a.y.is_finite()) {
                return Err(format!(
                    "anchor 0x{:04x}: position ({}, {}) must be finite",
                    a.addr, a.x, a.y
                ));
            }
            if a.p0_dbm.is_some_and(|v| !v.is_finite())
                || a.eta.is_some_and(|v| !(v > 0.0 && v.is_finite()))
            {
                return Err(format!(
                    "anchor 0x{:04x}: `p0_dbm` must be finite and `eta` finite and positive",
                    a.addr
                ));
            }
        }
        if let Some([lat, lon]) = f.origin
            && !(lat.abs() <= 90.0 && lon.abs() <= 180.0)
        {
            return Err(format!(
                "`origin` must be [latitude, longitude] within [-90, 90] and [-180, 180], not [{lat}, {lon}]"
            ));
        }
        for (key, v) in [
            ("power_sd_db", f.power_sd_db),
            ("exponent_sd", f.exponent_sd),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(format!("`{key}` must be a finite number >= 0, not {v}"));
            }
        }
        let positive = |key: &str, v: f32| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(format!("`{key}` must be a finite positive number, not {v}"))
            }
        };
        positive("dt_s", f.dt_s)?;
        positive("sigma_db", f.sigma_db)?;
        positive("path_loss.d0_m", f.path_loss.d0_m)?;
        positive("path_loss.eta", f.path_loss.eta)?;
        if !f.path_loss.p0_dbm.is_finite() {
            return Err(format!(
                "`path_loss.p0_dbm` must be finite, not {}",
                f.path_loss.p0_dbm
            ));
        }
        for q in f.process_q {
            positive("process_q", q)?;
        }
        if let Some([w, d]) = f.room {
            positive("room", w)?;
            positive("room", d)?;
        }
        Ok(f)
    }

    /// Anchor `i`'s path loss: its own P0 and eta where it gives them, else the file's.
    pub fn law(&self, i: usize) -> PathLoss {
        let a = self.anchor.get(i);
        PathLoss {
            p0: a.and_then(|a| a.p0_dbm).unwrap_or(self.path_loss.p0_dbm),
            d0: self.path_loss.d0_m,
            eta: a.and_then(|a| a.eta).unwrap_or(self.path_loss.eta),
        }
    }

    /// The file's text as `foxhunt simulate --scenario NAME` writes it.
    pub fn to_toml(&self, scenario: &str) -> Result<String, String> {
        Ok(format!(
            "# Anchors of `foxhunt simulate --scenario {scenario}`: short address (0x0101 works as\n\
             # well as 257), position in metres; room, epoch, noise and path loss of the model.\n{}",
            toml::to_string(self).map_err(|e| e.to_string())?
        ))
    }

    /// An anchors file from disk; errors name the file.
    pub fn load(path: &std::path::Path) -> Result<Self, String> {
        let text = crate::inputs::files::read_text(path)?;
        Self::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    fn tracker<const A: usize>(&self) -> RssiTracker<A> {
        RssiTracker {
            anchors: std::array::from_fn(|i| [self.anchor[i].x, self.anchor[i].y]),
            sigma: [self.sigma_db; A],
            path_loss: PathLoss {
                p0: self.path_loss.p0_dbm,
                d0: self.path_loss.d0_m,
                eta: self.path_loss.eta,
            },
            dt: self.dt_s,
            q: self.process_q,
            room: self.room,
        }
    }
}

/// One step of the track.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct TrackPoint {
    /// Epoch number from 0.
    pub step: usize,
    /// Time, seconds (step x dt).
    pub t_s: f32,
    /// East, metres.
    pub x_m: f32,
    /// North, metres.
    pub y_m: f32,
    /// Velocity east, m/s.
    pub vx_mps: f32,
    /// Velocity north, m/s.
    pub vy_mps: f32,
    /// Standard deviation of x, metres.
    pub sd_x_m: f32,
    /// Standard deviation of y, metres.
    pub sd_y_m: f32,
    /// Anchors heard in this epoch.
    pub heard: usize,
}

/// What `track` found.
#[derive(Debug, Clone)]
pub struct Track {
    /// One point per epoch.
    pub points: Vec<TrackPoint>,
    /// Frames from addresses the anchors file does not list, and those addresses.
    pub unknown: (u32, BTreeSet<u16>),
}

/// Track the node of a capture.
pub fn track(bytes: &[u8], anchors: &AnchorsFile, seed: u64) -> Result<Track, String> {
    match anchors.anchor.len() {
        3 => track_with::<3>(bytes, anchors, seed),
        4 => track_with::<4>(bytes, anchors, seed),
        5 => track_with::<5>(bytes, anchors, seed),
        6 => track_with::<6>(bytes, anchors, seed),
        n => Err(format!("give 3 to 6 anchors, not {n}")),
    }
}

/// Group readings into epochs: one reading per anchor each.
fn epochs<const A: usize>(readings: &[RssiReading]) -> Vec<RssiMeasurement<A>> {
    let mut out = Vec::new();
    let mut current = RssiMeasurement {
        dbm: [0.0; A],
        present: [false; A],
    };
    for r in readings {
        if current.present[r.anchor] {
            out.push(current);
            current.present = [false; A];
        }
        current.dbm[r.anchor] = r.dbm;
        current.present[r.anchor] = true;
    }
    if current.present.iter().any(|p| *p) {
        out.push(current);
    }
    out
}

fn track_with<const A: usize>(
    bytes: &[u8],
    file: &AnchorsFile,
    seed: u64,
) -> Result<Track, String> {
    let table: [(u16, [f32; 2]); A] =
        std::array::from_fn(|i| (file.anchor[i].addr, [file.anchor[i].x, file.anchor[i].y]));
    // One pass: frames go to the bridge, and the addresses it will skip are noted on the way
    // for the message.
    let mut demux = foxhunt_bridge::Demux::<600>::new();
    let mut bridge = Bridge::<A>::new(BridgeConfig::default(), table);
    let mut readings = Vec::new();
    let mut unknown = BTreeSet::new();
    let mut take = |f: foxhunt_bridge::Frame<'_>| {
        if let foxhunt_bridge::Frame::Mt(m) = f
            && let Ok(msg) = AfIncomingMsg::parse(&m)
            && !table.iter().any(|a| a.0 == msg.src_addr)
        {
            unknown.insert(msg.src_addr);
        }
        bridge.push(&f, &mut |e| {
            if let Event::Rssi(r) = e {
                readings.push(r);
            }
        });
    };
    demux.feed(bytes, &mut take);
    demux.finish_into(&mut take);
    let unknown_frames = bridge.counters().unknown_anchor;
    if readings.is_empty() {
        let heard: Vec<String> = unknown.iter().map(|a| format!("0x{a:04x}")).collect();
        return Err(if heard.is_empty() {
            "no AF_INCOMING_MSG frame in the capture: nothing to track".into()
        } else {
            format!(
                "no frame from a known anchor: heard {} but the anchors file lists {}",
                heard.join(", "),
                file.anchor
                    .iter()
                    .map(|a| format!("0x{:04x}", a.addr))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        });
    }
    let z = epochs::<A>(&readings);
    let model = file.tracker::<A>();
    let mut rng = XorShiftRng::seed_from_u64(seed);
    // Prior: anywhere in the room (or around the anchors), at walking speed.
    let (centre, spread) = match file.room {
        Some([w, d]) => ([w / 2.0, d / 2.0], w.max(d) / 3.0),
        None => {
            let n = A as f32;
            let c = [
                file.anchor.iter().map(|a| a.x).sum::<f32>() / n,
                file.anchor.iter().map(|a| a.y).sum::<f32>() / n,
            ];
            let s = file
                .anchor
                .iter()
                .map(|a| (a.x - c[0]).hypot(a.y - c[1]))
                .fold(1.0, f32::max);
            (c, s)
        }
    };
    let mut cloud = Box::new(ParticleSet::<PARTICLES, 4>::new());
    for x in cloud.states.iter_mut() {
        let p = [
            centre[0] + spread * random::normal(&mut rng),
            centre[1] + spread * random::normal(&mut rng),
        ];
        *x = model.confine([
            p[0],
            0.5 * random::normal(&mut rng),
            p[1],
            0.5 * random::normal(&mut rng),
        ]);
    }
    let mut points = Vec::with_capacity(z.len());
    let each = |k: usize, e: &Estimate<4>| {
        points.push(TrackPoint {
            step: k,
            t_s: k as f32 * file.dt_s,
            x_m: e.mean[0],
            y_m: e.mean[2],
            vx_mps: e.mean[1],
            vy_mps: e.mean[3],
            sd_x_m: e.covariance[0][0].max(0.0).sqrt(),
            sd_y_m: e.covariance[2][2].max(0.0).sqrt(),
            heard: z[k].present.iter().filter(|p| **p).count(),
        })
    };
    let steps = Steps {
        cloud: &cloud.states,
        measurements: &z,
        rng: &mut rng,
        each,
        keep_cloud: false,
    };
    crate::estimate::pool()
        .install(|| with_particle_filter::<PARTICLES, 4, _, _>(Method::SirWide, model, steps))
        .and_then(|r| r)
        .map_err(|e| format!("cannot track: {e}"))?;
    Ok(Track {
        points,
        unknown: (unknown_frames, unknown),
    })
}

impl Track {
    /// The track as CSV: a header, then one line per step.
    pub fn csv(&self) -> String {
        let mut out = String::from("step,t_s,x_m,y_m,vx_mps,vy_mps,sd_x_m,sd_y_m,heard\n");
        for p in &self.points {
            let _ = writeln!(
                out,
                "{},{:.2},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{}",
                p.step, p.t_s, p.x_m, p.y_m, p.vx_mps, p.vy_mps, p.sd_x_m, p.sd_y_m, p.heard
            );
        }
        out
    }
}
