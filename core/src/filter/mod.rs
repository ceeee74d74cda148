//! Sequential filters behind one trait: step a measurement in, get an estimate out.
//!
//! The two particle filters ([`sir`] and [`gpf`]) share one skeleton (`ParticleState`): the
//! prior they started from and restart from, the weighting and its collapse handling, the swarm
//! move and the likelihood count. They differ only in what they do with the weighted cloud:
//! the SIR resamples it, the GPF refits a Gaussian and draws afresh.

pub mod ekf;
pub mod gpf;
pub mod sir;

use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::particles::ParticleSet;
use crate::swarm::Swarm;
use rand_core::Rng;

/// What happened in a step besides the update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StepStatus {
    /// A normal update.
    #[default]
    Updated,
    /// Every weight vanished, or the estimate stopped being finite (the measurement
    /// contradicts every hypothesis): the filter went back to its prior, widened. The estimate
    /// is that prior, not a confident answer.
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

    /// The current estimate; [`Error::NotInitialised`] before [`Filter::initialise`].
    fn estimate(&self) -> Result<Estimate<D>, Error>;

    /// Likelihood evaluations so far: the machine-independent cost of a run.
    fn evaluations(&self) -> u64 {
        0
    }

    /// The particles as they stand (none for a Kalman filter): for maps and diagnostics.
    fn cloud(&self) -> &[[f32; D]] {
        &[]
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

/// Whether a mean and covariance hold only finite numbers.
pub(crate) fn all_finite<const D: usize>(mean: &[f32; D], cov: &[[f32; D]; D]) -> bool {
    mean.iter()
        .chain(cov.iter().flatten())
        .all(|v| v.is_finite())
}

/// Variance inflation of the prior when a particle filter restarts from it: wide enough to
/// catch a target the measurements moved away from, still centred on what was believed.
const RESTART_INFLATION: f32 = 4.0;

/// The moments of the cloud a particle filter was started from.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Prior<const D: usize> {
    mean: [f32; D],
    covariance: [[f32; D]; D],
}

/// The weighted cloud's effective sample size, mean and covariance.
pub(crate) type Weighed<const D: usize> = (f32, [f32; D], [[f32; D]; D]);

/// What both particle filters carry: the weighted set, the prior to restart from, the last
/// estimate and the likelihood evaluations spent.
#[derive(Debug, Clone)]
pub(crate) struct ParticleState<const N: usize, const D: usize> {
    pub(crate) set: ParticleSet<N, D>,
    evaluations: u64,
    prior: Option<Prior<D>>,
    last: Option<Estimate<D>>,
}

impl<const N: usize, const D: usize> ParticleState<N, D> {
    pub(crate) const fn new() -> Self {
        Self {
            set: ParticleSet::new(),
            evaluations: 0,
            prior: None,
            last: None,
        }
    }

    /// Take the moments of `cloud` as the prior and its points as the particles (repeated
    /// cyclically to fill N), equally weighted.
    pub(crate) fn initialise(&mut self, cloud: &[[f32; D]]) -> Result<(), Error> {
        let (mean, covariance) = moments(cloud)?;
        for (i, x) in self.set.states.iter_mut().enumerate() {
            *x = cloud[i % cloud.len()];
        }
        self.set.set_uniform_weights();
        self.prior = Some(Prior { mean, covariance });
        self.last = Some(Estimate {
            mean,
            covariance,
            ess: N as f32,
            status: StepStatus::Updated,
        });
        Ok(())
    }

    /// The checks before a step: initialised, and a usable measurement.
    pub(crate) fn ready<M: Model<D>>(&self, model: &M, z: &M::Measurement) -> Result<(), Error> {
        if self.prior.is_none() {
            return Err(Error::NotInitialised);
        }
        model.check(z)
    }

    /// The swarm's move toward higher likelihood (nothing for [`crate::NoSwarm`]).
    pub(crate) fn swarm_move<M: Model<D>, L: Likelihood, S: Swarm<D>, R: Rng + ?Sized>(
        &mut self,
        model: &M,
        z: &M::Measurement,
        likelihood: &L,
        swarm: &mut S,
        rng: &mut R,
    ) {
        if S::MOVES {
            let spent = optimise_swarm(&mut self.set, model, z, likelihood, swarm, rng);
            self.evaluations += u64::from(spent);
        }
    }

    /// Add the log-likelihood of `z` to every particle, normalise, and take the weighted
    /// moments, or `None` when the weights collapsed or the moments are not finite (the caller
    /// restarts).
    pub(crate) fn weigh<M: Model<D>, L: Likelihood>(
        &mut self,
        model: &M,
        z: &M::Measurement,
        likelihood: &L,
    ) -> Result<Option<Weighed<D>>, Error> {
        model.update_all(
            &mut self.set.states,
            z,
            likelihood,
            &mut self.set.log_weights,
        );
        self.evaluations += N as u64;
        let ess = match self.set.normalise() {
            Ok(ess) => ess,
            Err(Error::WeightCollapse) => return Ok(None),
            Err(e) => return Err(e),
        };
        let mean = self.set.mean();
        let covariance = self.set.covariance(&mean);
        Ok(all_finite(&mean, &covariance).then_some((ess, mean, covariance)))
    }

    /// Draw the particles afresh from the prior, widened, and report it as the estimate.
    pub(crate) fn restart<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Result<Estimate<D>, Error> {
        let prior = self.prior.ok_or(Error::NotInitialised)?;
        let mut wide = prior.covariance;
        for v in wide.iter_mut().flatten() {
            *v *= RESTART_INFLATION;
        }
        self.set.draw_gaussian(&prior.mean, &wide, rng)?;
        Ok(self.record(Estimate {
            mean: prior.mean,
            covariance: wide,
            ess: N as f32,
            status: StepStatus::Reinitialised,
        }))
    }

    /// Keep `e` as the current estimate and return it.
    pub(crate) fn record(&mut self, e: Estimate<D>) -> Estimate<D> {
        self.last = Some(e);
        e
    }

    pub(crate) fn estimate(&self) -> Result<Estimate<D>, Error> {
        self.last.ok_or(Error::NotInitialised)
    }

    pub(crate) fn evaluations(&self) -> u64 {
        self.evaluations
    }
}

/// One swarm move over `set`, kept out of line: inlined into the registry's dispatch, which
/// builds every filter in one function, the swarms' inner loops lost registers to it.
#[inline(never)]
fn optimise_swarm<const N: usize, const D: usize, M, L, S, R>(
    set: &mut ParticleSet<N, D>,
    model: &M,
    z: &M::Measurement,
    likelihood: &L,
    swarm: &mut S,
    rng: &mut R,
) -> u32
where
    M: Model<D>,
    L: Likelihood,
    S: Swarm<D>,
    R: Rng + ?Sized,
{
    swarm.optimise(set, model.fitness(z, likelihood), rng)
}
