//! What `foxhunt locate` makes of an emitter that moves (docs/src/field.md, "An emitter that
//! moves"): the field pipeline on every bearing of a moving scenario's run, its stations with
//! the offset prior the capture's stations file states, judged against the path.

use super::MovingScenario;
use crate::estimate::{Priors, pipeline, pool};
use crate::runs::field::THREE_SIGMA_TAIL;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, NoEmitter, Observation, Source};
use rayon::prelude::*;

/// What the pipeline said about one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Said {
    /// "The emitter moves" (the motion check), the early and late spans this far apart, m.
    Moving(f32),
    /// A fix.
    Fix {
        /// Whether its 95 % ellipse holds the emitter's position at some moment of the run.
        held: bool,
        /// Whether the emitter was beyond the ellipse's 3 sigma (the 99.73 % region) all run
        /// long: a confident wrong answer.
        wrong: bool,
        /// The fix's distance to the nearest point of the path, m.
        error: f32,
        /// Its semi-major axis, m.
        major: f32,
        /// The motion check's p-value.
        motion_p: Option<f32>,
    },
    /// A region (open range).
    Region,
    /// No consistent emitter for another reason.
    None(NoEmitter),
    /// The pipeline failed.
    Failed,
}

/// The tail probability of `truth` under a source's ellipse (its own distribution: chi-square,
/// or 2 F(2, dof) with the noise estimated), as the field judge has it.
fn tail(s: &Source, truth: &[f32; 2]) -> f32 {
    let m = mahalanobis(&s.covariance, &s.position, truth).unwrap_or(f32::INFINITY);
    let m2 = f64::from(m * m);
    let t = if s.sigma_estimated {
        let d = f64::from(s.dof);
        (1.0 + m2 / d).powf(-d / 2.0)
    } else {
        (-m2 / 2.0).exp()
    };
    t as f32
}

/// Run `run` of `scenario` through the field pipeline.
pub fn locate_run(scenario: &MovingScenario, run: usize) -> Said {
    let r = scenario.simulate(run);
    let observations: Vec<Observation> = r
        .updates
        .iter()
        .flat_map(|u| u.epoch.bearings().iter().copied())
        .collect();
    let priors = Priors::same(BiasPrior {
        mean: 0.0,
        sd: scenario.offset_sd,
    });
    let Ok(p) = pipeline(&observations, &LocateConfig::default(), &priors, run as u64) else {
        return Said::Failed;
    };
    match p.channels().first().map(|c| c.outcome) {
        Some(ChannelOutcome::Emitter(i)) => {
            let Some(s) = p.emitters().get(i) else {
                return Said::Failed;
            };
            let path = r.truth.iter().map(|t| t.0);
            let best_tail = path.clone().map(|q| tail(s, &q)).fold(0.0f32, f32::max);
            let error = path
                .map(|q| (q[0] - s.position[0]).hypot(q[1] - s.position[1]))
                .fold(f32::INFINITY, f32::min);
            Said::Fix {
                held: best_tail >= 1.0 - s.ellipse.confidence,
                wrong: best_tail < THREE_SIGMA_TAIL,
                error,
                major: s.ellipse.major,
                motion_p: s.motion_p,
            }
        }
        Some(ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m))) => Said::Moving(m.apart_m),
        Some(ChannelOutcome::NoConsistentEmitter(why)) => Said::None(why),
        Some(ChannelOutcome::Region(_)) => Said::Region,
        None => Said::Failed,
    }
}

/// `runs` seeded runs of `scenario`, in parallel.
pub fn locate_runs(scenario: &MovingScenario, runs: usize) -> Vec<Said> {
    pool().install(|| {
        (0..runs)
            .into_par_iter()
            .map(|run| locate_run(scenario, run))
            .collect()
    })
}
