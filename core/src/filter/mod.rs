//! Sequential filters behind one trait: step a measurement in, get an estimate out.

pub mod ekf;
pub mod gpf;
pub mod sir;

use crate::error::Error;
use rand_core::Rng;

/// What happened in a step besides the update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StepStatus {
    /// A normal update.
    #[default]
    Updated,
    /// Every weight vanished (the measurement contradicts every hypothesis): the filter went
    /// back to its prior, widened. The estimate is that prior, not a confident answer.
    Reinitialised,
}

/// A filter's estimate after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<const D: usize> {
    /// Posterior mean.
    pub mean: [f32; D],
    /// Posterior covariance.
    pub covariance: [[f32; D]; D],
    /// Effective sample size before resampling (particle filters), or 0 for Kalman filters.
    pub ess: f32,
    /// What the step did.
    pub status: StepStatus,
}

/// A recursive estimator of a `D`-dimensional state.
pub trait Filter<const D: usize> {
    /// The measurement it consumes.
    type Measurement;

    /// Start from a cloud of state hypotheses (e.g. bearing-pair intersections). Particle
    /// filters take the points themselves; Gaussian filters their mean and covariance.
    fn initialise<R: Rng + ?Sized>(&mut self, cloud: &[[f32; D]], rng: &mut R)
    -> Result<(), Error>;

    /// Fold in one measurement. A measurement that fails its check is rejected with a typed
    /// error and leaves the filter untouched.
    fn step<R: Rng + ?Sized>(
        &mut self,
        z: &Self::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error>;

    /// The current estimate.
    fn estimate(&self) -> Estimate<D>;

    /// Likelihood evaluations so far: the machine-independent cost of a run.
    fn evaluations(&self) -> u64 {
        0
    }
}

/// Mean and covariance of an equally weighted cloud: the prior every filter starts from.
/// An empty cloud is [`Error::TooFewMeasurements`], a non-finite one [`Error::NonFinite`].
pub(crate) fn moments<const D: usize>(
    cloud: &[[f32; D]],
) -> Result<([f32; D], [[f32; D]; D]), Error> {
    if cloud.is_empty() {
        return Err(Error::TooFewMeasurements);
    }
    let n = cloud.len() as f32;
    let mut mean = [0.0f32; D];
    for x in cloud {
        for j in 0..D {
            mean[j] += x[j] / n;
        }
    }
    let mut cov = [[0.0f32; D]; D];
    for x in cloud {
        for i in 0..D {
            for j in 0..D {
                cov[i][j] += (x[i] - mean[i]) * (x[j] - mean[j]) / n;
            }
        }
    }
    if all_finite(&mean, &cov) {
        Ok((mean, cov))
    } else {
        Err(Error::NonFinite)
    }
}

/// Covariance scaled by `k` (variance inflation for a widened prior).
pub(crate) fn scaled<const D: usize>(cov: &[[f32; D]; D], k: f32) -> [[f32; D]; D] {
    let mut c = *cov;
    for v in c.iter_mut().flatten() {
        *v *= k;
    }
    c
}

/// Whether a mean and covariance hold only finite numbers.
pub(crate) fn all_finite<const D: usize>(mean: &[f32; D], cov: &[[f32; D]; D]) -> bool {
    mean.iter()
        .chain(cov.iter().flatten())
        .all(|v| v.is_finite())
}
