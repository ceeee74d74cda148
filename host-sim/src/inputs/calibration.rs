//! A DF unit's mounting offset measured on a drive past a transmitter whose position is known
//! (`foxhunt locate --calibrate LAT,LON --calibration FILE`), kept in a small TOML file that
//! later runs load (`--calibration FILE`): the offset then enters every fix as a prior with
//! the measured spread, instead of being estimated from geometry that may not show it.

use crate::inputs::capture::Decoded;
use foxhunt_core::fix::bias::{BiasPrior, calibrate};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// A calibration as saved.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The unit's offset, degrees: it reports true bearing + this.
    pub offset_deg: f32,
    /// Its standard deviation, degrees.
    pub offset_sd_deg: f32,
    /// The bearing noise seen on the calibration drive, degrees.
    pub noise_deg: f32,
    /// Bearings used.
    pub bearings: u32,
    /// Bearings left out as wild or unusable.
    pub rejected: u32,
    /// Where the transmitter was, [latitude, longitude] degrees.
    pub transmitter: [f64; 2],
}

/// Parse `LAT,LON` in decimal degrees.
fn lat_lon(text: &str) -> Result<[f64; 2], String> {
    let bad = || format!("--calibrate wants LAT,LON in decimal degrees, not `{text}`");
    let (lat, lon) = text.split_once(',').ok_or_else(bad)?;
    let p: [f64; 2] = [
        lat.trim().parse().map_err(|_| bad())?,
        lon.trim().parse().map_err(|_| bad())?,
    ];
    if p[0].abs() <= 90.0 && p[1].abs() <= 180.0 {
        Ok(p)
    } else {
        Err(bad())
    }
}

impl Calibration {
    /// Measure the offset of the drive `d` past a transmitter at `target` (`LAT,LON`).
    pub fn measure(d: &Decoded, target: &str) -> Result<Self, String> {
        let t = lat_lon(target)?;
        let frame = d
            .frame
            .ok_or("no GPS fix in the calibration drive: its bearings cannot be placed")?;
        let local = frame
            .to_local(foxhunt_bridge::nmea::LatLon {
                lat: t[0],
                lon: t[1],
            })
            .map_err(|_| format!("the transmitter {target} cannot be put in the drive's frame"))?;
        let bearings: Vec<_> = d.bearings().copied().collect();
        let c = calibrate(&bearings, [local[0] as f32, local[1] as f32])
            .map_err(|e| format!("cannot calibrate on this drive: {e}"))?;
        Ok(Self {
            offset_deg: c.bias.to_degrees(),
            offset_sd_deg: c.sd.to_degrees(),
            noise_deg: c.sigma.to_degrees(),
            bearings: c.used,
            rejected: c.rejected,
            transmitter: t,
        })
    }

    /// The offset as a prior for the fixes.
    pub fn prior(&self) -> BiasPrior {
        BiasPrior {
            mean: self.offset_deg.to_radians(),
            sd: self.offset_sd_deg.to_radians(),
        }
    }

    /// The file's text.
    pub fn to_toml(&self) -> String {
        format!(
            "# A DF unit's mounting offset, measured by `foxhunt locate --calibrate` on a drive\n\
             # past a transmitter at a known position. Load it with `--calibration FILE`.\n{}",
            toml::to_string(self).unwrap_or_default()
        )
    }

    /// Load and check a calibration file; errors name the file.
    pub fn load(path: &Path) -> Result<Self, String> {
        let c: Self = crate::inputs::files::load_toml(path)?;
        let ok = c.offset_deg.is_finite()
            && c.offset_deg.abs() <= 180.0
            && c.offset_sd_deg.is_finite()
            && c.offset_sd_deg >= 0.0
            && c.prior().check().is_ok();
        if ok {
            Ok(c)
        } else {
            Err(format!(
                "{}: offset_deg must lie in [-180, 180] and offset_sd_deg be >= 0, not {} and {}",
                path.display(),
                c.offset_deg,
                c.offset_sd_deg
            ))
        }
    }

    /// The calibration as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "offset {:.2} +- {:.2} deg (the unit reports true bearing + this); noise {:.2} deg; {} bearings used, {} left out",
            self.offset_deg, self.offset_sd_deg, self.noise_deg, self.bearings, self.rejected
        );
        out
    }
}
