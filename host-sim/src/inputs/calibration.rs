//! A DF unit's mounting offset measured on a drive past a transmitter whose position is known
//! (`foxhunt locate --calibrate LAT,LON --calibration FILE`), kept in a small TOML file that
//! later runs load (`--calibration FILE`): the offset then enters every fix as a prior with
//! the measured spread, instead of being estimated from geometry that may not show it.

use crate::inputs::capture::Decoded;
use foxhunt_core::Bearing;
use foxhunt_core::fix::bias::{BiasPrior, calibrate};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// A calibration as saved.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The unit's offset, degrees, counter-clockwise as every offset (docs/src/conventions.md):
    /// it reports true azimuth - this.
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

/// What a calibration drive must show before its offset is saved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationCheck {
    /// A larger offset, degrees, is reported and not saved: five array elements indexed one
    /// off give 72 degrees, a swapped cable 90 or 180, and a transmitter typed wrong anything.
    pub max_offset_deg: f32,
    /// The noise of the drive's bearings about a point of their own choosing (the field
    /// pipeline's fix, offset estimated), degrees, if there is one: the bearings must agree
    /// with the transmitter given about as well.
    pub free_fit_noise_deg: Option<f32>,
}

impl Default for CalibrationCheck {
    fn default() -> Self {
        Self {
            max_offset_deg: 30.0,
            free_fit_noise_deg: None,
        }
    }
}

/// Bearings taken nearer the transmitter than this, metres, are left out: there a few metres
/// of GPS error or of the array's own size turn the direction by degrees.
pub const NEAREST_M: f32 = 100.0;
/// A transmitter farther than this from every bearing, metres, is no calibration target (a
/// position typed wrong, most likely): the bearings would hardly turn along the drive.
pub const FARTHEST_M: f32 = 50_000.0;
/// Bearings a calibration needs, at least [`NEAREST_M`] from the transmitter.
pub const MIN_BEARINGS: usize = 10;
/// The share of the bearings that may be left out as wild against the transmitter.
pub const MAX_WILD_SHARE: f32 = 0.25;
/// How much more the bearings may scatter about the transmitter than about their own best
/// point (as standard deviations) before they are said to disagree with it: with tens of
/// bearings, noise alone stays well inside 1.5 (a variance ratio of 2.25).
pub const MAX_NOISE_RATIO: f32 = 1.5;
/// Bearing noise above which, degrees, the bearings say nothing of an offset (the field
/// pipeline's limit for a consistent emitter).
pub const MAX_NOISE_DEG: f32 = 10.0;

impl Calibration {
    /// Measure the offset of the drive `d` past a transmitter at `target` ([lat, lon]),
    /// checked: the transmitter at a plausible range, the bearings agreeing with it, the offset
    /// within `check.max_offset_deg`. Each refusal says what is wrong on one line.
    pub fn measure(
        d: &Decoded,
        target: [f64; 2],
        check: &CalibrationCheck,
    ) -> Result<Self, String> {
        let at = format!("{:.6},{:.6}", target[0], target[1]);
        let frame = d
            .frame
            .ok_or("no GPS fix in the calibration drive: its bearings cannot be placed")?;
        let local = frame
            .to_local(foxhunt_bridge::nmea::LatLon {
                lat: target[0],
                lon: target[1],
            })
            .map_err(|_| format!("the transmitter {at} cannot be put in the drive's frame"))?;
        let tx = [local[0] as f32, local[1] as f32];
        let range = |b: &Bearing| (b.vehicle[0] - tx[0]).hypot(b.vehicle[1] - tx[1]);
        let all: Vec<Bearing> = d.bearings().copied().collect();
        let nearest = all.iter().map(range).fold(f32::INFINITY, f32::min);
        if nearest > FARTHEST_M {
            return Err(format!(
                "the transmitter at {at} is {:.0} km from the nearest bearing of the drive: too \
                 far to calibrate on (is its position right?)",
                nearest / 1000.0
            ));
        }
        let bearings: Vec<Bearing> = all
            .iter()
            .filter(|b| range(b) >= NEAREST_M)
            .copied()
            .collect();
        if bearings.len() < MIN_BEARINGS {
            return Err(format!(
                "{} of the drive's {} bearings were taken at least {NEAREST_M:.0} m from the \
                 transmitter at {at}: a calibration needs {MIN_BEARINGS}, taken from a distance \
                 (drive past it, not at it)",
                bearings.len(),
                all.len()
            ));
        }
        let c =
            calibrate(&bearings, tx).map_err(|e| format!("cannot calibrate on this drive: {e}"))?;
        let (offset, sd, noise) = (c.bias.to_degrees(), c.sd.to_degrees(), c.sigma.to_degrees());
        let n = bearings.len() as f32;
        let disagree = |why: String| {
            format!(
                "the bearings disagree with a transmitter at {at}: {why} (is its position \
                 right, and is it the transmitter the unit heard?); nothing saved"
            )
        };
        if c.rejected as f32 > MAX_WILD_SHARE * n {
            return Err(disagree(format!(
                "{} of {} bearings point elsewhere",
                c.rejected,
                bearings.len()
            )));
        }
        if noise > MAX_NOISE_DEG {
            return Err(disagree(format!(
                "they scatter by {noise:.1} degrees about it"
            )));
        }
        if let Some(free) = check.free_fit_noise_deg
            && noise > MAX_NOISE_RATIO * free.max(0.1)
        {
            return Err(disagree(format!(
                "they scatter by {noise:.1} degrees about it, and by {free:.1} about the point \
                 they agree on"
            )));
        }
        if offset.abs() > check.max_offset_deg {
            return Err(format!(
                "the measured offset is {offset:.1} +- {sd:.1} degrees, beyond \
                 --max-offset-deg {}: an antenna mounted turned, array elements indexed off or \
                 a swapped cable, or the wrong transmitter position; check them (or give \
                 --max-offset-deg {:.0} to save it); nothing saved",
                check.max_offset_deg,
                offset.abs().ceil()
            ));
        }
        Ok(Self {
            offset_deg: offset,
            offset_sd_deg: sd,
            noise_deg: noise,
            bearings: c.used,
            rejected: c.rejected + (all.len() - bearings.len()) as u32,
            transmitter: target,
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

    /// Load and check a calibration file; errors name the file and the key.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = crate::inputs::files::read_text(path)?;
        Self::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Parse and check a calibration file's text; the error names the key.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let c: Self = crate::inputs::files::parse_toml(text)?;
        c.check()?;
        Ok(c)
    }

    /// Whether the values are ones a calibration gives; the first that is not, named.
    pub fn check(&self) -> Result<(), String> {
        let within = |key: &str, v: f32, ok: bool, wants: &str| {
            if ok && v.is_finite() {
                Ok(())
            } else {
                Err(format!("`{key}` must be {wants}, not {v}"))
            }
        };
        within(
            "offset_deg",
            self.offset_deg,
            self.offset_deg.abs() <= 180.0,
            "a number of degrees from -180 to 180",
        )?;
        within(
            "offset_sd_deg",
            self.offset_sd_deg,
            self.offset_sd_deg > 0.0 && self.offset_sd_deg <= 90.0,
            "a number of degrees above 0, at most 90",
        )?;
        within(
            "noise_deg",
            self.noise_deg,
            self.noise_deg > 0.0 && self.noise_deg <= MAX_NOISE_DEG,
            "a number of degrees above 0, at most 10",
        )?;
        if (self.bearings as usize) < MIN_BEARINGS {
            return Err(format!(
                "`bearings` must be at least {MIN_BEARINGS} (a calibration's), not {}",
                self.bearings
            ));
        }
        let [lat, lon] = self.transmitter;
        if !(lat.abs() <= 90.0 && lon.abs() <= 180.0) {
            return Err(format!(
                "`transmitter` must be [latitude -90 to 90, longitude -180 to 180], not [{lat}, {lon}]"
            ));
        }
        self.prior()
            .check()
            .map_err(|e| format!("the offset is no usable prior: {e}"))
    }

    /// The calibration as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "offset {:.2} +- {:.2} deg (counter-clockwise: the unit reports true azimuth - this); noise {:.2} deg; {} bearings used, {} left out",
            self.offset_deg, self.offset_sd_deg, self.noise_deg, self.bearings, self.rejected
        );
        out
    }
}
