//! Gaussian particle filter (Kotecha and Djuric 2003; seed 003): the posterior is carried as one
//! Gaussian, and each step samples it, propagates, weights, and refits mean and covariance.
//! No resampling, so no degeneracy; O(N D^2) per step.

use super::{Estimate, Filter, StepStatus, moments, scaled};
use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::particles::ParticleSet;
use crate::swarm::{NoSwarm, Swarm};
use rand_core::Rng;

/// The Gaussian particle filter over model `M`, likelihood `L`, `N` samples of dimension `D`.
#[derive(Debug, Clone)]
pub struct Gpf<M, L, const N: usize, const D: usize, S = NoSwarm> {
    /// State-space model.
    pub model: M,
    /// Measurement likelihood.
    pub likelihood: L,
    /// Swarm move run between prediction and weighting ([`NoSwarm`] for the plain filter).
    pub swarm: S,
    samples: ParticleSet<N, D>,
    evaluations: u64,
    prior: Option<([f32; D], [[f32; D]; D])>,
    last: Estimate<D>,
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize> Gpf<M, L, N, D> {
    /// A plain GPF awaiting [`Filter::initialise`].
    pub fn new(model: M, likelihood: L) -> Self {
        Self::with_swarm(model, likelihood, NoSwarm)
    }
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize, S: Swarm<D>> Gpf<M, L, N, D, S> {
    /// A swarm-optimised GPF (PSO-GPF, GSA-GPF) awaiting [`Filter::initialise`].
    pub fn with_swarm(model: M, likelihood: L, swarm: S) -> Self {
        Self {
            model,
            likelihood,
            swarm,
            evaluations: 0,
            samples: ParticleSet::new(),
            prior: None,
            last: Estimate {
                mean: [0.0; D],
                covariance: [[0.0; D]; D],
                ess: 0.0,
                status: StepStatus::Updated,
            },
        }
    }

    /// The weighted samples of the last step.
    pub fn samples(&self) -> &ParticleSet<N, D> {
        &self.samples
    }

    /// Mutable samples: the swarm optimisers move them before the moments are refitted.
    pub fn samples_mut(&mut self) -> &mut ParticleSet<N, D> {
        &mut self.samples
    }

    /// Draw the samples from the current Gaussian and propagate them.
    pub fn predict<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<(), Error> {
        let Estimate {
            mean, covariance, ..
        } = self.last;
        self.samples.draw_gaussian(&mean, &covariance, rng)?;
        self.model.propagate_all(&mut self.samples.states, z, rng);
        Ok(())
    }

    /// Weight the current samples by `z` and refit the Gaussian.
    pub fn update<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error> {
        self.samples.log_weights = [0.0; N];
        self.model.add_ln_likelihoods(
            &self.samples.states,
            z,
            &self.likelihood,
            &mut self.samples.log_weights,
        );
        self.evaluations += N as u64;
        let ess = match self.samples.normalise() {
            Ok(ess) => ess,
            Err(Error::WeightCollapse) => {
                let (mean, cov) = self.prior.ok_or(Error::NotInitialised)?;
                self.samples.draw_gaussian(&mean, &scaled(&cov, 4.0), rng)?;
                self.last = Estimate {
                    mean,
                    covariance: scaled(&cov, 4.0),
                    ess: N as f32,
                    status: StepStatus::Reinitialised,
                };
                return Ok(self.last);
            }
            Err(e) => return Err(e),
        };
        let mean = self.samples.mean();
        let covariance = self.samples.covariance(&mean);
        if !super::all_finite(&mean, &covariance) {
            return Err(Error::NonFinite);
        }
        self.last = Estimate {
            mean,
            covariance,
            ess,
            status: StepStatus::Updated,
        };
        Ok(self.last)
    }
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize, S: Swarm<D>> Filter<D>
    for Gpf<M, L, N, D, S>
{
    type Measurement = M::Measurement;

    fn initialise<R: Rng + ?Sized>(
        &mut self,
        cloud: &[[f32; D]],
        _rng: &mut R,
    ) -> Result<(), Error> {
        let (mean, covariance) = moments(cloud)?;
        self.prior = Some((mean, covariance));
        self.last = Estimate {
            mean,
            covariance,
            ess: N as f32,
            status: StepStatus::Updated,
        };
        Ok(())
    }

    fn step<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error> {
        if self.prior.is_none() {
            return Err(Error::NotInitialised);
        }
        self.model.check(z)?;
        self.predict(z, rng)?;
        if S::MOVES {
            let fitness = self.model.fitness(z, &self.likelihood);
            let spent = self.swarm.optimise(&mut self.samples, fitness, rng);
            self.evaluations += spent as u64;
        }
        self.update(z, rng)
    }

    fn estimate(&self) -> Estimate<D> {
        self.last
    }

    fn evaluations(&self) -> u64 {
        self.evaluations
    }
}
