//! The driving policies the benchmark compares, each deciding the next move from what a DF
//! vehicle knows (its bearings, its position and heading, the current fix):
//!
//! - `homing`: as the KrakenSDR app navigates: along the averaged bearing (the last 10) for
//!   the first 5 km, then to the fix;
//! - `straight`: keep the heading;
//! - `perpendicular`: across the last bearing, on the side nearer the current heading;
//! - `greedy-d`, `greedy-a`: the free heading (16 directions, 300 m) with the largest one-step
//!   D- or A-optimal gain;
//! - `lookahead`: the core planner's sequence that reaches the target in the fewest metres
//!   ([`foxhunt_core::guidance::plan::Cost::Distance`], the benchmark's measure) over a horizon (60 s of free
//!   headings; on roads 150 s, at most 8 segments, of reachable road segments), planned to
//!   [`crate::guidance::PLAN_TARGET_SHARE`] of the goal.
//!
//! On a road network every policy but `lookahead` picks the road out of the junction nearest
//! its free heading: the free-heading greedy policies "forced onto roads". `lookahead` scores
//! the reachable road segments themselves.

use crate::guidance::reach::{OnRoad, Roads};
use crate::guidance::{
    GuidanceOptions, Situation, averaged_bearing, median_sigma, situation_beliefs,
};
use crate::inputs::roads::RoadGraph;
use foxhunt_core::guidance::plan::{Leg, Objective, Pose, plan};
use foxhunt_core::guidance::stop::StopRule;
use foxhunt_core::model::bearing::wrap;
use std::f32::consts::{FRAC_PI_2, PI};

/// A driving policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Policy {
    /// Along the averaged bearing, then to the fix (the KrakenSDR app).
    Homing,
    /// Straight ahead.
    Straight,
    /// Perpendicular to the last bearing.
    Perpendicular,
    /// Greedy D-optimal free heading.
    GreedyD,
    /// Greedy A-optimal free heading.
    GreedyA,
    /// The look-ahead planner (road-aware on roads).
    Lookahead,
}

impl Policy {
    /// Every policy, in report order.
    pub const ALL: [Policy; 6] = [
        Policy::Homing,
        Policy::Straight,
        Policy::Perpendicular,
        Policy::GreedyD,
        Policy::GreedyA,
        Policy::Lookahead,
    ];

    /// Its name in the report's `method` column.
    pub fn name(&self) -> &'static str {
        match self {
            Policy::Homing => "homing",
            Policy::Straight => "straight",
            Policy::Perpendicular => "perpendicular",
            Policy::GreedyD => "greedy-d",
            Policy::GreedyA => "greedy-a",
            Policy::Lookahead => "lookahead",
        }
    }
}

/// The benchmark's goal: CEP50 below this many metres with the truth inside the ellipse.
pub const GOAL_M: f32 = 100.0;

/// The look-ahead's settings: what `locate` and `serve` advise with (open terrain, or roads),
/// aiming at the benchmark's goal.
pub fn lookahead_options(on_roads: bool) -> GuidanceOptions {
    let base = if on_roads {
        GuidanceOptions::roads()
    } else {
        GuidanceOptions::default()
    };
    GuidanceOptions {
        stop: StopRule {
            target_cep50_m: GOAL_M,
            ..base.stop
        },
        ..base
    }
}
/// Homing follows the averaged bearing this far before it drives to the fix, metres.
pub const HOMING_BEARING_M: f32 = 5000.0;

/// What a policy decides with.
pub struct Decision<'a> {
    /// What the vehicle knows.
    pub situation: Situation<'a>,
    /// Its heading now, radians.
    pub heading: f32,
    /// Distance driven so far, metres.
    pub driven_m: f32,
    /// On roads: where it is on the graph.
    pub on_road: Option<(&'a RoadGraph, OnRoad)>,
}

/// The next move: the leg and, on roads, the graph state at its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// The leg to drive.
    pub leg: Leg,
    /// On roads: the state at its end.
    pub end: Option<OnRoad>,
}

fn free_leg(from: [f32; 2], heading: f32) -> Leg {
    let o = GuidanceOptions::default();
    Leg {
        from,
        to: [
            from[0] + o.leg_m * heading.cos(),
            from[1] + o.leg_m * heading.sin(),
        ],
        seconds: o.leg_m / o.speed,
    }
}

/// The heading a policy wants in open terrain (also what it is forced onto roads with);
/// `None` for the look-ahead on roads, which plans on the graph itself.
fn free_heading(p: Policy, d: &Decision<'_>) -> Option<f32> {
    let s = &d.situation;
    let bearings = s.bearings;
    if bearings.is_empty() {
        return Some(d.heading);
    }
    let sigma = median_sigma(bearings)?;
    // The core planner over free headings: the look-ahead with the settings users get, the
    // greedy policies one leg deep with any turn.
    let planned = |o: &GuidanceOptions, objective: Option<Objective>| -> Option<f32> {
        let (b, n) = situation_beliefs(s).ok()?;
        let mut options = o.plan_options(sigma);
        if let Some(objective) = objective {
            options.objective = objective;
        }
        let pose = Pose {
            position: s.vehicle,
            heading: d.heading,
        };
        plan(&b[..n], pose, &o.free_headings(), options)
            .ok()
            .map(|c| c.leg.heading())
    };
    let open = GuidanceOptions::default();
    let greedy = GuidanceOptions {
        depth: 1,
        horizon_s: open.leg_m / open.speed,
        max_turn: PI,
        ..open
    };
    match p {
        Policy::Homing => {
            let to_fix = s
                .fix
                .filter(|_| d.driven_m >= HOMING_BEARING_M)
                .map(|f| (f.position[1] - s.vehicle[1]).atan2(f.position[0] - s.vehicle[0]));
            to_fix.or_else(|| averaged_bearing(bearings, 10))
        }
        Policy::Straight => Some(d.heading),
        Policy::Perpendicular => {
            let last = bearings.last()?.theta;
            let a = wrap(last + FRAC_PI_2);
            let b = wrap(last - FRAC_PI_2);
            Some(if wrap(a - d.heading).abs() <= wrap(b - d.heading).abs() {
                a
            } else {
                b
            })
        }
        Policy::GreedyD => planned(&greedy, Some(Objective::DOptimal)),
        Policy::GreedyA => planned(&greedy, Some(Objective::AOptimal)),
        Policy::Lookahead => planned(&lookahead_options(false), None),
    }
}

/// The next move of policy `p`.
pub fn decide(p: Policy, d: &Decision<'_>) -> Option<Move> {
    match d.on_road {
        None => {
            let h = free_heading(p, d).unwrap_or(d.heading);
            Some(Move {
                leg: free_leg(d.situation.vehicle, h),
                end: None,
            })
        }
        Some((g, at)) => {
            let roads = Roads(g);
            if p == Policy::Lookahead && !d.situation.bearings.is_empty() {
                let planned = (|| {
                    let sigma = median_sigma(d.situation.bearings)?;
                    let (b, n) = situation_beliefs(&d.situation).ok()?;
                    let options = lookahead_options(true).plan_options(sigma);
                    plan(&b[..n], at, &roads, options).ok()
                })();
                if let Some(c) = planned {
                    return Some(Move {
                        leg: c.leg,
                        end: Some(c.state),
                    });
                }
            }
            let h = free_heading(p, d).unwrap_or(d.heading);
            roads.nearest_heading(&at, h).map(|(end, leg)| Move {
                leg,
                end: Some(end),
            })
        }
    }
}
