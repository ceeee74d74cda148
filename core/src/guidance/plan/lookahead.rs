//! The look-ahead: every sequence of moves within the horizon, walked depth first with the
//! beliefs copied per level, each scored by the objective; the best sequence's first move.

use super::super::belief::Belief;
use super::{Choice, Cost, Emitter, Leg, MAX_EMITTERS, MAX_SAMPLES, Objective, PlanOptions, Reach};
use crate::error::Error;

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
pub(super) fn search<R: Reach, const N: usize>(
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
