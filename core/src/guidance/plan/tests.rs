//! Greedy and look-ahead plans, the goal's costs, several emitters, bad settings.

use super::*;
use crate::fix::bias::BiasPrior;
use crate::model::bearing::{Bearing, predicted};
use core::f32::consts::PI;

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
