//! A constant bearing offset per DF source, estimated with the position.
//!
//! Every real DF unit has one: an antenna mounted a few degrees off the vehicle's axis, an
//! array whose reference element is not where the software thinks (1-5 degrees for
//! pseudo-Doppler units, 9-12 for some KrakenSDR set-ups: docs/src/field.md, "Mounting offset"). Ignored, an offset b
//! moves the fix by about r b (5 degrees at 2 km: 175 m) while the ellipse stays small. Here
//! the model is z_k = atan2(emitter - s_k) + b_{source(k)} + noise and the unknowns are
//! [x, y, b_0 .. b_{S-1}]: the ML Jacobian gains one column of ones per source.
//!
//! Each offset has a Gaussian prior: by default mean 0 and sd [`DEFAULT_BIAS_SD`] (6 degrees,
//! so the 1-12 degrees real units show lie within two sd); sd 0 is a calibrated unit (the
//! offset is fixed at the prior's mean); an infinite sd is no prior at all. On a drive that
//! cannot tell an offset from a cross-range shift (a straight road, a short arc: docs/src/field.md's
//! inscribed-angle argument) the prior governs and the position covariance, the marginal of the
//! (2 + S)-dimensional one, grows to show it; where the drive surrounds the emitter the offset
//! is measured to sigma / sqrt(N) and costs the position nothing.
//!
//! Levenberg-Marquardt on sum rho(r_k / sigma_k) + sum (b - mu)^2 / (2 tau^2) with any
//! [`Likelihood`](crate::likelihood::Likelihood)'s IRLS weights; the normal matrix is scaled to
//! unit diagonal before it is factored, since in f32 the position terms (1 / (sigma r)^2) and
//! the offset terms (1 / sigma^2) differ by the square of the range.

mod bound;
mod calibration;
mod prior;
mod problem;
mod profile_likelihood;
mod solve;
#[cfg(test)]
mod tests;

pub use bound::{BiasedCrlb, crlb, information};
pub use calibration::{Calibration, calibrate};
pub use prior::{BiasPrior, same_priors};
pub use profile_likelihood::{ProfilePoint, profile};
pub use solve::{BiasedFix, BiasedOptions, Start, ml, ml_sources, refit};

use crate::model::bearing::Bearing;

/// DF sources (units, or antenna set-ups) whose offsets are estimated separately.
pub const MAX_SOURCES: usize = 4;
/// Unknowns of the fix: position and one offset per source.
pub const STATE: usize = 2 + MAX_SOURCES;
/// Default prior sd of an uncalibrated unit's offset: 6 degrees, radians.
pub const DEFAULT_BIAS_SD: f32 = 6.0 * core::f32::consts::PI / 180.0;

/// A bearing together with the DF source that took it.
pub trait Sighting {
    /// The bearing.
    fn bearing(&self) -> &Bearing;
    /// Index of its DF source (< [`MAX_SOURCES`] to be used).
    fn source(&self) -> usize {
        0
    }
}

impl Sighting for Bearing {
    fn bearing(&self) -> &Bearing {
        self
    }
}
