//! Sampling importance resampling, the bootstrap particle filter (Gordon 1993; seed 004, and
//! the baseline of seeds 001-003). Cost O(N) per step: one propagation and one likelihood per
//! particle, one normalisation, an O(N) resampling when the ESS falls below the threshold.

use super::{Estimate, Filter, StepStatus, moments, scaled};
use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::particles::ParticleSet;
use crate::resample::Resampling;
use crate::roughen::Roughening;
use crate::swarm::{NoSwarm, Swarm};
use rand_core::Rng;

/// SIR settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SirConfig {
    /// Resampling scheme.
    pub resampling: Resampling,
    /// Resample when ESS < threshold * N; 1.0 resamples every step.
    pub ess_threshold: f32,
    /// Jitter after resampling.
    pub roughening: Roughening,
}

impl Default for SirConfig {
    /// Systematic resampling at ESS < N/2 with shrinkage roughening: the well-tuned plain
    /// filter every fancier one must beat.
    fn default() -> Self {
        Self {
            resampling: Resampling::Systematic,
            ess_threshold: 0.5,
            roughening: Roughening::Shrinkage { scale: 1.0 },
        }
    }
}

impl SirConfig {
    /// `Ok` when the threshold and the roughening parameter are usable numbers.
    pub fn check(&self) -> Result<(), Error> {
        let p = match self.roughening {
            Roughening::None => 0.0,
            Roughening::Gordon { k } => k,
            Roughening::Shrinkage { scale } => scale,
        };
        if self.ess_threshold.is_finite() && p.is_finite() && p >= 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// The bootstrap particle filter over model `M`, likelihood `L`, `N` particles of dimension `D`.
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
    particles: ParticleSet<N, D>,
    evaluations: u64,
    prior: Option<([f32; D], [[f32; D]; D])>,
    last: Estimate<D>,
}

/// Variance inflation of the prior when the filter must restart from it.
const RESTART_INFLATION: f32 = 4.0;

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize> Sir<M, L, N, D> {
    /// A plain SIR filter awaiting [`Filter::initialise`].
    pub fn new(model: M, likelihood: L, config: SirConfig) -> Self {
        Self::with_swarm(model, likelihood, config, NoSwarm)
    }
}

impl<M: Model<D>, L: Likelihood, const N: usize, const D: usize, S: Swarm<D>> Sir<M, L, N, D, S> {
    /// A swarm-optimised SIR filter (AFSA-PF, FA-PF...) awaiting [`Filter::initialise`].
    pub fn with_swarm(model: M, likelihood: L, config: SirConfig, swarm: S) -> Self {
        Self {
            model,
            likelihood,
            config,
            swarm,
            evaluations: 0,
            particles: ParticleSet::new(),
            prior: None,
            last: Estimate {
                mean: [0.0; D],
                covariance: [[0.0; D]; D],
                ess: 0.0,
                status: StepStatus::Updated,
            },
        }
    }

    /// The particles, for plots and diagnostics.
    pub fn particles(&self) -> &ParticleSet<N, D> {
        &self.particles
    }

    /// Mutable particles: the swarm optimisers move them between weighting and resampling.
    pub fn particles_mut(&mut self) -> &mut ParticleSet<N, D> {
        &mut self.particles
    }

    fn restart<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Result<Estimate<D>, Error> {
        let (mean, cov) = self.prior.ok_or(Error::NotInitialised)?;
        let wide = scaled(&cov, RESTART_INFLATION);
        self.particles.draw_gaussian(&mean, &wide, rng)?;
        self.last = Estimate {
            mean,
            covariance: wide,
            ess: N as f32,
            status: StepStatus::Reinitialised,
        };
        Ok(self.last)
    }

    /// Weight, normalise, estimate, resample and roughen: the half of a step after the particles
    /// have moved. Swarm-optimised variants call this after their own move.
    pub fn update<R: Rng + ?Sized>(
        &mut self,
        z: &M::Measurement,
        rng: &mut R,
    ) -> Result<Estimate<D>, Error> {
        self.model.add_ln_likelihoods(
            &self.particles.states,
            z,
            &self.likelihood,
            &mut self.particles.log_weights,
        );
        self.evaluations += N as u64;
        let ess = match self.particles.normalise() {
            Ok(ess) => ess,
            Err(Error::WeightCollapse) => return self.restart(rng),
            Err(e) => return Err(e),
        };
        let mean = self.particles.mean();
        let covariance = self.particles.covariance(&mean);
        if !super::all_finite(&mean, &covariance) {
            return self.restart(rng);
        }
        if ess < self.config.ess_threshold * N as f32 {
            self.particles.resample(self.config.resampling, rng);
            self.config
                .roughening
                .apply(&mut self.particles, &mean, &covariance, rng);
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
    for Sir<M, L, N, D, S>
{
    type Measurement = M::Measurement;

    fn initialise<R: Rng + ?Sized>(
        &mut self,
        cloud: &[[f32; D]],
        _rng: &mut R,
    ) -> Result<(), Error> {
        let prior = moments(cloud)?;
        for (i, x) in self.particles.states.iter_mut().enumerate() {
            *x = cloud[i % cloud.len()];
        }
        self.particles.set_uniform_weights();
        self.prior = Some(prior);
        self.last = Estimate {
            mean: prior.0,
            covariance: prior.1,
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
        self.config.check()?;
        self.model.check(z)?;
        self.model.propagate_all(&mut self.particles.states, z, rng);
        if S::MOVES {
            let fitness = self.model.fitness(z, &self.likelihood);
            let spent = self.swarm.optimise(&mut self.particles, fitness, rng);
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
