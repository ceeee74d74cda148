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

use super::belief::{Belief, MAX_POINTS};
use crate::error::{Error, check_finite};
use core::f32::consts::{PI, TAU};

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

/// A stretch of driving.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Where it starts, metres.
    pub from: [f32; 2],
    /// Where it ends, metres.
    pub to: [f32; 2],
    /// How long it takes, seconds (> 0).
    pub seconds: f32,
}

impl Leg {
    /// Its length, metres.
    pub fn length(&self) -> f32 {
        libm::hypotf(self.to[0] - self.from[0], self.to[1] - self.from[1])
    }

    /// Its direction, radians counter-clockwise from east.
    pub fn heading(&self) -> f32 {
        libm::atan2f(self.to[1] - self.from[1], self.to[0] - self.from[0])
    }

    /// The first `share` (0..1) of it.
    fn part(&self, share: f32) -> Leg {
        Leg {
            from: self.from,
            to: [
                self.from[0] + share * (self.to[0] - self.from[0]),
                self.from[1] + share * (self.to[1] - self.from[1]),
            ],
            seconds: share * self.seconds,
        }
    }
}

/// Where the vehicle can go from a state (a position and heading, a road node and the edge it
/// came by...).
pub trait Reach {
    /// What the planner needs to know to continue from the end of a move.
    type State: Copy;
    /// Call `each` with every move from `state`: the state at its end and the leg.
    fn moves(&self, state: &Self::State, each: &mut dyn FnMut(Self::State, Leg));
}

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

/// Settings of [`plan`].
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
    /// Bearing noise, radians ([`plan`]; [`plan_for`] takes each emitter's own).
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

/// Scores of one sequence, before they are ranked.
#[derive(Debug, Clone, Copy)]
struct Outcome {
    score: f32,
    reached_s: Option<f32>,
    cep50_m: f32,
}

/// The geometric mean of the hypotheses' predicted CEP50.
fn mean_cep(beliefs: &[Belief]) -> f32 {
    let n = beliefs.len().max(1) as f32;
    libm::expf(
        beliefs
            .iter()
            .map(|b| libm::logf(b.cep50().max(1e-3)))
            .sum::<f32>()
            / n,
    )
}

/// Each emitter's beliefs of `beliefs` and its noise (slices that [`check_emitters`] found to
/// fit).
fn groups<'b>(
    beliefs: &'b [Belief],
    emitters: &'b [Emitter],
) -> impl Iterator<Item = (&'b [Belief], f32)> + 'b {
    let mut start = 0;
    emitters.iter().filter_map(move |e| {
        let g = beliefs.get(start..start + e.hypotheses);
        start += e.hypotheses;
        g.map(|g| (g, e.sigma))
    })
}

/// [`groups`], mutably.
fn groups_mut<'b>(
    mut beliefs: &'b mut [Belief],
    emitters: &'b [Emitter],
) -> impl Iterator<Item = (&'b mut [Belief], f32)> + 'b {
    emitters.iter().filter_map(move |e| {
        let rest = core::mem::take(&mut beliefs);
        let (g, tail) = rest.split_at_mut_checked(e.hypotheses)?;
        beliefs = tail;
        Some((g, e.sigma))
    })
}

/// The largest of the emitters' predicted CEP50 (each the geometric mean over its
/// hypotheses); NaN if any is, so that no goal is met on bad numbers.
fn worst_cep(beliefs: &[Belief], emitters: &[Emitter]) -> f32 {
    groups(beliefs, emitters)
        .map(|(g, _)| mean_cep(g))
        .fold(0.0, |m, c| if c > m || c.is_nan() { c } else { m })
}

/// The mean over emitters of `f` of each emitter's beliefs.
fn per_emitter(
    beliefs: &[Belief],
    emitters: &[Emitter],
    mut f: impl FnMut(&[Belief]) -> f32,
) -> f32 {
    let n = emitters.len().max(1) as f32;
    groups(beliefs, emitters).map(|(g, _)| f(g)).sum::<f32>() / n
}

/// What a sequence has cost so far.
#[derive(Debug, Clone, Copy, Default)]
struct Spent {
    seconds: f32,
    metres: f32,
}

impl Spent {
    /// After the first `share` of `leg` too.
    fn after(self, leg: &Leg, share: f32) -> Spent {
        Spent {
            seconds: self.seconds + share * leg.seconds,
            metres: self.metres + share * leg.length(),
        }
    }

    fn cost(&self, cost: Cost) -> f32 {
        match cost {
            Cost::Time => self.seconds,
            Cost::Distance => self.metres,
        }
    }
}

struct Search<'a, R: Reach> {
    reach: &'a R,
    options: PlanOptions,
    emitters: &'a [Emitter],
    start: &'a [Belief],
    best: Option<Choice<R::State>>,
    sequences: u32,
}

impl<R: Reach> Search<'_, R> {
    /// Add a leg's bearings to the beliefs; the share of the leg after which the target was
    /// first met (by every emitter), if it was.
    fn drive(&self, beliefs: &mut [Belief], leg: &Leg) -> Option<f32> {
        let n = libm::ceilf(leg.length() / self.options.sample_m).clamp(1.0, MAX_SAMPLES as f32);
        let count = leg.seconds * self.options.rate_hz / n;
        let target = match self.options.objective {
            Objective::Goal { target_m, .. } => Some(target_m),
            _ => None,
        };
        let mut met = None;
        for i in 0..n as usize {
            let t = (i as f32 + 0.5) / n;
            let at = [
                leg.from[0] + t * (leg.to[0] - leg.from[0]),
                leg.from[1] + t * (leg.to[1] - leg.from[1]),
            ];
            for (g, sigma) in groups_mut(beliefs, self.emitters) {
                for b in g.iter_mut() {
                    b.observe(at, sigma, count);
                }
            }
            if let Some(tm) = target
                && met.is_none()
                && worst_cep(beliefs, self.emitters) < tm
            {
                met = Some((i as f32 + 1.0) / n);
            }
        }
        met
    }

    /// The mean over emitters of each emitter's mean `gain(start, now)` over its hypotheses.
    fn gain(&self, beliefs: &[Belief], gain: impl Fn(&Belief, &Belief) -> f32) -> f32 {
        let start = self.start;
        let mut k = 0;
        per_emitter(beliefs, self.emitters, |g| {
            let a = start.get(k..k + g.len()).unwrap_or(&[]);
            k += g.len();
            a.iter().zip(g).map(|(a, b)| gain(a, b)).sum::<f32>() / g.len().max(1) as f32
        })
    }

    /// `reached`: what the sequence had cost when the target was met, if it was.
    fn outcome(&self, beliefs: &[Belief], reached: Option<Spent>) -> Outcome {
        let emitters = self.emitters;
        let cep50_m = worst_cep(beliefs, emitters);
        let score = match self.options.objective {
            Objective::DOptimal => self.gain(beliefs, |a, b| a.log_det() - b.log_det()),
            Objective::AOptimal => self.gain(beliefs, |a, b| {
                1.0 - b.trace() / a.trace().max(f32::MIN_POSITIVE)
            }),
            // Reaching beats not reaching (scores near 1e6 against below 100); sooner is
            // better. Short of the target, the smaller final CEP50s win, each counted down to
            // the target only; between sequences that reach it at the same sample, the smaller
            // CEP50s too (their weight keeps it under a second).
            Objective::Goal { target_m, cost } => match reached {
                Some(r) => {
                    let info =
                        per_emitter(beliefs, emitters, |g| -libm::logf(mean_cep(g).max(1e-3)));
                    1e6 - r.cost(cost) + 0.05 * info
                }
                None => per_emitter(beliefs, emitters, |g| {
                    -libm::logf(mean_cep(g).max(target_m).max(1e-3))
                }),
            },
        };
        Outcome {
            score,
            reached_s: reached.map(|r| r.seconds),
            cep50_m,
        }
    }

    /// Walk on from `state` with `beliefs` after `spent` and `depth` legs; the best outcome
    /// below.
    fn walk<const N: usize>(
        &mut self,
        state: &R::State,
        beliefs: &[Belief; N],
        len: usize,
        spent: Spent,
        depth: usize,
    ) -> Option<Outcome> {
        let mut best: Option<Outcome> = None;
        let reach = self.reach;
        reach.moves(state, &mut |next, leg| {
            if !(leg.seconds > 0.0) || !leg.seconds.is_finite() || !leg.length().is_finite() {
                return;
            }
            let left = self.options.horizon_s - spent.seconds;
            let cut = leg.seconds > left;
            let whole = leg;
            let leg = if cut {
                leg.part(left / leg.seconds)
            } else {
                leg
            };
            let mut b = *beliefs;
            let met = self
                .drive(&mut b[..len], &leg)
                .map(|share| spent.after(&leg, share));
            let o = if met.is_some() || cut || depth + 1 >= self.options.depth {
                self.sequences += 1;
                self.outcome(&b[..len], met)
            } else {
                match self.walk(&next, &b, len, spent.after(&leg, 1.0), depth + 1) {
                    Some(o) => o,
                    None => {
                        // A dead end: the sequence stops here.
                        self.sequences += 1;
                        self.outcome(&b[..len], None)
                    }
                }
            };
            if depth == 0 {
                let better = self.best.as_ref().is_none_or(|c| o.score > c.score);
                if better && o.score.is_finite() {
                    // The whole first move: the state is at its end, wherever the horizon cut.
                    self.best = Some(Choice {
                        state: next,
                        leg: whole,
                        score: o.score,
                        reached_s: o.reached_s,
                        cep50_m: o.cep50_m,
                        sequences: 0,
                    });
                }
            }
            if best.as_ref().is_none_or(|x| o.score > x.score) && o.score.is_finite() {
                best = Some(o);
            }
        });
        best
    }
}

/// `Ok` when `emitters` split `len` beliefs (held in `capacity`): at least one, at most
/// [`MAX_EMITTERS`], each with a hypothesis and a usable noise, together exactly `len`.
fn check_emitters(emitters: &[Emitter], len: usize, capacity: usize) -> Result<(), Error> {
    if emitters.is_empty() || len == 0 {
        return Err(Error::TooFewMeasurements);
    }
    let total = emitters.iter().map(|e| e.hypotheses).sum::<usize>();
    let usable = emitters
        .iter()
        .all(|e| e.hypotheses > 0 && e.sigma > 0.0 && e.sigma.is_finite());
    if usable && emitters.len() <= MAX_EMITTERS && total == len && len <= capacity {
        Ok(())
    } else {
        Err(Error::OutOfRange)
    }
}

/// The search from `state` over `beliefs` (held in a copy of `N`), split by `emitters`.
fn search<R: Reach, const N: usize>(
    beliefs: &[Belief],
    emitters: &[Emitter],
    state: R::State,
    reach: &R,
    options: PlanOptions,
) -> Result<Choice<R::State>, Error> {
    options.check()?;
    let Some(first) = beliefs.first() else {
        return Err(Error::TooFewMeasurements);
    };
    check_emitters(emitters, beliefs.len(), N)?;
    let len = beliefs.len();
    let mut start = [*first; N];
    start
        .get_mut(..len)
        .ok_or(Error::OutOfRange)?
        .copy_from_slice(beliefs);
    let begun = start.get(..len).ok_or(Error::OutOfRange)?;
    // A goal met before moving ranks every sequence by its first sample alone (the cheapest
    // wins, however little it teaches). The bound can be met while the fix is not yet
    // believed (an emitter near the track: the bound at the point fix is tiny, its honest
    // ellipse is not), so the plan then learns the most instead: D-optimal over the horizon.
    let met_already = matches!(options.objective, Objective::Goal { target_m, .. }
        if worst_cep(begun, emitters) < target_m);
    let searched = if met_already {
        PlanOptions {
            objective: Objective::DOptimal,
            ..options
        }
    } else {
        options
    };
    let mut search = Search {
        reach,
        options: searched,
        emitters,
        start: begun,
        best: None,
        sequences: 0,
    };
    let _ = search.walk(&state, &start, len, Spent::default(), 0);
    let sequences = search.sequences;
    search
        .best
        .map(|c| Choice {
            sequences,
            reached_s: if met_already { Some(0.0) } else { c.reached_s },
            ..c
        })
        .ok_or(Error::TooFewMeasurements)
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
    search::<R, MAX_POINTS>(beliefs, &one, state, reach, options)
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
    search::<R, MAX_BELIEFS>(beliefs, emitters, state, reach, options)
}

/// Free headings in open terrain: legs of a fixed length in `count` evenly spaced directions,
/// those within `max_turn` of the current heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeHeadings {
    /// Directions (at most 64).
    pub count: u32,
    /// Length of a leg, metres.
    pub leg_m: f32,
    /// Speed, m/s.
    pub speed: f32,
    /// Largest turn at the start of a leg, radians (pi: any direction, a U-turn included).
    pub max_turn: f32,
}

/// A free-heading state: where the vehicle is and which way it points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Position, metres.
    pub position: [f32; 2],
    /// Heading, radians counter-clockwise from east.
    pub heading: f32,
}

impl Reach for FreeHeadings {
    type State = Pose;
    fn moves(&self, state: &Pose, each: &mut dyn FnMut(Pose, Leg)) {
        if !(self.speed > 0.0) || !(self.leg_m > 0.0) {
            return;
        }
        let count = self.count.clamp(1, 64);
        for k in 0..count {
            let h = TAU * k as f32 / count as f32;
            let turn = libm::fabsf(crate::model::bearing::wrap(h - state.heading));
            if turn > self.max_turn + 1e-4 {
                continue;
            }
            let to = [
                state.position[0] + self.leg_m * libm::cosf(h),
                state.position[1] + self.leg_m * libm::sinf(h),
            ];
            each(
                Pose {
                    position: to,
                    heading: h,
                },
                Leg {
                    from: state.position,
                    to,
                    seconds: self.leg_m / self.speed,
                },
            );
        }
    }
}

impl Default for FreeHeadings {
    fn default() -> Self {
        Self {
            count: 16,
            leg_m: 300.0,
            speed: 15.0,
            max_turn: PI,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fix::bias::BiasPrior;
    use crate::model::bearing::{Bearing, predicted};

    const DEG: f32 = PI / 180.0;

    /// Bearings from 300 m of road heading east at the origin, emitter 3 km north.
    fn start(prior: BiasPrior) -> Belief {
        let e = [0.0, 3000.0];
        let bs: [Bearing; 20] = core::array::from_fn(|k| {
            let v = [15.0 * k as f32, 0.0];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 4.0 * DEG,
            }
        });
        Belief::from_bearings(e, &bs, prior, 2e4).unwrap()
    }

    fn options(objective: Objective, depth: usize) -> PlanOptions {
        PlanOptions {
            objective,
            depth,
            horizon_s: 20.0 * depth as f32,
            rate_hz: 1.0,
            sigma: 4.0 * DEG,
            sample_m: 100.0,
        }
    }

    fn pose() -> Pose {
        Pose {
            position: [285.0, 0.0],
            heading: 0.0,
        }
    }

    #[test]
    fn greedy_d_crosses_the_line_of_sight_and_closes() {
        // The ellipse's major axis lies along the line of sight (north): D-optimal wants the
        // next line of sight along the minor axis, so it drives across, east or west, and
        // (closer is better) somewhat toward the emitter.
        let b = start(BiasPrior::calibrated(0.0));
        let c = plan(
            &[b],
            pose(),
            &FreeHeadings::default(),
            options(Objective::DOptimal, 1),
        )
        .unwrap();
        let h = c.leg.heading();
        assert!(
            libm::sinf(h) > 0.0 && libm::fabsf(libm::cosf(h)) > 0.3,
            "{}",
            h / DEG
        );
        assert_eq!(c.sequences, 16);
        let a = plan(
            &[b],
            pose(),
            &FreeHeadings::default(),
            options(Objective::AOptimal, 1),
        )
        .unwrap();
        assert!(
            libm::sinf(a.leg.heading()) > 0.0,
            "{}",
            a.leg.heading() / DEG
        );
    }

    #[test]
    fn look_ahead_scores_every_sequence_and_beats_a_poor_move() {
        let b = start(BiasPrior::default());
        let headings = FreeHeadings {
            max_turn: PI / 2.0,
            ..FreeHeadings::default()
        };
        let goal = Objective::Goal {
            target_m: 100.0,
            cost: Cost::Time,
        };
        let c = plan(&[b], pose(), &headings, options(goal, 3)).unwrap();
        // 9 headings within 90 degrees, three levels deep.
        assert_eq!(c.sequences, 9 * 9 * 9);
        // Driving away from the emitter (south) is never the best first move.
        assert!(
            libm::sinf(c.leg.heading()) > -0.1,
            "{}",
            c.leg.heading() / DEG
        );
        // The chosen sequence predicts a CEP50 below what straight-on driving gives.
        let mut straight = b;
        for k in 0..60 {
            straight.observe([285.0 + 15.0 * k as f32, 0.0], 4.0 * DEG, 1.0);
        }
        assert!(
            c.cep50_m < straight.cep50(),
            "{} {}",
            c.cep50_m,
            straight.cep50()
        );
    }

    /// The same road east twice: a fast one and a slow one (twice the bearings per metre).
    struct FastOrSlow;

    impl Reach for FastOrSlow {
        type State = bool;
        fn moves(&self, _: &bool, each: &mut dyn FnMut(bool, Leg)) {
            for (fast, speed) in [(true, 30.0), (false, 10.0)] {
                let leg = Leg {
                    from: [285.0, 0.0],
                    to: [3285.0, 0.0],
                    seconds: 3000.0 / speed,
                };
                each(fast, leg);
            }
        }
    }

    #[test]
    fn the_goal_costs_seconds_or_metres() {
        let b = start(BiasPrior::calibrated(0.0));
        let at = |cost: Cost| {
            let goal = Objective::Goal {
                target_m: 150.0,
                cost,
            };
            let o = PlanOptions {
                horizon_s: 300.0,
                ..options(goal, 1)
            };
            plan(&[b], true, &FastOrSlow, o).unwrap()
        };
        let (time, distance) = (at(Cost::Time), at(Cost::Distance));
        // Sooner in seconds: the fast road (more angle per second); sooner in metres: the slow
        // one (more bearings per metre). Both reach the target within their leg.
        assert!(time.state, "{time:?}");
        assert!(!distance.state, "{distance:?}");
        assert!(time.reached_s.is_some() && distance.reached_s.is_some());
    }

    #[test]
    fn a_goal_met_before_moving_plans_for_information() {
        let b = start(BiasPrior::calibrated(0.0));
        let goal = Objective::Goal {
            target_m: 1e5,
            cost: Cost::Distance,
        };
        let c = plan(&[b], pose(), &FreeHeadings::default(), options(goal, 1)).unwrap();
        let d = plan(
            &[b],
            pose(),
            &FreeHeadings::default(),
            options(Objective::DOptimal, 1),
        )
        .unwrap();
        // Not the cheapest first sample (any heading would do) but the most informative move.
        assert_eq!(c.leg, d.leg);
        assert_eq!(c.reached_s, Some(0.0));
    }

    #[test]
    fn bad_settings_and_no_moves_are_errors() {
        let b = start(BiasPrior::default());
        let mut o = options(Objective::DOptimal, 0);
        assert_eq!(
            plan(&[b], pose(), &FreeHeadings::default(), o).map(|_| ()),
            Err(Error::OutOfRange)
        );
        o.depth = 1;
        o.sigma = f32::NAN;
        assert_eq!(
            plan(&[b], pose(), &FreeHeadings::default(), o).map(|_| ()),
            Err(Error::NonFinite)
        );
        let none = FreeHeadings {
            speed: 0.0,
            ..FreeHeadings::default()
        };
        assert_eq!(
            plan(&[b], pose(), &none, options(Objective::DOptimal, 1)).map(|_| ()),
            Err(Error::TooFewMeasurements)
        );
        assert_eq!(
            plan(
                &[],
                pose(),
                &FreeHeadings::default(),
                options(Objective::DOptimal, 1)
            )
            .map(|_| ()),
            Err(Error::TooFewMeasurements)
        );
    }

    /// A belief well resolved: the start's emitter after bearings from all round it.
    fn resolved() -> Belief {
        let mut b = start(BiasPrior::calibrated(0.0));
        for k in 0..36 {
            let a = 10.0 * k as f32 * DEG;
            b.observe(
                [500.0 * libm::cosf(a), 3000.0 + 500.0 * libm::sinf(a)],
                4.0 * DEG,
                10.0,
            );
        }
        b
    }

    #[test]
    fn one_emitter_plans_as_plan_does() {
        let b = start(BiasPrior::default());
        for objective in [
            Objective::DOptimal,
            Objective::AOptimal,
            Objective::Goal {
                target_m: 100.0,
                cost: Cost::Time,
            },
        ] {
            let o = options(objective, 2);
            let one = [Emitter {
                hypotheses: 1,
                sigma: o.sigma,
            }];
            let p = plan(&[b], pose(), &FreeHeadings::default(), o).unwrap();
            let q = plan_for(&[b], &one, pose(), &FreeHeadings::default(), o).unwrap();
            assert_eq!(p, q);
        }
    }

    #[test]
    fn several_emitters_reach_the_goal_only_together() {
        let tight = resolved();
        let wide = start(BiasPrior::default());
        assert!(
            tight.cep50() < 30.0 && wide.cep50() > 300.0,
            "{} {}",
            tight.cep50(),
            wide.cep50()
        );
        let goal = options(
            Objective::Goal {
                target_m: 100.0,
                cost: Cost::Time,
            },
            1,
        );
        // Pooled as one emitter's hypotheses, the geometric mean is below the target at the
        // first sample (a third of the 20 s leg): the goal "met" while the wide emitter is
        // several times the target.
        let pooled = plan(&[tight, wide], pose(), &FreeHeadings::default(), goal).unwrap();
        assert!(
            pooled.reached_s.is_some_and(|t| t < 7.0) && pooled.cep50_m < 100.0,
            "{pooled:?}"
        );
        let two = [
            Emitter {
                hypotheses: 1,
                sigma: goal.sigma,
            },
            Emitter {
                hypotheses: 1,
                sigma: goal.sigma,
            },
        ];
        let c = plan_for(&[tight, wide], &two, pose(), &FreeHeadings::default(), goal).unwrap();
        assert!(c.reached_s.is_none(), "{c:?}");
        assert!(c.cep50_m > 100.0, "the worst emitter's CEP50: {c:?}");
        // The resolved emitter earns nothing more: the move is the wide one's own.
        let alone = plan(&[wide], pose(), &FreeHeadings::default(), goal).unwrap();
        assert_eq!(c.leg, alone.leg, "{c:?} {alone:?}");
        assert!((c.cep50_m - alone.cep50_m).abs() < 1e-3 * alone.cep50_m);
    }

    #[test]
    fn emitters_that_do_not_split_the_beliefs_are_refused() {
        let b = start(BiasPrior::default());
        let o = options(Objective::DOptimal, 1);
        let e = |hypotheses: usize, sigma: f32| Emitter { hypotheses, sigma };
        let free = FreeHeadings::default();
        for emitters in [
            &[e(2, o.sigma)][..],
            &[e(1, o.sigma), e(0, o.sigma)][..],
            &[e(1, f32::NAN)][..],
            &[e(1, 0.0)][..],
        ] {
            assert_eq!(
                plan_for(&[b], emitters, pose(), &free, o).map(|_| ()),
                Err(Error::OutOfRange),
                "{emitters:?}"
            );
        }
        let many = [b; MAX_EMITTERS + 1];
        let each = [e(1, o.sigma); MAX_EMITTERS + 1];
        assert_eq!(
            plan_for(&many, &each, pose(), &free, o).map(|_| ()),
            Err(Error::OutOfRange)
        );
        assert!(
            plan_for(
                &many[..MAX_EMITTERS],
                &each[..MAX_EMITTERS],
                pose(),
                &free,
                o
            )
            .is_ok()
        );
        assert_eq!(
            plan_for(&[], &[], pose(), &free, o).map(|_| ()),
            Err(Error::TooFewMeasurements)
        );
    }
}
