//! One closed-loop run: the vehicle drives by a policy, the DF unit gives a bearing a second,
//! the fix is refitted every few seconds until it is good enough or the run gives up.

use super::{FIX_EVERY_S, MAX_DISTANCE_M, MAX_TIME_S, OFFSET, RunResult, Set};
use crate::estimate::Priors;
use crate::guidance::reach::OnRoad;
use crate::guidance::{FixView, Situation};
use crate::inputs::roads::RoadGraph;
use crate::runs::guidance::networks::{HALF_M, Network};
use crate::runs::guidance::policy::{Decision, GOAL_M, Move, Policy, decide};
use foxhunt_core::fix::bias::{self, BiasPrior, BiasedFix, StationSlot};
use foxhunt_core::fix::ellipse::cep50;
use foxhunt_core::fix::locate::{LocateConfig, NoiseModel, Observation, Source};
use foxhunt_core::guidance::stop::{FixQuality, Limit, Reason, StopRule, verdict};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::{Gaussian, random};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use std::f32::consts::PI;

/// The seeded generator of run `run` of a set (the same start, emitter and noise for every
/// policy).
fn run_rng(set: Set, run: usize, seed: u64) -> XorShiftRng {
    let salt = Network::ALL
        .iter()
        .position(|n| *n == set.network)
        .unwrap_or(0) as u64
        + if set.offset { 8 } else { 0 };
    XorShiftRng::seed_from_u64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(salt << 32)
            .wrapping_add(run as u64),
    )
}

/// Where a run starts and where its emitter is.
struct Start {
    position: [f32; 2],
    heading: f32,
    on_road: Option<OnRoad>,
    emitter: [f32; 2],
    sigma: f32,
    offset: f32,
}

fn start(set: Set, g: Option<&RoadGraph>, rng: &mut XorShiftRng) -> Start {
    let inner = HALF_M - 4000.0;
    loop {
        let mut p = [
            random::uniform_in(rng, -inner, inner),
            random::uniform_in(rng, -inner, inner),
        ];
        if set.network == Network::Highway {
            // On the highway itself.
            p[1] = 0.0;
        }
        let (position, on_road) = match g {
            None => (p, None),
            Some(g) => match g.nearest(p).and_then(|n| Some((n, g.position(n)?))) {
                Some((n, q)) => (
                    q,
                    Some(OnRoad {
                        node: n,
                        from: None,
                    }),
                ),
                None => continue,
            },
        };
        let r = random::uniform_in(rng, 3000.0, 5000.0);
        let a = random::uniform_in(rng, -PI, PI);
        let emitter = [position[0] + r * a.cos(), position[1] + r * a.sin()];
        let inside = emitter.iter().all(|v| v.abs() < HALF_M - 1000.0);
        // Across the river from the start: the bridges are what the network is about.
        let across = set.network != Network::River || (emitter[0] < 0.0) != (position[0] < 0.0);
        if inside && across {
            return finish_start(set, position, on_road, emitter, rng);
        }
    }
}

fn finish_start(
    set: Set,
    position: [f32; 2],
    on_road: Option<OnRoad>,
    emitter: [f32; 2],
    rng: &mut XorShiftRng,
) -> Start {
    let heading = random::uniform_in(rng, -PI, PI);
    let sigma = random::uniform_in(rng, 3.0, 5.0).to_radians();
    let sign = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
    Start {
        position,
        heading,
        on_road,
        emitter,
        sigma,
        offset: if set.offset { sign * OFFSET } else { 0.0 },
    }
}

/// The fix of `bearings`, started from the last one.
fn fix(bearings: &[Bearing], prior: BiasPrior, last: Option<&BiasedFix>) -> Option<BiasedFix> {
    let options = bias::BiasedOptions::default();
    let warm = last.and_then(|f| {
        bias::ml_sources(
            bearings,
            &mut [StationSlot::new(prior)],
            bias::Start {
                position: f.position,
                offsets: bias::StartOffsets::Common(f.bias),
            },
            &Gaussian,
            options,
        )
        .ok()
    });
    let f = warm.or_else(|| bias::ml(bearings, prior, None, &Gaussian, options).ok())?;
    // A fix tens of kilometres out is the solver lost in a shallow crossing, not a fix.
    let near = bearings
        .last()
        .map(|b| (f.position[0] - b.vehicle[0]).hypot(f.position[1] - b.vehicle[1]) < 50_000.0);
    near.unwrap_or(false).then_some(f)
}

/// The field pipeline's emitter ([`foxhunt_core::fix::locate::locate`], the unit's sigmas
/// trusted and checked) of `bearings`.
fn honest(bearings: &[Bearing], prior: BiasPrior) -> Option<Source> {
    let obs: Vec<Observation> = bearings
        .iter()
        .enumerate()
        .map(|(k, b)| Observation::new(*b, k as f32))
        .collect();
    let config = LocateConfig {
        noise: NoiseModel::Known,
        ..LocateConfig::default()
    };
    let seed = obs.len() as u64;
    let r = crate::estimate::pipeline(&obs, &config, &Priors::same(prior), seed).ok()?;
    r.emitters().first().copied()
}

/// The fix as guidance sees it.
fn view(f: &BiasedFix) -> FixView {
    let dof = (f.used as f32 - f.parameters).max(1.0);
    let p = foxhunt_core::stats::chi2_sf(f.chi2, dof).unwrap_or(0.0);
    FixView {
        position: f.position,
        covariance: f.covariance,
        consistent: p > 1e-3,
        effective: f.used as f32,
        offset_beyond_prior: false,
    }
}

/// One closed-loop run of `policy` on `set`.
pub fn run(set: Set, policy: Policy, g: Option<&RoadGraph>, run: usize, seed: u64) -> RunResult {
    let mut rng = run_rng(set, run, seed);
    let s = start(set, g, &mut rng);
    let prior = if set.offset {
        BiasPrior::default()
    } else {
        BiasPrior::calibrated(0.0)
    };
    let rule = StopRule {
        target_cep50_m: GOAL_M,
        ..StopRule::default()
    };
    let mut noise = XorShiftRng::seed_from_u64(rng.next_u64());
    let mut pos = s.position;
    let mut heading = s.heading;
    let mut on_road = s.on_road;
    let mut leg: Option<(Move, f32)> = None; // the move and the seconds driven on it
    // The unit's first bearing is in before the vehicle moves off: the first move is a
    // decision too (at a highway exit it is two kilometres of driving).
    // What the unit reports at `at`: the true bearing, its offset and noise.
    let mut observe = |at: [f32; 2]| Bearing {
        vehicle: at,
        theta: wrap(predicted(&s.emitter, &at) + s.offset + s.sigma * random::normal(&mut noise)),
        sigma: s.sigma,
    };
    let mut bearings: Vec<Bearing> = vec![observe(pos)];
    let mut last_fix: Option<BiasedFix> = None;
    let mut out = RunResult {
        distance_m: None,
        time_s: None,
        wrong: false,
        cep50_2km_m: None,
        final_inside: None,
        offset_limited: 0,
        decisions: 0,
        curve: Vec::new(),
    };
    let mut driven = 0.0f32;
    let mut two_km_done = false;
    let mut t = 0u32;
    while (t as f32) < MAX_TIME_S && driven < MAX_DISTANCE_M {
        // One second of driving, across as many legs as it takes.
        let mut left = 1.0f32;
        let mut guard = 0;
        while left > 1e-4 && guard < 8 {
            guard += 1;
            if leg.is_none() {
                let situation = Situation {
                    bearings: &bearings,
                    vehicle: pos,
                    heading: Some(heading),
                    fix: last_fix.as_ref().map(view),
                    prior,
                };
                if let Some(f) = situation.fix {
                    out.decisions += 1;
                    let q = FixQuality {
                        consistent: f.consistent,
                        effective: f.effective,
                        offset_beyond_prior: f.offset_beyond_prior,
                    };
                    if let Ok(v) = verdict(f.position, &bearings, prior, q, &rule)
                        && v.limit == Limit::Offset
                        && v.reason() == Reason::CalibrationLeg
                    {
                        out.offset_limited += 1;
                    }
                }
                let d = Decision {
                    situation,
                    heading,
                    driven_m: driven,
                    on_road: g.zip(on_road),
                };
                match decide(policy, &d) {
                    Some(m) => leg = Some((m, 0.0)),
                    None => break,
                }
            }
            let Some((m, done)) = leg.as_mut() else {
                break;
            };
            let remaining = m.leg.seconds - *done;
            let step = remaining.min(left);
            *done += step;
            left -= step;
            let share = (*done / m.leg.seconds).clamp(0.0, 1.0);
            let next = [
                m.leg.from[0] + share * (m.leg.to[0] - m.leg.from[0]),
                m.leg.from[1] + share * (m.leg.to[1] - m.leg.from[1]),
            ];
            driven += (next[0] - pos[0]).hypot(next[1] - pos[1]);
            pos = next;
            heading = m.leg.heading();
            if *done >= m.leg.seconds - 1e-4 {
                if let Some(end) = m.end {
                    on_road = Some(end);
                }
                leg = None;
            }
        }
        t += 1;
        bearings.push(observe(pos));
        if !t.is_multiple_of(FIX_EVERY_S) {
            continue;
        }
        last_fix = fix(&bearings, prior, last_fix.as_ref());
        let Some(f) = last_fix.as_ref() else {
            continue;
        };
        let Ok(c) = cep50(&f.covariance) else {
            continue;
        };
        out.curve.push((driven, c));
        if !two_km_done && driven >= 2000.0 {
            two_km_done = true;
            out.cep50_2km_m = Some(c);
        }
        if c < GOAL_M {
            // The claim is the field pipeline's, as `foxhunt locate` would make it: robust,
            // with the honest ellipse (the ML alone can settle on a point on the track when
            // the bearings run nearly parallel).
            let Some(h) = honest(&bearings, prior) else {
                continue;
            };
            if !(h.cep50 < GOAL_M) {
                continue;
            }
            let inside = h.ellipse.contains(&h.position, &s.emitter);
            if inside {
                out.distance_m = Some(driven);
                out.time_s = Some(t as f32);
                break;
            }
            // A confident wrong answer: counted, and the drive goes on.
            out.wrong = true;
        }
    }
    out.final_inside =
        honest(&bearings, prior).map(|h| h.ellipse.contains(&h.position, &s.emitter));
    out
}
