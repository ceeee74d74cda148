//! When to stop, and otherwise what the fix lacks.
//!
//! "Good enough" needs five things at once (docs/src/guidance.md, "The stop rule"): the predicted CEP50 from
//! the bias-aware bound at the fix below the target radius; residuals consistent with the noise
//! model; enough independent bearings behind the fix; a DF unit whose offset is not in doubt
//! (below); and an offset known to [`KNOWN_SD`], by its prior (a calibration) or by the drive.
//! A fix that rests on an unchecked prior is right only while the prior is: an offset far
//! outside it moves the fix by range x offset with nothing in the residuals to show it. What limits a fix that is not yet good
//! enough is read off the same bound:
//! - the **offset**, when the bound with the offset known would already be much smaller (an
//!   unmodelled offset floors any drive that does not surround the emitter at about r b): drive a
//!   calibration leg past a known transmitter, or round the emitter;
//! - the **angle**, when the ellipse is long and thin (its axes' ratio beyond
//!   [`StopRule::max_axis_ratio`]: the bearings' doubled angles do not cancel): widen the angle;
//! - the **range**, otherwise: both axes are too long for the target: get closer.
//!
//! A fix whose offset contradicted its prior (the fix itself then relaxed the prior:
//! docs/src/field.md, "Past the prior") is never good enough, however small its ellipse: the
//! unit is not what its prior said, so it needs checking before any fix of it is trusted.

use super::belief::Belief;
use crate::error::{Error, check_finite};
use crate::fix::bias::{BiasPrior, KNOWN_SD};
use crate::model::bearing::Bearing;
use core::fmt;

/// Settings of the stop rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopRule {
    /// CEP50 that is good enough, metres.
    pub target_cep50_m: f32,
    /// Independent bearings (N_eff) a fix needs at least.
    pub min_effective: f32,
    /// A bound whose offset-known CEP50 is below this share of the bias-aware one is limited
    /// by the offset.
    pub offset_share: f32,
    /// Axis ratio (major / minor sd) beyond which the angle limits the fix.
    pub max_axis_ratio: f32,
}

impl Default for StopRule {
    fn default() -> Self {
        Self {
            target_cep50_m: 100.0,
            min_effective: 10.0,
            offset_share: 0.6,
            max_axis_ratio: 3.0,
        }
    }
}

impl StopRule {
    /// `Ok` when usable.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[
            self.target_cep50_m,
            self.min_effective,
            self.offset_share,
            self.max_axis_ratio,
        ])?;
        if self.target_cep50_m > 0.0
            && self.min_effective >= 0.0
            && self.offset_share > 0.0
            && self.offset_share <= 1.0
            && self.max_axis_ratio >= 1.0
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// What the fix says about itself (from [`crate::fix::locate::Source`]: `consistent` and
/// `effective`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixQuality {
    /// The residuals agree with the noise model.
    pub consistent: bool,
    /// Effective number of independent bearings.
    pub effective: f32,
    /// The DF unit's offset contradicted its prior (from
    /// [`crate::fix::locate::OffsetCheck::relaxed`]).
    pub offset_beyond_prior: bool,
}

/// What limits the fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// The bearings' angles: the ellipse is long and thin.
    Angle,
    /// The range: both axes are too long.
    Range,
    /// The unit's unknown offset.
    Offset,
}

/// What a fix lacks to be good enough.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Missing {
    /// The predicted CEP50 is above the target.
    pub precision: bool,
    /// The residuals are not consistent with the noise model.
    pub consistency: bool,
    /// Too few independent bearings.
    pub bearings: bool,
    /// A DF unit whose offset agrees with its prior.
    pub offset: bool,
    /// An offset known to [`KNOWN_SD`]: the prior is wider and the drive has not measured it.
    pub offset_measurement: bool,
}

impl Missing {
    /// Nothing is missing.
    pub fn none(&self) -> bool {
        !(self.precision
            || self.consistency
            || self.bearings
            || self.offset
            || self.offset_measurement)
    }
}

/// The stop rule's verdict.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    /// Stop: the fix is good enough.
    pub good_enough: bool,
    /// Predicted CEP50 from the bias-aware bound at the fix, metres.
    pub cep50_m: f32,
    /// The same with the offset known, metres (equal for a calibrated unit).
    pub offset_known_cep50_m: f32,
    /// Major / minor sd of the bound's ellipse.
    pub axis_ratio: f32,
    /// What is missing.
    pub missing: Missing,
    /// What limits the precision.
    pub limit: Limit,
}

/// Why a move is advised: the words a driver reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason {
    /// The stop rule holds.
    GoodEnough,
    /// The bearings cross too shallowly: drive across the line of bearing.
    WidenAngle,
    /// The emitter is too far for the bearings' noise: drive toward it.
    GetCloser,
    /// The unknown offset limits the fix: drive a calibration leg (or round the emitter).
    CalibrationLeg,
    /// The drive has not measured the offset and its prior is an assumption: turn, or
    /// calibrate.
    MeasureOffset,
    /// Too few independent bearings yet: keep collecting.
    MoreBearings,
    /// The residuals do not fit the noise model: check the DF unit (or a reflection).
    CheckUnit,
    /// The DF unit's offset is in doubt (far from its prior, or another offset fits as well):
    /// check the antenna, then calibrate.
    CheckOffset,
}

impl Reason {
    /// A short name for machine-readable output.
    pub fn name(&self) -> &'static str {
        match self {
            Reason::GoodEnough => "good-enough",
            Reason::WidenAngle => "widen-angle",
            Reason::GetCloser => "get-closer",
            Reason::CalibrationLeg => "calibration-leg",
            Reason::MeasureOffset => "measure-offset",
            Reason::MoreBearings => "more-bearings",
            Reason::CheckUnit => "check-unit",
            Reason::CheckOffset => "check-offset",
        }
    }
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Reason::GoodEnough => "good enough: stop",
            Reason::WidenAngle => "widen the angle",
            Reason::GetCloser => "get closer",
            Reason::CalibrationLeg => "drive a calibration leg (the offset limits the fix)",
            Reason::MeasureOffset => {
                "the drive has not measured the DF unit's offset (the fix assumes its prior): \
                 turn, or drive a calibration leg"
            }
            Reason::MoreBearings => "more bearings",
            Reason::CheckUnit => "residuals inconsistent: check the DF unit",
            Reason::CheckOffset => {
                "the DF unit's offset is in doubt (far from its prior, or another fits as \
                 well): check the antenna (mounting, array indexing, cables), then calibrate"
            }
        })
    }
}

impl Verdict {
    /// The one reason to give the driver: what is missing first (consistency, precision with
    /// its limit, bearings, the offset's doubt, then its measurement).
    pub fn reason(&self) -> Reason {
        if self.good_enough {
            Reason::GoodEnough
        } else if self.missing.consistency {
            Reason::CheckUnit
        } else if self.missing.precision {
            match self.limit {
                Limit::Offset => Reason::CalibrationLeg,
                Limit::Angle => Reason::WidenAngle,
                Limit::Range => Reason::GetCloser,
            }
        } else if self.missing.bearings {
            Reason::MoreBearings
        } else if self.missing.offset {
            // Late: early in a drive the offset is often in doubt only because the bearings
            // have not turned yet, and the move that turns them serves both.
            Reason::CheckOffset
        } else {
            Reason::MeasureOffset
        }
    }
}

/// The stop rule on the fix at `position` from `bearings`, the unit's offset `prior` and the
/// fix's own `quality`.
pub fn verdict(
    position: [f32; 2],
    bearings: &[Bearing],
    prior: BiasPrior,
    quality: FixQuality,
    rule: &StopRule,
) -> Result<Verdict, Error> {
    rule.check()?;
    check_finite(&[quality.effective])?;
    let aware = Belief::from_bearings(position, bearings, prior, f32::INFINITY)?;
    let known = if prior.is_free() {
        Belief::from_bearings(
            position,
            bearings,
            BiasPrior::calibrated(prior.mean),
            f32::INFINITY,
        )?
    } else {
        aware
    };
    let cep50_m = aware.cep50();
    let offset_known_cep50_m = known.cep50();
    let (major, minor) = known.axes();
    let axis_ratio = if minor > 0.0 { major / minor } else { f32::MAX };
    check_finite(&[cep50_m, offset_known_cep50_m])?;
    let missing = Missing {
        precision: !(cep50_m < rule.target_cep50_m),
        consistency: !quality.consistent,
        bearings: !(quality.effective >= rule.min_effective),
        offset: quality.offset_beyond_prior,
        offset_measurement: !(aware.bias_sd() <= KNOWN_SD),
    };
    let limit = if offset_known_cep50_m < rule.offset_share * cep50_m {
        Limit::Offset
    } else if axis_ratio > rule.max_axis_ratio {
        Limit::Angle
    } else {
        Limit::Range
    };
    Ok(Verdict {
        good_enough: missing.none(),
        cep50_m,
        offset_known_cep50_m,
        axis_ratio,
        missing,
        limit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::predicted;

    const DEG: f32 = core::f32::consts::PI / 180.0;

    fn leg(e: [f32; 2], from: [f32; 2], to: [f32; 2]) -> [Bearing; 60] {
        core::array::from_fn(|k| {
            let t = k as f32 / 59.0;
            let v = [
                from[0] + t * (to[0] - from[0]),
                from[1] + t * (to[1] - from[1]),
            ];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 3.0 * DEG,
            }
        })
    }

    const GOOD: FixQuality = FixQuality {
        consistent: true,
        effective: 60.0,
        offset_beyond_prior: false,
    };

    #[test]
    fn each_limit_is_named() {
        let rule = StopRule::default();
        let cal = BiasPrior::calibrated(0.0);
        // A short straight leg broadside to a far emitter: long thin ellipse.
        let e = [0.0, 4000.0];
        let v = verdict(e, &leg(e, [-300.0, 0.0], [300.0, 0.0]), cal, GOOD, &rule).unwrap();
        assert_eq!(
            (v.limit, v.reason()),
            (Limit::Angle, Reason::WidenAngle),
            "{v:?}"
        );
        // A right-angle crossing, far away: round but large.
        let far = [-4000.0, 4000.0];
        let mut cross = leg(far, [0.0, 4000.0], [0.0, 4300.0]);
        cross[30..].copy_from_slice(&leg(far, [-4000.0, 0.0], [-3700.0, 0.0])[30..]);
        // (A 45 m CEP50: against a 20 m target, the range is what is short.)
        let strict = StopRule {
            target_cep50_m: 20.0,
            ..rule
        };
        let v = verdict(far, &cross, cal, GOOD, &strict).unwrap();
        assert_eq!(
            (v.limit, v.reason()),
            (Limit::Range, Reason::GetCloser),
            "{v:?}"
        );
        // The same long straight leg with an unknown offset: the offset limits.
        let e = [0.0, 1500.0];
        let long = leg(e, [-1500.0, 0.0], [1500.0, 0.0]);
        let v = verdict(e, &long, BiasPrior::default(), GOOD, &strict).unwrap();
        assert_eq!(
            (v.limit, v.reason()),
            (Limit::Offset, Reason::CalibrationLeg),
            "{v:?}"
        );
        assert!(v.offset_known_cep50_m < 0.6 * v.cep50_m);
    }

    #[test]
    fn an_offset_the_drive_has_not_measured_is_never_good_enough() {
        // A short straight leg: the bearings turn 28 degrees, too little to tell a 6 degree
        // prior's offset from a cross-range shift. A generous target isolates the offset.
        let rule = StopRule {
            target_cep50_m: 1000.0,
            ..StopRule::default()
        };
        let e = [0.0, 400.0];
        let short = leg(e, [-100.0, 0.0], [100.0, 0.0]);
        let v = verdict(e, &short, BiasPrior::default(), GOOD, &rule).unwrap();
        assert!(
            v.missing.offset_measurement && !v.good_enough && v.reason() == Reason::MeasureOffset,
            "{v:?}"
        );
        // A calibration states the offset: the same leg is good enough.
        let cal = BiasPrior {
            mean: 0.0,
            sd: 0.5 * DEG,
        };
        let v = verdict(e, &short, cal, GOOD, &rule).unwrap();
        assert!(v.good_enough, "{v:?}");
        // A leg past the emitter turns the bearings 127 degrees: the drive measures it.
        let long = leg(e, [-800.0, 0.0], [800.0, 0.0]);
        let v = verdict(e, &long, BiasPrior::default(), GOOD, &rule).unwrap();
        assert!(!v.missing.offset_measurement && v.good_enough, "{v:?}");
    }

    #[test]
    fn good_enough_needs_all_three() {
        let rule = StopRule::default();
        let e = [0.0, 300.0];
        let bs = leg(e, [-600.0, 0.0], [600.0, 0.0]);
        let cal = BiasPrior::calibrated(0.0);
        let v = verdict(e, &bs, cal, GOOD, &rule).unwrap();
        assert!(v.good_enough && v.reason() == Reason::GoodEnough, "{v:?}");
        let bad = FixQuality {
            consistent: false,
            ..GOOD
        };
        let v = verdict(e, &bs, cal, bad, &rule).unwrap();
        assert!(!v.good_enough && v.reason() == Reason::CheckUnit);
        let few = FixQuality {
            effective: 4.0,
            ..GOOD
        };
        let v = verdict(e, &bs, cal, few, &rule).unwrap();
        assert!(
            v.missing.bearings && v.reason() == Reason::MoreBearings,
            "{v:?}"
        );
        // A fix past its offset's prior: never good enough, however tight, and the unit first.
        let beyond = FixQuality {
            offset_beyond_prior: true,
            ..GOOD
        };
        let v = verdict(e, &bs, cal, beyond, &rule).unwrap();
        assert!(
            v.missing.offset && !v.good_enough && v.reason() == Reason::CheckOffset,
            "{v:?}"
        );
        let strict = StopRule {
            target_cep50_m: 1.0,
            ..rule
        };
        let v = verdict(e, &bs, cal, GOOD, &strict).unwrap();
        assert!(v.missing.precision && !v.good_enough);
        let broken = StopRule {
            offset_share: 0.0,
            ..rule
        };
        assert_eq!(verdict(e, &bs, cal, GOOD, &broken), Err(Error::OutOfRange));
    }
}
