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
//!   ([`Cost::Distance`], the benchmark's measure) over a horizon (60 s of free
//!   headings; on roads 150 s, at most 8 segments, of reachable road segments), planned to
//!   [`PLAN_TARGET_SHARE`] of the goal.
//!
//! On a road network every policy but `lookahead` picks the road out of the junction nearest
//! its free heading: the free-heading greedy policies "forced onto roads". `lookahead` scores
//! the reachable road segments themselves.

use super::bench::GOAL_M;
use crate::guidance::reach::{OnRoad, Roads};
use crate::guidance::{
    PLAN_TARGET_SHARE, Situation, averaged_bearing, median_sigma, situation_beliefs,
};
use crate::inputs::roads::RoadGraph;
use foxhunt_core::guidance::plan::{Cost, FreeHeadings, Leg, Objective, PlanOptions, Pose, plan};
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

/// Open terrain: the length of one free move, metres, and the speed, m/s.
pub const OPEN_LEG_M: f32 = 300.0;
/// Open terrain speed, m/s.
pub const OPEN_SPEED: f32 = 15.0;
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
    Leg {
        from,
        to: [
            from[0] + OPEN_LEG_M * heading.cos(),
            from[1] + OPEN_LEG_M * heading.sin(),
        ],
        seconds: OPEN_LEG_M / OPEN_SPEED,
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
    // The core planner over free headings of one leg each: `depth` legs deep, turns up to
    // `max_turn` per leg.
    let planned = |objective: Objective, depth: usize, max_turn: f32| -> Option<f32> {
        let (b, n) = situation_beliefs(s).ok()?;
        let options = PlanOptions {
            objective,
            depth,
            horizon_s: depth as f32 * OPEN_LEG_M / OPEN_SPEED,
            rate_hz: 1.0,
            sigma,
            sample_m: 100.0,
        };
        let free = FreeHeadings {
            count: 16,
            leg_m: OPEN_LEG_M,
            speed: OPEN_SPEED,
            max_turn,
        };
        let pose = Pose {
            position: s.vehicle,
            heading: d.heading,
        };
        plan(&b[..n], pose, &free, options)
            .ok()
            .map(|c| c.leg.heading())
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
        Policy::GreedyD => planned(Objective::DOptimal, 1, PI),
        Policy::GreedyA => planned(Objective::AOptimal, 1, PI),
        Policy::Lookahead => planned(
            Objective::Goal {
                target_m: PLAN_TARGET_SHARE * GOAL_M,
                cost: Cost::Distance,
            },
            3,
            0.75 * PI,
        ),
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
                    let options = PlanOptions {
                        objective: Objective::Goal {
                            target_m: PLAN_TARGET_SHARE * GOAL_M,
                            cost: Cost::Distance,
                        },
                        depth: 8,
                        horizon_s: 150.0,
                        rate_hz: 1.0,
                        sigma,
                        sample_m: 100.0,
                    };
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
