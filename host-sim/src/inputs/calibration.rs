//! A DF unit's mounting offset measured on a drive past a transmitter whose position is known
//! (`foxhunt locate --calibrate LAT,LON --calibration FILE`), kept in a small TOML file that
//! later runs load (`--calibration FILE`): the offset then enters every fix as a prior with
//! the measured spread, instead of being estimated from geometry that may not show it. Where
//! the drive turned through enough directions relative to the vehicle ([`MIN_SPAN`]), the
//! file also holds the unit's direction-dependent error (docs/src/field.md, "Calibration"),
//! which later fixes take as a known table with its sd.

use crate::inputs::capture::Decoded;
use foxhunt_core::Bearing;
use foxhunt_core::fix::bias::{
    BiasPrior, DirectionCalibration, DirectionPrior, HARMONICS, MIN_SPAN, calibrate,
    calibrate_direction, relative_to_course,
};
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
    /// How evenly the drive's bearings spanned the directions relative to the vehicle: the
    /// smallest eigenvalue of the harmonics' information per bearing (0.5 for an even full
    /// turn; the harmonics are measured from [`MIN_SPAN`]). Absent in files written before
    /// it was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction_span: Option<f32>,
    /// The direction-dependent error's coefficients a_1, b_1, a_2, b_2, degrees (as the
    /// stations file's `direction_deg`), where the drive turned enough to measure them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction_deg: Option<[f32; HARMONICS]>,
    /// One sd for the four coefficients, degrees (the stations file's
    /// `direction_error_deg`): the largest along any combination of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction_error_deg: Option<f32>,
    /// Where the transmitter was, [latitude, longitude] degrees.
    pub transmitter: [f64; 2],
}

/// A harmonic of larger amplitude (sqrt(a^2 + b^2)), degrees, is refused, measured or
/// loaded: pseudo-Doppler units and small arrays show 2-5 degrees; 15 is a broken antenna or
/// array, a reflection near the calibration drive, or a file gone wrong.
pub const MAX_HARMONIC_DEG: f32 = 15.0;

/// Whether a calibration drive turned enough for its harmonics: the joint fit's table when
/// the span reaches [`MIN_SPAN`] and its sd stays within [`MAX_HARMONIC_DEG`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Turned {
    /// Measured: the table with its sd.
    Enough(DirectionPrior),
    /// Not enough directions, or too uncertain to be worth a table.
    Not,
}

impl Turned {
    fn of(joint: &DirectionCalibration) -> Self {
        let p = joint.prior();
        if joint.measured() && p.sd.to_degrees() <= MAX_HARMONIC_DEG {
            Self::Enough(p)
        } else {
            Self::Not
        }
    }
}

/// The larger of the two harmonics' amplitudes of coefficients `c` (degrees); `None` when
/// one is not finite.
fn largest_amplitude_deg(c: &[f32; HARMONICS]) -> Option<f32> {
    // f32::max passes over a NaN: every coefficient is checked first.
    c.iter()
        .all(|v| v.is_finite())
        .then(|| c[0].hypot(c[1]).max(c[2].hypot(c[3])))
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
        let all: Vec<Bearing> = d.bearings().copied().collect();
        Self::measure_local(&all, tx, target, check)
    }

    /// [`Calibration::measure`] on bearings `all` in the drive's local frame (time order),
    /// the transmitter at `tx` there and at `target` ([lat, lon]) on the map.
    pub fn measure_local(
        all: &[Bearing],
        tx: [f32; 2],
        target: [f64; 2],
        check: &CalibrationCheck,
    ) -> Result<Self, String> {
        let at = format!("{:.6},{:.6}", target[0], target[1]);
        let range = |b: &Bearing| (b.vehicle[0] - tx[0]).hypot(b.vehicle[1] - tx[1]);
        // Each bearing relative to the vehicle's course, from the whole drive's track.
        let mut relative = vec![0.0f32; all.len()];
        relative_to_course(all, std::f32::consts::FRAC_PI_2, &mut relative);
        let nearest = all.iter().map(range).fold(f32::INFINITY, f32::min);
        if nearest > FARTHEST_M {
            return Err(format!(
                "the transmitter at {at} is {:.0} km from the nearest bearing of the drive: too \
                 far to calibrate on (is its position right?)",
                nearest / 1000.0
            ));
        }
        let (bearings, relative): (Vec<Bearing>, Vec<f32>) = all
            .iter()
            .zip(&relative)
            .filter(|(b, _)| range(b) >= NEAREST_M)
            .map(|(b, r)| (*b, *r))
            .unzip();
        if bearings.len() < MIN_BEARINGS {
            return Err(format!(
                "{} of the drive's {} bearings were taken at least {NEAREST_M:.0} m from the \
                 transmitter at {at}: a calibration needs {MIN_BEARINGS}, taken from a distance \
                 (drive past it, not at it)",
                bearings.len(),
                all.len()
            ));
        }
        let fail = |e: foxhunt_core::Error| format!("cannot calibrate on this drive: {e}");
        let joint = calibrate_direction(&bearings, &relative, tx).map_err(fail)?;
        let turned = Turned::of(&joint);
        let c = match turned {
            Turned::Enough(_) => joint.offset,
            _ => calibrate(&bearings, tx).map_err(fail)?,
        };
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
        if let Turned::Enough(p) = turned
            && let Some(a) = largest_amplitude_deg(&p.mean.map(f32::to_degrees))
            && a > MAX_HARMONIC_DEG
        {
            return Err(format!(
                "the measured direction-dependent error has a harmonic of {a:.1} degrees, \
                 beyond {MAX_HARMONIC_DEG:.0}: a broken antenna or array, a reflection near \
                 the drive, or the wrong transmitter position; nothing saved"
            ));
        }
        let direction = match turned {
            Turned::Enough(p) => Some(p),
            _ => None,
        };
        Ok(Self {
            offset_deg: offset,
            offset_sd_deg: sd,
            noise_deg: noise,
            bearings: c.used,
            rejected: c.rejected + (all.len() - bearings.len()) as u32,
            direction_span: Some(joint.span),
            direction_deg: direction.map(|p| p.mean.map(f32::to_degrees)),
            direction_error_deg: direction.map(|p| p.sd.to_degrees()),
            transmitter: target,
        })
    }

    /// The direction-dependent error as a prior for the fixes (a known table with its sd),
    /// where the file holds one.
    pub fn direction(&self) -> Option<DirectionPrior> {
        Some(DirectionPrior {
            mean: self.direction_deg?.map(f32::to_radians),
            sd: self.direction_error_deg?.to_radians(),
        })
    }

    /// Why the file holds the offset only, in one line, where it does.
    pub fn offset_only(&self) -> Option<String> {
        if self.direction_deg.is_some() {
            return None;
        }
        Some(match self.direction_span {
            Some(span) => format!(
                "offset only: the drive did not turn through enough directions to measure \
                 the direction-dependent error (span {span:.3}, wants {MIN_SPAN}; drive a loop \
                 or turn where the transmitter is in view)"
            ),
            None => String::from("offset only"),
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
            .map_err(|e| format!("the offset is no usable prior: {e}"))?;
        if let Some(span) = self.direction_span {
            within(
                "direction_span",
                span,
                (0.0..=1.0).contains(&span),
                "a number from 0 to 1",
            )?;
        }
        match (self.direction_deg, self.direction_error_deg) {
            (None, None) => Ok(()),
            (Some(c), Some(sd)) => {
                match largest_amplitude_deg(&c) {
                    Some(a) if a <= MAX_HARMONIC_DEG => {}
                    _ => {
                        return Err(format!(
                            "`direction_deg` must be four coefficients (a1, b1, a2, b2) whose \
                             harmonics have amplitudes of at most {MAX_HARMONIC_DEG} degrees, \
                             not {c:?}"
                        ));
                    }
                }
                within(
                    "direction_error_deg",
                    sd,
                    sd > 0.0 && sd <= MAX_HARMONIC_DEG,
                    "a number of degrees above 0, at most 15",
                )
            }
            _ => Err(String::from(
                "`direction_deg` and `direction_error_deg` come together (the table and its sd)",
            )),
        }
    }

    /// The calibration as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "offset {:.2} +- {:.2} deg (counter-clockwise: the unit reports true azimuth - this); noise {:.2} deg; {} bearings used, {} left out",
            self.offset_deg, self.offset_sd_deg, self.noise_deg, self.bearings, self.rejected
        );
        match (self.direction_deg, self.direction_error_deg) {
            (Some(c), Some(sd)) => {
                let _ = writeln!(
                    out,
                    "direction-dependent error: a1 {:.2}, b1 {:.2}, a2 {:.2}, b2 {:.2} deg, each +- {sd:.2} deg (span {:.3})",
                    c[0],
                    c[1],
                    c[2],
                    c[3],
                    self.direction_span.unwrap_or(f32::NAN)
                );
            }
            _ => {
                if let Some(why) = self.offset_only() {
                    let _ = writeln!(out, "{why}");
                }
            }
        }
        out
    }
}
