//! Gaussian particle filter (Kotecha and Djuric 2003; seed 003): the posterior is carried as one
//! Gaussian, and each step samples it, propagates, weights, and refits mean and covariance.
//! No resampling, so no degeneracy; O(N D^2) per step.

use super::{Estimate, Filter, ParticleState, StepStatus};
use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::particles::ParticleSet;
use crate::swarm::{NoSwarm, Swarm};
use rand_core::Rng;

/// The Gaussian particle filter over model `M`, likelihood `L`, `N` samples of dimension `D`,
/// with an optional swarm move between prediction and weighting (PSO-GPF, GSA-GPF).
#[derive(Debug, Clone)]
pub struct Gpf<M, L, const N: usize, const D: usize, S = NoSwarm> {
    /// State-space model.
    pub model: M,
    /// Measurement likelihood.
    pub likelihood: L,
    /// Swarm move run between prediction and weighting ([`NoSwarm`] for the plain filter).
    pub swarm: S,
    state: ParticleState<N, D>,
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
            state: ParticleState::new(),
        }
    }

    /// The weighted samples of the last step.
    pub fn samples(&self) -> &ParticleSet<N, D> {
        &self.state.set
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
        self.state.initialise(cloud)
    }

    fn step<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error> {
        self.state.ready(&self.model, z)?;
        let Estimate {
            mean, covariance, ..
        } = self.state.estimate()?;
        // A covariance that lost its positive definiteness cannot be sampled: start over, as
        // for a collapse of the weights.
        if self
            .state
            .set
            .draw_gaussian(&mean, &covariance, rng)
            .is_err()
        {
            return self.state.restart(rng);
        }
        self.model.propagate_all(&mut self.state.set.states, z, rng);
        let (model, lik) = (&self.model, &self.likelihood);
        self.state.swarm_move(model, z, lik, &mut self.swarm, rng);
        let Some((ess, mean, covariance)) = self.state.weigh(model, z, lik)? else {
            return self.state.restart(rng);
        };
        Ok(self.state.record(Estimate {
            mean,
            covariance,
            ess,
            status: StepStatus::Updated,
        }))
    }

    fn estimate(&self) -> Result<Estimate<D>, Error> {
        self.state.estimate()
    }

    fn evaluations(&self) -> u64 {
        self.state.evaluations()
    }

    fn cloud(&self) -> &[[f32; D]] {
        &self.state.set.states
    }
}
