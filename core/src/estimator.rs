//! Every estimator by one name, and the one place that assembles it.
//!
//! An estimator is a base (SIR, GPF, EKF or a batch fix) with a swarm move, a likelihood and
//! settings. [`Method`] names each one; [`Method::spec`] says what it is made of; and
//! [`with_particle_filter`] / [`with_bearing_filter`] build it and hand it to a [`WithFilter`]
//! visitor (each filter is its own Rust type, so a visitor is how one function can build any of
//! them without an allocator). The bench, `foxhunt locate`, the criterion benches, the speed
//! tables and the MCU step-bench image all build their filters here, so a name means the same
//! estimator everywhere. [`with_particles!`](crate::with_particles) dispatches a run-time
//! particle count to the one list of compiled counts, [`PARTICLE_COUNTS`].

use crate::error::Error;
use crate::filter::Filter;
use crate::filter::ekf::BearingEkf;
use crate::filter::gpf::Gpf;
use crate::filter::sir::{Sir, SirConfig};
use crate::fix::{Fix, ml, ple};
use crate::likelihood::{Cauchy, Gaussian, GaussianUniform, Huber, Widened};
use crate::model::Model;
use crate::model::bearing::{Bearing, StaticEmitter};
use crate::resample::{ResamplePolicy, Resampling};
use crate::roughen::Roughening;
use crate::track::imm::ImmEkf;
use crate::track::{Epoch, Mover};
use crate::{Afsa, Firefly, Gsa, ImprovedFirefly, Pso};

/// An estimator's name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Method {
    /// The seeds' SIR: Gaussian likelihood, systematic resampling every step, no roughening,
    /// the scenario's jitter on a static emitter.
    SirSeed,
    /// The tuned SIR: static model, Gaussian likelihood, systematic resampling at ESS < N/2,
    /// shrinkage roughening.
    Sir,
    /// The tuned SIR with a Gaussian + uniform likelihood (5 % outliers): survives wild
    /// bearings.
    SirRobust,
    /// SIR for sharp likelihoods (RSSI): a Cauchy likelihood widened 2x, resampling every step
    /// with shrinkage.
    SirWide,
    /// AFSA-PF (seed 002): the seeds' SIR with an artificial-fish-swarm move every step.
    AfsaPf,
    /// Standard firefly PF (seed 001's comparison): the seeds' SIR with Yang's O(N^2) move.
    FaPf,
    /// Improved firefly PF (seed 001): move toward the best only, resample at ESS < N/2.
    FaPfImp,
    /// Gaussian particle filter (Kotecha and Djuric).
    Gpf,
    /// Particle swarm optimisation inside the GPF.
    PsoGpf,
    /// Gravitational search inside the GPF (seed 003).
    GsaGpf,
    /// Extended Kalman filter on the emitter position (bearings only).
    Ekf,
    /// Pseudo-linear estimator (closed form, biased toward the vehicle).
    Ple,
    /// Bias-compensated pseudo-linear estimator.
    BcPle,
    /// Weighted instrumental variable (Dogancay), three iterations.
    Wiv,
    /// Maximum likelihood, Gaussian loss (Levenberg-Marquardt from the bias-compensated PLE).
    Ml,
    /// Maximum likelihood with a Huber loss (IRLS): wild bearings down-weighted.
    MlHuber,
    /// The field pipeline ([`crate::fix::locate`]): RANSAC start, Tukey then trimmed ML over
    /// position and the DF unit's offset, noise estimated, consistency checked, F-scaled
    /// ellipses, one emitter per channel and other sources.
    MlRobust,
    /// The DF unit's windowed fix ([`crate::fix::window`]), what the firmware runs on every
    /// bearing: the last 120 bearings, Tukey's loss by Levenberg-Marquardt from a pair search,
    /// the noise estimated from the inliers; no offset, one emitter.
    Unit,
}

/// What a filter is built on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Base {
    /// Sampling importance resampling.
    Sir,
    /// Gaussian particle filter.
    Gpf,
    /// Extended Kalman filter (bearing model only).
    Ekf,
    /// A batch fix over all bearings at once (no particles, no steps).
    Batch,
    /// The field pipeline ([`crate::fix::locate`]): emitters per channel, other sources and
    /// consistency, from bearings with their times; it needs working storage lent to it.
    Pipeline,
    /// The windowed fix ([`crate::fix::window`]): bearings one at a time with their times, the
    /// answer the last update's.
    Window,
}

/// The swarm move between prediction and weighting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SwarmMove {
    /// None: the plain filter.
    None,
    /// Artificial fish swarm (seed 002).
    Afsa,
    /// Yang's firefly, every pair (O(N^2)).
    Firefly,
    /// Seed 001's firefly, toward the best only.
    ImprovedFirefly,
    /// Particle swarm.
    Pso,
    /// Gravitational search (seed 003).
    Gsa,
}

/// What an estimator is made of (its likelihood is chosen where it is built,
/// [`with_particle_filter`] and [`batch_fix`]; each [`Method`] variant's doc says which).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spec {
    /// The one name used in the CLI, JSON, the book and tests.
    pub name: &'static str,
    /// Base filter or batch fix.
    pub base: Base,
    /// Swarm move.
    pub swarm: SwarmMove,
    /// Resampling settings (SIR only).
    pub config: SirConfig,
    /// On a static emitter, whether each step adds the scenario's random-walk jitter (the
    /// seeds' construction; the tuned filters use a truly static model).
    pub jitter: bool,
}

/// The seeds' construction: resample every step, no roughening (SIR).
const SEEDS: SirConfig = SirConfig::SEEDS;
/// Tuned: resample at ESS < N/2, shrinkage roughening.
const TUNED: SirConfig = SirConfig::TUNED;
/// Resample at ESS < N/2 without roughening: seed 001's improved FA-PF.
const HALF_ESS: SirConfig = SirConfig {
    resampling: Resampling::Systematic,
    policy: ResamplePolicy::BelowEss(0.5),
    roughening: Roughening::None,
};
/// Every step with shrinkage: the tracking SIR, whose state moves every step anyway.
const EVERY_STEP_SHRINK: SirConfig = SirConfig {
    resampling: Resampling::Systematic,
    policy: ResamplePolicy::Always,
    roughening: Roughening::Shrinkage { scale: 1.0 },
};

/// The outlier share of `sir-robust`'s Gaussian + uniform likelihood.
const ROBUST_EPS: f32 = 0.05;
/// `sir-wide`'s widening of a Cauchy likelihood. Chosen on rssi-sim: a 0.5 dB likelihood is far
/// sharper than 50 particles resolve and starves a Gaussian PF (1.5x: 1.04 m at N = 50, 2x:
/// 1.02 m, none: 1.34 m; a widened Gaussian: 1.16-1.64 m).
const WIDENING: f32 = 2.0;

const fn spec(
    name: &'static str,
    base: Base,
    swarm: SwarmMove,
    config: SirConfig,
    jitter: bool,
) -> Spec {
    Spec {
        name,
        base,
        swarm,
        config,
        jitter,
    }
}

/// Every estimator, in table order ([`Method::spec`] indexes it by the enum's order).
const SPECS: [Spec; 18] = {
    use Base as B;
    use SwarmMove as S;
    [
        spec("sir-seed", B::Sir, S::None, SEEDS, true),
        spec("sir", B::Sir, S::None, TUNED, false),
        spec("sir-robust", B::Sir, S::None, TUNED, false),
        spec("sir-wide", B::Sir, S::None, EVERY_STEP_SHRINK, false),
        spec("afsa-pf", B::Sir, S::Afsa, SEEDS, true),
        spec("fa-pf", B::Sir, S::Firefly, SEEDS, true),
        spec("fa-pf-imp", B::Sir, S::ImprovedFirefly, HALF_ESS, true),
        spec("gpf", B::Gpf, S::None, TUNED, false),
        spec("pso-gpf", B::Gpf, S::Pso, TUNED, false),
        spec("gsa-gpf", B::Gpf, S::Gsa, TUNED, false),
        spec("ekf", B::Ekf, S::None, TUNED, false),
        spec("ple", B::Batch, S::None, TUNED, false),
        spec("bc-ple", B::Batch, S::None, TUNED, false),
        spec("wiv", B::Batch, S::None, TUNED, false),
        spec("ml", B::Batch, S::None, TUNED, false),
        spec("ml-huber", B::Batch, S::None, TUNED, false),
        spec("ml-robust", B::Pipeline, S::None, TUNED, false),
        spec("unit", B::Window, S::None, TUNED, false),
    ]
};

impl Method {
    /// Every method, in table order.
    pub const ALL: [Method; 18] = [
        Method::SirSeed,
        Method::Sir,
        Method::SirRobust,
        Method::SirWide,
        Method::AfsaPf,
        Method::FaPf,
        Method::FaPfImp,
        Method::Gpf,
        Method::PsoGpf,
        Method::GsaGpf,
        Method::Ekf,
        Method::Ple,
        Method::BcPle,
        Method::Wiv,
        Method::Ml,
        Method::MlHuber,
        Method::MlRobust,
        Method::Unit,
    ];

    /// What the method is made of.
    pub const fn spec(self) -> &'static Spec {
        &SPECS[self as usize]
    }

    /// The method's one name.
    pub const fn name(self) -> &'static str {
        self.spec().name
    }

    /// The method called `name`.
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether it carries particles (and so has an N).
    pub const fn uses_particles(self) -> bool {
        matches!(self.spec().base, Base::Sir | Base::Gpf)
    }

    /// Whether it moves its particles with a swarm (and so is compared with the plain filter
    /// at equal cost).
    pub const fn is_swarm(self) -> bool {
        !matches!(self.spec().swarm, SwarmMove::None)
    }

    /// Whether its likelihood or loss down-weights wild bearings (Huber, Gaussian + uniform,
    /// widened Cauchy, the pipeline's and the unit's Tukey): the noise its residuals give is then
    /// estimated
    /// robustly, from the inliers.
    pub const fn robust_loss(self) -> bool {
        matches!(
            self,
            Method::SirRobust | Method::SirWide | Method::MlHuber | Method::MlRobust | Method::Unit
        )
    }

    /// Whether it steps through the bearings one at a time (particle filters and the EKF).
    pub const fn is_sequential(self) -> bool {
        matches!(self.spec().base, Base::Sir | Base::Gpf | Base::Ekf)
    }
}

impl core::fmt::Display for Method {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// What to do with a filter once it is built: each filter is a different type, so the
/// assembly hands it to a visitor.
pub trait WithFilter<const D: usize, Z> {
    /// What the visit returns.
    type Output;
    /// Use the freshly built (not yet initialised) filter.
    fn visit<F: Filter<D, Measurement = Z>>(self, filter: &mut F) -> Self::Output;
}

/// Build particle method `method` with `N` particles on `model` and hand it to `w`. The EKF
/// and the batch fixes are not particle filters: [`Error::Unsupported`].
pub fn with_particle_filter<const N: usize, const D: usize, M, W>(
    method: Method,
    model: M,
    w: W,
) -> Result<W::Output, Error>
where
    M: Model<D> + Copy,
    W: WithFilter<D, M::Measurement>,
{
    let config = method.spec().config;
    let robust = GaussianUniform { eps: ROBUST_EPS };
    let wide = Widened {
        inner: Cauchy,
        factor: WIDENING,
    };
    Ok(match method {
        Method::SirSeed | Method::Sir => {
            w.visit(&mut Sir::<M, _, N, D>::new(model, Gaussian, config))
        }
        Method::SirRobust => w.visit(&mut Sir::<M, _, N, D>::new(model, robust, config)),
        Method::SirWide => w.visit(&mut Sir::<M, _, N, D>::new(model, wide, config)),
        Method::AfsaPf => w.visit(&mut Sir::<M, _, N, D, _>::with_swarm(
            model,
            Gaussian,
            config,
            Afsa::default(),
        )),
        Method::FaPf => w.visit(&mut Sir::<M, _, N, D, _>::with_swarm(
            model,
            Gaussian,
            config,
            Firefly::default(),
        )),
        Method::FaPfImp => w.visit(&mut Sir::<M, _, N, D, _>::with_swarm(
            model,
            Gaussian,
            config,
            ImprovedFirefly::default(),
        )),
        Method::Gpf => w.visit(&mut Gpf::<M, _, N, D>::new(model, Gaussian)),
        Method::PsoGpf => w.visit(&mut Gpf::<M, _, N, D, _>::with_swarm(
            model,
            Gaussian,
            Pso::default(),
        )),
        Method::GsaGpf => w.visit(&mut Gpf::<M, _, N, D, _>::with_swarm(
            model,
            Gaussian,
            Gsa::default(),
        )),
        Method::Ekf
        | Method::Ple
        | Method::BcPle
        | Method::Wiv
        | Method::Ml
        | Method::MlHuber
        | Method::MlRobust
        | Method::Unit => {
            return Err(Error::Unsupported);
        }
    })
}

/// Build sequential method `method` on the static emitter and hand it to `w`: particle
/// methods with `N` particles, the seeds' ones jittered by `jitter_var` (m^2 per step), and
/// the EKF. Batch fixes: [`Error::Unsupported`] (see [`batch_fix`]).
pub fn with_bearing_filter<const N: usize, W>(
    method: Method,
    jitter_var: f32,
    w: W,
) -> Result<W::Output, Error>
where
    W: WithFilter<2, Bearing>,
{
    let process_var = if method.spec().jitter {
        jitter_var
    } else {
        0.0
    };
    match method {
        Method::Ekf => Ok(w.visit(&mut BearingEkf::new(0.0))),
        _ => with_particle_filter::<N, 2, _, W>(method, StaticEmitter { process_var }, w),
    }
}

/// Build sequential method `method` on the moving emitter `model` (state of `D` components,
/// epochs of up to `K` of each measurement: [`crate::track`]) and hand it to `w`: the particle
/// methods with `N` particles, as on a static emitter, each with its own settings and
/// likelihood; `ekf` as the interacting multiple model of a still and a moving EKF
/// ([`crate::track::imm::ImmEkf`]). Batch fixes and the pipeline: [`Error::Unsupported`]
/// (they assume an emitter that stands still).
pub fn with_moving_filter<const N: usize, const D: usize, const K: usize, W>(
    method: Method,
    model: Mover<K>,
    w: W,
) -> Result<W::Output, Error>
where
    W: WithFilter<D, Epoch<K>>,
{
    match method {
        Method::Ekf => Ok(w.visit(&mut ImmEkf::<D, K>::new(model))),
        _ => with_particle_filter::<N, D, _, W>(method, model, w),
    }
}

/// A batch method's fix over all `bearings`; sequential methods and the pipeline (which needs
/// working storage and reports several sources: [`crate::fix::locate::locate`]):
/// [`Error::Unsupported`].
pub fn batch_fix(method: Method, bearings: &[Bearing]) -> Result<Fix, Error> {
    match method {
        Method::Ple => ple::ple(bearings),
        Method::BcPle => ple::bias_compensated_ple(bearings),
        Method::Wiv => ple::wiv(bearings, 3),
        Method::Ml => ml::ml(bearings, None, &Gaussian, ml::MlOptions::default()),
        Method::MlHuber => ml::ml(bearings, None, &Huber::default(), ml::MlOptions::default()),
        _ => Err(Error::Unsupported),
    }
}

/// The particle counts compiled for run-time choice (the core sizes particle arrays at compile
/// time): every dispatch on the host goes through [`with_particles!`](crate::with_particles),
/// which matches exactly these.
pub const PARTICLE_COUNTS: [usize; 10] = [50, 80, 100, 200, 500, 1000, 2000, 5000, 10_000, 100_000];

/// Run `$body` with the const `$n` bound to the run-time particle count `$count` when it is
/// one of [`PARTICLE_COUNTS`]; otherwise evaluate to `Err(Error::Unsupported)`. `$body` must
/// evaluate to a `Result<_, Error>`.
///
/// ```
/// use foxhunt_core::{Error, ParticleSet, with_particles};
/// fn states(count: usize) -> Result<usize, Error> {
///     with_particles!(count, N => Ok(ParticleSet::<N, 2>::new().states.len()))
/// }
/// assert_eq!(states(80), Ok(80));
/// assert_eq!(states(81), Err(Error::Unsupported));
/// ```
#[macro_export]
macro_rules! with_particles {
    ($count:expr, $n:ident => $body:expr) => {
        match $count {
            50 => {
                const $n: usize = 50;
                $body
            }
            80 => {
                const $n: usize = 80;
                $body
            }
            100 => {
                const $n: usize = 100;
                $body
            }
            200 => {
                const $n: usize = 200;
                $body
            }
            500 => {
                const $n: usize = 500;
                $body
            }
            1000 => {
                const $n: usize = 1000;
                $body
            }
            2000 => {
                const $n: usize = 2000;
                $body
            }
            5000 => {
                const $n: usize = 5000;
                $body
            }
            10_000 => {
                const $n: usize = 10_000;
                $body
            }
            100_000 => {
                const $n: usize = 100_000;
                $body
            }
            _ => Err($crate::Error::Unsupported),
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_round_trip() {
        for (i, m) in Method::ALL.iter().enumerate() {
            assert_eq!(*m as usize, i, "ALL follows the enum's order");
            assert_eq!(Method::from_name(m.name()), Some(*m));
            for other in &Method::ALL[i + 1..] {
                assert_ne!(m.name(), other.name());
            }
        }
        assert_eq!(Method::from_name("pf"), None);
    }

    #[test]
    fn the_macro_covers_every_listed_count() {
        for n in PARTICLE_COUNTS {
            let got: Result<usize, Error> = with_particles!(n, K => Ok(K));
            assert_eq!(got, Ok(n));
        }
    }
}
