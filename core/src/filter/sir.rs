//! Sampling importance resampling, the bootstrap particle filter (Gordon 1993; seed 004, and
//! the baseline of seeds 001-003). Cost O(N) per step: one propagation and one likelihood per
//! particle, one normalisation, an O(N) resampling when the policy says so.

use super::{Estimate, Filter, ParticleState, StepStatus};
use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::particles::ParticleSet;
use crate::resample::{ResamplePolicy, Resampling};
use crate::roughen::{KERNEL_PERIOD_S, Roughening};
use crate::swarm::{NoSwarm, Swarm};
use rand_core::Rng;

/// SIR settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SirConfig {
    /// Resampling scheme.
    pub resampling: Resampling,
    /// When to resample.
    pub policy: ResamplePolicy,
    /// Jitter after resampling.
    pub roughening: Roughening,
}

impl Default for SirConfig {
    /// [`SirConfig::TUNED`].
    fn default() -> Self {
        Self::TUNED
    }
}

impl SirConfig {
    /// Systematic resampling at ESS < N/2 with shrinkage roughening: the well-tuned plain
    /// filter every fancier one must beat.
    pub const TUNED: SirConfig = SirConfig {
        resampling: Resampling::Systematic,
        policy: ResamplePolicy::BelowEss(0.5),
        roughening: Roughening::Shrinkage { scale: 1.0 },
    };

    /// The seeds' construction: systematic resampling after every step, no roughening.
    pub const SEEDS: SirConfig = SirConfig {
        resampling: Resampling::Systematic,
        policy: ResamplePolicy::Always,
        roughening: Roughening::None,
    };

    /// `Ok` when the policy and the roughening parameter are usable numbers.
    pub fn check(&self) -> Result<(), Error> {
        self.policy.check()?;
        let p = match self.roughening {
            Roughening::None => 0.0,
            Roughening::Gordon { k } => k,
            Roughening::Shrinkage { scale } => scale,
        };
        if p.is_finite() && p >= 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// The bootstrap particle filter over model `M`, likelihood `L`, `N` particles of dimension `D`,
/// with an optional swarm move between prediction and weighting (AFSA-PF, FA-PF...).
#[derive(Debug, Clone)]
pub struct Sir<M, L, const N: usize, const D: usize, S = NoSwarm> {
    /// State-space model.
    pub model: M,
    /// Measurement likelihood.
    pub likelihood: L,
    /// Settings.
    pub config: SirConfig,
    /// Swarm move run between prediction and weighting ([`NoSwarm`] for the plain filter).
    pub swarm: S,
    state: ParticleState<N, D>,
    /// Seconds of time since the last roughening (a model whose steps are time).
    since_kernel_s: f32,
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize> Sir<M, L, N, D> {
    /// A plain SIR filter awaiting [`Filter::initialise`].
    pub fn new(model: M, likelihood: L, config: SirConfig) -> Self {
        Self::with_swarm(model, likelihood, config, NoSwarm)
    }
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize, S: Swarm<D>> Sir<M, L, N, D, S> {
    /// A swarm-optimised SIR filter awaiting [`Filter::initialise`].
    pub fn with_swarm(model: M, likelihood: L, config: SirConfig, swarm: S) -> Self {
        Self {
            model,
            likelihood,
            config,
            swarm,
            state: ParticleState::new(),
            since_kernel_s: 0.0,
        }
    }

    /// The particles, for plots and diagnostics.
    pub fn particles(&self) -> &ParticleSet<N, D> {
        &self.state.set
    }
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize, S: Swarm<D>> Filter<D>
    for Sir<M, L, N, D, S>
{
    type Measurement = M::Measurement;

    fn initialise<R: Rng + ?Sized>(
        &mut self,
        cloud: &[[f32; D]],
        _rng: &mut R,
    ) -> Result<(), Error> {
        self.since_kernel_s = 0.0;
        self.state.initialise(cloud)
    }

    fn step<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error> {
        self.config.check()?;
        self.state.ready(&self.model, z)?;
        self.model.propagate_all(&mut self.state.set.states, z, rng);
        let elapsed = self.model.elapsed_s(z);
        if let Some(dt) = elapsed {
            self.since_kernel_s += dt.max(0.0);
        }
        let (model, lik) = (&self.model, &self.likelihood);
        self.state.swarm_move(model, z, lik, &mut self.swarm, rng);
        let Some((ess, mean, covariance)) = self.state.weigh(model, z, lik)? else {
            return self.state.restart(rng);
        };
        if self.config.policy.due(ess, N) {
            let set = &mut self.state.set;
            set.resample(self.config.resampling, rng);
            let kernel = self.model.regularised(&covariance);
            // The kernel owed: a full one per resampling, or per KERNEL_PERIOD_S of time.
            let share = elapsed.map_or(1.0, |_| self.since_kernel_s / KERNEL_PERIOD_S);
            self.since_kernel_s = 0.0;
            self.config
                .roughening
                .apply_to(set, &mean, &covariance, &kernel, share, rng);
        }
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
