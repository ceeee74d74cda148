//! The univariate nonstationary growth model (seed 001's benchmark, after Gordon et al. 1993):
//! x_k = x/2 + 25 x / (1 + x^2) + 8 cos(1.2 k) + u_k, z_k = x_k^2 / 20 + v_k.
//! The likelihood cannot tell x from -x: the bimodal stress test for any particle filter.

use super::Model;
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::random;
use rand_core::Rng;

/// One UNGM observation and its step index k (the transition depends on k).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UngmObservation {
    /// Step index k (1 for the first observation).
    pub k: u32,
    /// Observed value z_k.
    pub z: f32,
}

/// The UNGM with its noise levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ungm {
    /// Process noise variance.
    pub process_var: f32,
    /// Measurement noise variance.
    pub measurement_var: f32,
}

impl Default for Ungm {
    fn default() -> Self {
        Self {
            process_var: 1.0,
            measurement_var: 1.0,
        }
    }
}

impl Ungm {
    /// Noise-free transition into step k.
    #[inline]
    pub fn transition(x: f32, k: u32) -> f32 {
        0.5 * x + 25.0 * x / (1.0 + x * x) + 8.0 * libm::cosf(1.2 * k as f32)
    }

    /// Noise-free observation.
    #[inline]
    pub fn observe(x: f32) -> f32 {
        x * x / 20.0
    }
}

impl Model<1> for Ungm {
    type Measurement = UngmObservation;

    fn check(&self, z: &UngmObservation) -> Result<(), Error> {
        check_finite(&[z.z, self.process_var, self.measurement_var])?;
        if self.process_var >= 0.0 && self.measurement_var > 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; 1], z: &UngmObservation, rng: &mut R) {
        x[0] = Self::transition(x[0], z.k) + libm::sqrtf(self.process_var) * random::normal(rng);
    }

    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; 1], z: &UngmObservation, lik: &L) -> f32 {
        lik.ln(z.z - Self::observe(x[0]), libm::sqrtf(self.measurement_var))
    }
}
