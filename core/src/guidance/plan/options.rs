//! What a plan maximises and its settings.

use super::MAX_DEPTH;
use crate::error::{Error, check_finite};

/// What a plan maximises.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Objective {
    /// ln det of the position covariance removed (greedy D-optimal).
    DOptimal,
    /// Share of the trace of the position covariance removed (greedy A-optimal).
    AOptimal,
    /// Reach a predicted CEP50 below `target_m` soonest (the geometric mean over the
    /// hypotheses), else the smallest predicted CEP50 at the end of the sequence.
    Goal {
        /// Target CEP50, metres.
        target_m: f32,
        /// What "soonest" counts.
        cost: Cost,
    },
}

/// What reaching the goal costs: where every road has the same speed the two agree; where
/// they differ (a highway and its side roads) a fast road is cheap in time but gives fewer
/// bearings per kilometre.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Cost {
    /// Seconds of driving (what the driver waits).
    #[default]
    Time,
    /// Metres driven.
    Distance,
}

/// Settings of [`plan`](super::plan).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanOptions {
    /// What to maximise.
    pub objective: Objective,
    /// Legs per sequence at most (1 = greedy; at most [`MAX_DEPTH`]).
    pub depth: usize,
    /// Seconds of driving looked ahead at most (the last leg is cut there).
    pub horizon_s: f32,
    /// Bearings per second.
    pub rate_hz: f32,
    /// Bearing noise, radians ([`plan`](super::plan); [`plan_for`](super::plan_for) takes each
    /// emitter's own).
    pub sigma: f32,
    /// Distance between sample points of a leg, metres.
    pub sample_m: f32,
}

impl PlanOptions {
    /// `Ok` when usable.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[self.horizon_s, self.rate_hz, self.sigma, self.sample_m])?;
        if let Objective::Goal { target_m, .. } = self.objective
            && !(target_m > 0.0 && target_m.is_finite())
        {
            return Err(Error::OutOfRange);
        }
        if (1..=MAX_DEPTH).contains(&self.depth)
            && self.horizon_s > 0.0
            && self.rate_hz > 0.0
            && self.sigma > 0.0
            && self.sample_m > 0.0
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}
