//! What is known of each DF station's offset before the drive.

use super::DEFAULT_BIAS_SD;
use crate::error::{Error, check_finite};

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

    /// 1 / sd^2: the prior's information (0 for no prior).
    pub(super) fn information(&self) -> f32 {
        if self.sd.is_finite() && self.sd > 0.0 {
            1.0 / (self.sd * self.sd)
        } else {
            0.0
        }
    }
}
