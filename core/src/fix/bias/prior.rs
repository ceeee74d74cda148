//! What is known of each DF station's offset before the drive.

use super::DEFAULT_BIAS_SD;
use crate::error::{Error, check_finite};
use crate::model::bearing::wrap;

/// A fitted offset more than this many of its predicted sds from the prior's mean
/// ([`BiasPrior::surprise`]) contradicts the prior: 3 sds, a false alarm in 0.3 % of drives
/// whose prior holds, where a unit five degrees out of a 6 degree prior is never flagged and an
/// array indexed one element off (72 degrees) always is.
pub const CONTRADICTED_Z: f32 = 3.0;

/// An offset known to this sd (radians: 3 degrees, half the default prior's) or better is
/// measured: by a calibration, a surveyed station, or the drive itself. A wider one is the
/// prior's assumption, which the drive has not checked: an offset several of its sds off (a
/// swapped cable, an array indexed one element off) moves such a fix by about range x offset
/// with nothing in the residuals to show it, and only a turn or a calibration can tell
/// (docs/src/field.md, "Past the prior"). Measured to 3 degrees, a unit whose 6 degree prior is
/// 21 degrees wrong lies 3 of the sds the prior predicts out, which the offset check flags.
pub const KNOWN_SD: f32 = 3.0 * core::f32::consts::PI / 180.0;

/// What is known of one station's offset before the drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasPrior {
    /// Expected offset, radians (added to the true bearing by the unit).
    pub mean: f32,
    /// Its standard deviation, radians: 0 for a calibrated unit (fixed at `mean`), infinite
    /// for no prior.
    pub sd: f32,
}

impl Default for BiasPrior {
    fn default() -> Self {
        Self {
            mean: 0.0,
            sd: DEFAULT_BIAS_SD,
        }
    }
}

impl BiasPrior {
    /// A unit calibrated to `offset` (its offset is not estimated).
    pub const fn calibrated(offset: f32) -> Self {
        Self {
            mean: offset,
            sd: 0.0,
        }
    }

    /// `Ok` when the mean is finite and the sd is >= 0 (infinity allowed).
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[self.mean])?;
        if self.sd >= 0.0 {
            Ok(())
        } else if self.sd.is_nan() {
            Err(Error::NonFinite)
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// Whether the offset is a free unknown (sd > 0).
    pub fn is_free(&self) -> bool {
        self.sd > 0.0
    }

    /// How far a fit's offset `estimate` (made with this prior; its posterior sd `sd`) lies from
    /// the prior's mean, in the sds the prior predicts for it: if the prior holds, the
    /// estimate's spread about the mean is the prior's variance less the posterior's (the
    /// share of the offset the data measured), so this is a standard normal. 0 for a
    /// calibrated unit or no prior (nothing to contradict), and near 0 where the data measured
    /// nothing of the offset (the estimate did not move).
    pub fn surprise(&self, estimate: f32, sd: f32) -> f32 {
        if !(self.is_free() && self.sd.is_finite()) {
            return 0.0;
        }
        let tau2 = self.sd * self.sd;
        // Floored at 5 % of the prior's sd: a posterior as wide as the prior moved nothing.
        let spread = (tau2 - sd * sd).max(0.0025 * tau2);
        let z = wrap(estimate - self.mean) / libm::sqrtf(spread);
        if z.is_finite() { z } else { 0.0 }
    }

    /// [`BiasPrior::surprise`] of a fit whose bearings' errors are correlated over `tau`
    /// bearings (N / N_eff, >= 1): the fit weighed them as independent, so its offset moved
    /// toward the data by w = 1 - sd^2 / tau_p^2 as if they held tau times the information
    /// they hold, and the estimate's spread about the prior's mean is w sqrt(tau_p^2 +
    /// tau / I_data) (I_data = 1 / sd^2 - 1 / tau_p^2), not sqrt(tau_p^2 - sd^2). Without
    /// correlation (tau = 1) this is [`BiasPrior::surprise`].
    pub fn surprise_correlated(&self, estimate: f32, sd: f32, tau: f32) -> f32 {
        if !(tau > 1.0 && self.is_free() && self.sd.is_finite()) {
            return self.surprise(estimate, sd);
        }
        let info_prior = self.information();
        let info_data = 1.0 / (sd * sd) - info_prior;
        if !(info_data > 0.0) {
            return self.surprise(estimate, sd);
        }
        let w = info_data / (info_data + info_prior);
        let spread = (w * libm::sqrtf(self.sd * self.sd + tau / info_data)).max(0.05 * self.sd);
        let z = wrap(estimate - self.mean) / spread;
        if z.is_finite() { z } else { 0.0 }
    }

    /// [`BiasPrior::surprise`] of an offset `estimate` fitted without this prior (its sd `sd`,
    /// the data's alone): if the prior holds, the estimate's spread about its mean is the
    /// prior's variance plus the data's.
    pub fn surprise_unaided(&self, estimate: f32, sd: f32) -> f32 {
        if !(self.is_free() && self.sd.is_finite()) {
            return 0.0;
        }
        let z = wrap(estimate - self.mean) / libm::sqrtf(self.sd * self.sd + sd * sd);
        if z.is_finite() { z } else { 0.0 }
    }

    /// 1 / sd^2: the prior's information (0 for no prior).
    pub fn information(&self) -> f32 {
        if self.sd.is_finite() && self.sd > 0.0 {
            1.0 / (self.sd * self.sd)
        } else {
            0.0
        }
    }
}
