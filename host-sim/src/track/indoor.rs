//! The anchors file of indoor RSSI tracking: where each ZigBee anchor (by short address)
//! stands, the room, and the log-distance path loss and noise of its readings. `foxhunt
//! track` reads the anchors' AF_INCOMING_MSG frames with it ([`crate::track::capture`]) and
//! groups their readings into the tracker's updates ([`crate::track::updates`]).

use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::PathLoss;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// Anchors an anchors file may list.
pub const MAX_ANCHORS: usize = 16;

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

    /// The frame of the file's metres on the earth: east and north of its `origin` (none
    /// without one, or with one out of range).
    pub fn frame(&self) -> Option<LocalFrame> {
        let [lat, lon] = self.origin?;
        LocalFrame::new(LatLon { lat, lon }, 0.0).ok()
    }

    /// An anchors file from disk; errors name the file.
    pub fn load(path: &std::path::Path) -> Result<Self, String> {
        let text = crate::inputs::files::read_text(path)?;
        Self::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
    }
}
