//! Every bearing-only method the bench compares, run on one simulated drive.

use crate::scenario::Scenario;
use foxhunt_core::fix::{init::initial_particles, intersection::MIN_CROSSING, ml, ple};
use foxhunt_core::{
    Afsa, Bearing, BearingEkf, Error, Filter, Firefly, Gaussian, GaussianUniform, Gpf, Huber,
    ImprovedFirefly, NoSwarm, ParticleSet, Resampling, Roughening, Sir, SirConfig, StaticEmitter,
    Swarm,
};
use rand_xorshift::XorShiftRng;

/// A method of the bench.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// The seeds' plain SIR: jitter of the scenario's process variance every step, systematic
    /// resampling every step, no roughening.
    SirSeed,
    /// Well-tuned SIR: static model, systematic resampling at ESS < N/2, shrinkage roughening.
    Sir,
    /// The tuned SIR with a Gaussian + uniform likelihood (5 % outlier share): survives wild
    /// bearings.
    SirRobust,
    /// AFSA-PF (seed 002): the seeds' SIR with an artificial-fish-swarm move every step.
    AfsaPf,
    /// Standard firefly PF (seed 001's comparison): the seeds' SIR with Yang's O(N^2) move.
    FaPf,
    /// Improved firefly PF (seed 001): move toward the best only, resample when ESS < N/2.
    FaPfImproved,
    /// Gaussian particle filter.
    Gpf,
    /// Extended Kalman filter.
    Ekf,
    /// Pseudo-linear estimator.
    Ple,
    /// Bias-compensated PLE.
    BcPle,
    /// Weighted instrumental variable.
    Wiv,
    /// Gaussian maximum likelihood.
    Ml,
    /// Robust (Huber IRLS) maximum likelihood.
    MlHuber,
}

impl Method {
    /// All methods, in table order.
    pub const ALL: [Method; 13] = [
        Method::SirSeed,
        Method::Sir,
        Method::SirRobust,
        Method::AfsaPf,
        Method::FaPf,
        Method::FaPfImproved,
        Method::Gpf,
        Method::Ekf,
        Method::Ple,
        Method::BcPle,
        Method::Wiv,
        Method::Ml,
        Method::MlHuber,
    ];

    /// The methods of a bearing scenario's table: each paper's own comparison, plus the tuned
    /// SIR, the Kalman filter and the batch fixes for context. The O(N^2) standard firefly runs
    /// only where its paper compares it.
    pub fn for_scenario(name: &str) -> Vec<Method> {
        use Method::*;
        match name {
            "aoa-afsa" => vec![
                SirSeed, Sir, SirRobust, AfsaPf, Gpf, Ekf, Ple, BcPle, Wiv, Ml, MlHuber,
            ],
            "aoa-firefly" => vec![SirSeed, Sir, FaPf, FaPfImproved, Gpf, Ekf, Ml],
            "aoa-pf-vs-kf" => vec![SirSeed, Sir, Ekf, Ml],
            "aoa-afsa-wild" => vec![SirSeed, Sir, SirRobust, Gpf, Ekf, Ple, Ml, MlHuber],
            _ => vec![
                SirSeed,
                Sir,
                SirRobust,
                AfsaPf,
                FaPfImproved,
                Gpf,
                Ekf,
                Ple,
                BcPle,
                Wiv,
                Ml,
                MlHuber,
            ],
        }
    }

    /// The name printed in tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::SirSeed => "sir-seed",
            Method::Sir => "sir",
            Method::SirRobust => "sir-robust",
            Method::AfsaPf => "afsa-pf",
            Method::FaPf => "fa-pf",
            Method::FaPfImproved => "fa-pf-imp",
            Method::Gpf => "gpf",
            Method::Ekf => "ekf",
            Method::Ple => "ple",
            Method::BcPle => "bc-ple",
            Method::Wiv => "wiv",
            Method::Ml => "ml",
            Method::MlHuber => "ml-huber",
        }
    }

    /// Whether the method uses particles (and so reports N).
    pub fn uses_particles(self) -> bool {
        matches!(
            self,
            Method::SirSeed
                | Method::Sir
                | Method::SirRobust
                | Method::AfsaPf
                | Method::FaPf
                | Method::FaPfImproved
                | Method::Gpf
        )
    }

    /// Estimate the emitter from one drive's bearings.
    pub fn run(
        self,
        scenario: &Scenario,
        bearings: &[Bearing],
        rng: &mut XorShiftRng,
    ) -> Result<[f32; 2], Error> {
        self.run_counted(scenario, bearings, rng).map(|(p, _)| p)
    }

    /// [`Method::run`] and the likelihood evaluations it spent (0 for batch fixes).
    pub fn run_counted(
        self,
        scenario: &Scenario,
        bearings: &[Bearing],
        rng: &mut XorShiftRng,
    ) -> Result<([f32; 2], u64), Error> {
        let batch = |r: Result<foxhunt_core::Fix, Error>| r.map(|f| (f.position, 0));
        match self {
            Method::Ple => batch(ple::ple(bearings)),
            Method::BcPle => batch(ple::bias_compensated_ple(bearings)),
            Method::Wiv => batch(ple::wiv(bearings, 3)),
            Method::Ml => batch(ml::ml(bearings, None, &Gaussian, Default::default())),
            Method::MlHuber => batch(robust_ml(bearings)),
            _ => with_particles(self, scenario, bearings, rng),
        }
    }
}

/// Robust ML: Huber IRLS started from the bias-compensated PLE. The start is dragged by wild
/// bearings, but Huber's bounded influence pulls the fix back within a few iterations.
fn robust_ml(bearings: &[Bearing]) -> Result<foxhunt_core::Fix, Error> {
    ml::ml(bearings, None, &Huber::default(), Default::default())
}

/// Particle counts the bench can run (the core sizes particle arrays at compile time).
pub const PARTICLE_COUNTS: [usize; 9] = [50, 80, 100, 200, 500, 1000, 2000, 5000, 10000];

fn with_particles(
    method: Method,
    s: &Scenario,
    bearings: &[Bearing],
    rng: &mut XorShiftRng,
) -> Result<([f32; 2], u64), Error> {
    match s.particles {
        50 => sequential::<50>(method, s, bearings, rng),
        80 => sequential::<80>(method, s, bearings, rng),
        100 => sequential::<100>(method, s, bearings, rng),
        200 => sequential::<200>(method, s, bearings, rng),
        500 => sequential::<500>(method, s, bearings, rng),
        1000 => sequential::<1000>(method, s, bearings, rng),
        2000 => sequential::<2000>(method, s, bearings, rng),
        5000 => sequential::<5000>(method, s, bearings, rng),
        10000 => sequential::<10000>(method, s, bearings, rng),
        _ => Err(Error::OutOfRange),
    }
}

fn sequential<const N: usize>(
    method: Method,
    s: &Scenario,
    bearings: &[Bearing],
    rng: &mut XorShiftRng,
) -> Result<([f32; 2], u64), Error> {
    let mut cloud = Box::new(ParticleSet::<N, 2>::new());
    initial_particles(bearings, MIN_CROSSING, &mut cloud, rng)?;
    let seed_config = SirConfig {
        resampling: Resampling::Systematic,
        ess_threshold: 1.0 + 1.0 / N as f32,
        roughening: Roughening::None,
    };
    let seed_model = StaticEmitter {
        process_var: s.process_var,
    };
    let cloud = &cloud.states;
    // The seeds' construction: their jitter and resampling, plus a swarm move.
    let seeds = |config| -> SeedsRun<'_> { (seed_model, config, cloud, bearings) };
    match method {
        Method::SirSeed => seeds_sir::<N, _>(NoSwarm, seeds(seed_config), rng),
        Method::AfsaPf => seeds_sir::<N, _>(Afsa::default(), seeds(seed_config), rng),
        Method::FaPf => seeds_sir::<N, _>(Firefly::default(), seeds(seed_config), rng),
        Method::FaPfImproved => {
            let config = SirConfig {
                ess_threshold: 0.5,
                ..seed_config
            };
            seeds_sir::<N, _>(ImprovedFirefly::default(), seeds(config), rng)
        }
        Method::Sir => {
            let model = StaticEmitter { process_var: 0.0 };
            let f = Sir::<_, _, N, 2>::new(model, Gaussian, SirConfig::default());
            drive(&mut *Box::new(f), cloud, bearings, rng)
        }
        Method::SirRobust => {
            let model = StaticEmitter { process_var: 0.0 };
            let lik = GaussianUniform { eps: 0.05 };
            drive(
                &mut *Box::new(Sir::<_, _, N, 2>::new(model, lik, SirConfig::default())),
                cloud,
                bearings,
                rng,
            )
        }
        Method::Gpf => {
            let model = StaticEmitter { process_var: 0.0 };
            drive(
                &mut *Box::new(Gpf::<_, _, N, 2>::new(model, Gaussian)),
                cloud,
                bearings,
                rng,
            )
        }
        _ => drive(&mut *Box::new(BearingEkf::new(0.0)), cloud, bearings, rng),
    }
}

/// The seeds' model and settings, the cloud and the bearings of one run.
type SeedsRun<'a> = (StaticEmitter, SirConfig, &'a [[f32; 2]], &'a [Bearing]);

/// A seeds-style SIR with `swarm`, driven through one run.
fn seeds_sir<const N: usize, S: Swarm<2>>(
    swarm: S,
    (model, config, cloud, bearings): SeedsRun<'_>,
    rng: &mut XorShiftRng,
) -> Result<([f32; 2], u64), Error> {
    let mut f = Box::new(Sir::<_, _, N, 2, S>::with_swarm(
        model, Gaussian, config, swarm,
    ));
    drive(&mut *f, cloud, bearings, rng)
}

/// Initialise a filter from the cloud and step it through every bearing; rejected bearings are
/// skipped (and would be counted by a caller that reports them).
pub fn drive<F: Filter<2, Measurement = Bearing>>(
    filter: &mut F,
    cloud: &[[f32; 2]],
    bearings: &[Bearing],
    rng: &mut XorShiftRng,
) -> Result<([f32; 2], u64), Error> {
    filter.initialise(cloud, rng)?;
    for b in bearings {
        let _ = filter.step(b, rng);
    }
    let m = filter.estimate().mean;
    if m.iter().all(|v| v.is_finite()) {
        Ok((m, filter.evaluations()))
    } else {
        Err(Error::NonFinite)
    }
}
