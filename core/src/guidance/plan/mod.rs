//! Scores of candidate moves, and the look-ahead over sequences of them.
//!
//! A move is a [`Leg`]: a stretch of driving from one point to the next, with its duration.
//! Bearings arrive at a fixed rate along it, so a leg adds, at sample points every
//! [`PlanOptions::sample_m`] metres, the information of the bearings taken there
//! ([`Belief::observe`], one rank-one update per sample and hypothesis). Where the vehicle can
//! go next is a [`Reach`]: free headings in open terrain ([`FreeHeadings`]), or the road
//! graph's turns on the host. [`plan`] walks every sequence of moves within a horizon (depth
//! first, the beliefs copied per level, nothing allocated) and returns the first move of the
//! best sequence.
//!
//! Objectives ([`Objective`]), each averaged over the hypothesised emitter positions:
//! - `DOptimal`: ln det P before minus after (the log-volume of the ellipse removed);
//! - `AOptimal`: the relative drop of trace P;
//! - `Goal`: the soonest (in seconds or in metres driven, [`Cost`]) that the predicted CEP50
//!   falls below a target radius, and where no sequence reaches it, the smallest predicted
//!   CEP50 at the horizon. With depth 1 it is greedy; with a horizon of minutes it is the
//!   look-ahead. A goal the bound meets before moving plans D-optimal instead.
//!
//! Several emitters at once ([`plan_for`]): the vehicle drives one way, so one move serves
//! them all. Their hypotheses are not pooled into one average: a geometric mean over every
//! emitter's points would call the goal met while one emitter is still far above the target
//! and another far below. Each emitter's points are averaged alone (its own predicted CEP50,
//! from bearings of its own noise), the goal is met when *every* emitter's is below the target,
//! and short of that a sequence scores the mean over emitters of -ln max(CEP50, target): an
//! emitter already below the target earns nothing more, so the move goes to those still short.
//! The D- and A-optimal scores are the mean over emitters of each emitter's mean. With one
//! emitter every score is [`plan`]'s.
//!
//! Cost: (candidate sequences) x (samples per leg) x (hypotheses) updates of 3 x 3 (about 60
//! flops each), plus the objective (a 2 x 2 eigen-decomposition) per leaf.

mod lookahead;
mod moves;
mod options;
#[cfg(test)]
mod tests;

pub use moves::{FreeHeadings, Leg, Pose, Reach};
pub use options::{Cost, Objective, PlanOptions};

use super::belief::{Belief, MAX_POINTS};
use crate::error::Error;

/// Depth of a look-ahead at most (legs in one sequence).
pub const MAX_DEPTH: usize = 8;
/// Sample points of one leg at most.
pub const MAX_SAMPLES: usize = 16;
/// Emitters one [`plan_for`] serves at most.
pub const MAX_EMITTERS: usize = 4;
/// Beliefs one [`plan_for`] holds at most (every emitter's hypotheses).
pub const MAX_BELIEFS: usize = MAX_EMITTERS * MAX_POINTS;

/// One emitter of a plan for several ([`plan_for`]): how many of the beliefs, in order, are
/// its hypotheses, and the noise of its bearings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emitter {
    /// Its hypotheses' beliefs (> 0), the next ones of the slice.
    pub hypotheses: usize,
    /// Its bearings' noise, radians (> 0).
    pub sigma: f32,
}

/// The chosen first move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice<S> {
    /// The state after the first move.
    pub state: S,
    /// The first move.
    pub leg: Leg,
    /// Its sequence's score (larger is better; comparable only within one plan).
    pub score: f32,
    /// Goal only: seconds from now at which the best sequence reaches the target, if it does.
    pub reached_s: Option<f32>,
    /// The predicted CEP50 at the end of the best sequence, metres (geometric mean over the
    /// hypotheses; for several emitters, the largest of theirs).
    pub cep50_m: f32,
    /// Candidate sequences scored.
    pub sequences: u32,
}

/// The first move of the best sequence from `state`, the beliefs (one per hypothesis, see
/// [`super::belief::beliefs`]; at most [`MAX_POINTS`] count) updated along each.
/// `Err(TooFewMeasurements)` without a belief or a move.
pub fn plan<R: Reach>(
    beliefs: &[Belief],
    state: R::State,
    reach: &R,
    options: PlanOptions,
) -> Result<Choice<R::State>, Error> {
    let beliefs = beliefs.get(..beliefs.len().min(MAX_POINTS)).unwrap_or(&[]);
    let one = [Emitter {
        hypotheses: beliefs.len(),
        sigma: options.sigma,
    }];
    lookahead::search::<R, MAX_POINTS>(beliefs, &one, state, reach, options)
}

/// [`plan`] for several emitters at once (the module doc says how their scores combine):
/// `beliefs` holds every emitter's hypotheses in the order of `emitters` (at most
/// [`MAX_EMITTERS`], [`MAX_BELIEFS`] beliefs in all), each emitter's future bearings of its own
/// noise (`options.sigma` is not used). The choice's `reached_s` is when every emitter's
/// predicted CEP50 is below the target, its `cep50_m` the largest of theirs.
/// `Err(OutOfRange)` when `emitters` do not split `beliefs`.
pub fn plan_for<R: Reach>(
    beliefs: &[Belief],
    emitters: &[Emitter],
    state: R::State,
    reach: &R,
    options: PlanOptions,
) -> Result<Choice<R::State>, Error> {
    lookahead::search::<R, MAX_BELIEFS>(beliefs, emitters, state, reach, options)
}
