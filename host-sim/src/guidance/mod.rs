//! Drive guidance on the host: where to drive next (a free heading, or the next road turn of
//! an OpenStreetMap extract's graph) and whether the fix is good enough, from the core's
//! bias-aware planner ([`foxhunt_core::guidance`]); the policies it is measured against; the
//! closed-loop benchmark (`foxhunt bench --scenario guidance`).
//!
//! [`advise`] is the one entry point for live use: give it the bearings so far, the vehicle's
//! position and heading, the fix (if any) and the roads (if an extract was given) and it
//! returns an [`Advice`]: the move (heading and point to drive to; on roads the next turn), the
//! reason ("widen the angle", "get closer", "drive a calibration leg"...) and the stop rule's
//! verdict with what is missing. Without an extract the moves are free headings: the vehicle
//! is assumed able to drive any direction (open terrain), which on a real road network it is
//! not: give `--roads` there.

pub mod across;
pub mod guide;
pub mod reach;

use crate::inputs::roads::RoadGraph;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::guidance::belief::{Belief, Hypotheses, MAX_POINTS, beliefs};
use foxhunt_core::guidance::plan::{
    Cost, Emitter, FreeHeadings, Leg, MAX_EMITTERS, Objective, PlanOptions, Pose, plan_for,
};
use foxhunt_core::guidance::stop::{FixQuality, Reason, StopRule, Verdict, verdict};
use foxhunt_core::model::bearing::wrap;
use foxhunt_core::{Bearing, Error};
use reach::Roads;
use serde::Serialize;
use std::f32::consts::PI;

/// Prior sd of the emitter's position before the bearings cross, metres: it keeps the
/// information proper (a broad "somewhere within 20 km").
pub const POSITION_SD_M: f32 = 2.0e4;
/// Ranges along the averaged bearing scored before there is a fix, metres (even in log range,
/// docs/src/field.md's initialisation).
pub const RANGES_M: [f32; 4] = [1000.0, 2000.0, 4000.0, 8000.0];
/// A fix whose 1-sigma ellipse reaches beyond this share of the range is scored over its
/// spread, not at its centre.
pub const WIDE: f32 = 0.15;

/// The planner aims at this share of the target CEP50: the bound it predicts is the best case,
/// and the claim it serves is the field pipeline's honest ellipse (stretched along the line of
/// sight, and it must hold the truth). Measured in the closed loop: 0.7 of a 100 m goal cuts
/// the mean distance on the road networks by 1-5 % against aiming at the goal itself.
pub const PLAN_TARGET_SHARE: f32 = 0.7;

/// The fix guidance starts from (from [`foxhunt_core::fix::locate::Source`] or an ML fix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixView {
    /// Emitter position, local metres.
    pub position: [f32; 2],
    /// Its covariance, m^2.
    pub covariance: [[f32; 2]; 2],
    /// Residuals consistent with the noise model.
    pub consistent: bool,
    /// Effective number of independent bearings.
    pub effective: f32,
    /// The DF unit's offset contradicted its prior (the fix relaxed it): never good enough.
    pub offset_beyond_prior: bool,
}

/// What guidance is told.
#[derive(Debug, Clone, Copy)]
pub struct Situation<'a> {
    /// The bearings so far (time order).
    pub bearings: &'a [Bearing],
    /// Where the vehicle is, local metres.
    pub vehicle: [f32; 2],
    /// Its heading, radians counter-clockwise from east (`None`: from the last bearings'
    /// positions).
    pub heading: Option<f32>,
    /// The current fix, if any.
    pub fix: Option<FixView>,
    /// The DF unit's offset prior.
    pub prior: BiasPrior,
}

/// Settings of [`advise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuidanceOptions {
    /// The stop rule.
    pub stop: StopRule,
    /// Seconds of driving looked ahead.
    pub horizon_s: f32,
    /// Moves per sequence at most.
    pub depth: usize,
    /// Open terrain: speed, m/s.
    pub speed: f32,
    /// Open terrain: length of a move, metres.
    pub leg_m: f32,
    /// Bearings per second.
    pub rate_hz: f32,
    /// Open terrain: the largest turn between two moves, radians.
    pub max_turn: f32,
}

impl Default for GuidanceOptions {
    fn default() -> Self {
        Self {
            stop: StopRule::default(),
            horizon_s: 60.0,
            depth: 3,
            speed: 15.0,
            leg_m: 300.0,
            rate_hz: 1.0,
            // What the closed-loop benchmark measured: sharper turns than 135 degrees a
            // move spend the horizon on turning back.
            max_turn: 0.75 * PI,
        }
    }
}

impl GuidanceOptions {
    /// The road settings: a longer look-ahead (minutes of driving), more moves.
    pub fn roads() -> Self {
        Self {
            horizon_s: 150.0,
            depth: 8,
            ..Self::default()
        }
    }

    /// The planner's settings at bearing noise `sigma`: aim at [`PLAN_TARGET_SHARE`] of the
    /// stop rule's target, counting metres, over the look-ahead. The live advice and the
    /// benchmark's look-ahead policy both plan with these, so the benchmark measures the
    /// planner users get.
    pub fn plan_options(&self, sigma: f32) -> PlanOptions {
        PlanOptions {
            objective: Objective::Goal {
                target_m: PLAN_TARGET_SHARE * self.stop.target_cep50_m,
                // Metres, as the benchmark measures it: on roads of one speed the same plan
                // as seconds; off a highway onto slower roads it counts the bearings per
                // kilometre.
                cost: Cost::Distance,
            },
            depth: self.depth,
            horizon_s: self.horizon_s,
            rate_hz: self.rate_hz,
            sigma,
            sample_m: 100.0,
        }
    }

    /// The moves of open terrain: 16 headings, one leg each.
    pub fn free_headings(&self) -> FreeHeadings {
        FreeHeadings {
            count: 16,
            leg_m: self.leg_m,
            speed: self.speed,
            max_turn: self.max_turn,
        }
    }
}

/// How the road turns at the next node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TurnKind {
    /// Within 30 degrees of the current heading.
    Straight,
    /// Left (counter-clockwise).
    Left,
    /// Right.
    Right,
    /// Back the way the vehicle came (more than 150 degrees).
    UTurn,
}

/// The next turn on the road graph.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Turn {
    /// Where: the graph node, local metres.
    pub at: [f32; 2],
    /// Its node index.
    pub node: u32,
    /// Which way.
    pub kind: TurnKind,
    /// Change of direction, degrees (positive left).
    pub angle_deg: f32,
}

/// The suggested next move and the stop rule's verdict.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Advice {
    /// Direction to drive, radians counter-clockwise from east.
    pub heading: f32,
    /// The point to drive to, local metres (the end of the first move).
    pub waypoint: [f32; 2],
    /// On roads: the turn onto the first move.
    pub turn: Option<Turn>,
    /// Why.
    pub reason: Reason,
    /// The stop rule at the current fix (`None` without a fix).
    pub verdict: Option<Verdict>,
    /// The planner's predicted CEP50 at its horizon, metres.
    pub predicted_cep50_m: f32,
    /// Seconds until the plan expects the target, if it does within the horizon.
    pub reached_s: Option<f32>,
    /// Whether the move is a road move (false: a free heading).
    pub on_roads: bool,
}

/// A model angle (radians counter-clockwise from east) as an azimuth in [0, 360) degrees
/// clockwise from north, rounded to 0.1 degree (so -0.01 degrees is 0, not 360).
pub fn azimuth_deg(theta: f32) -> f32 {
    let a = ((90.0 - theta.to_degrees()) * 10.0).round() / 10.0;
    a.rem_euclid(360.0) % 360.0
}

fn whole_degrees(azimuth: f32) -> i32 {
    (azimuth.round() as i32).rem_euclid(360)
}

/// The eight-point compass word of an azimuth (degrees clockwise from north).
pub fn compass(azimuth: f32) -> &'static str {
    const POINTS: [&str; 8] = ["N", "NE", "E", "SE", "S", "SW", "W", "NW"];
    let k = (azimuth.rem_euclid(360.0) / 45.0).round() as usize % 8;
    POINTS.get(k).copied().unwrap_or("N")
}

/// The circular mean of the last `n` bearings' angles.
pub fn averaged_bearing(bearings: &[Bearing], n: usize) -> Option<f32> {
    let tail = &bearings[bearings.len().saturating_sub(n)..];
    let (s, c) = tail
        .iter()
        .filter(|b| b.theta.is_finite())
        .fold((0.0f32, 0.0f32), |(s, c), b| {
            (s + b.theta.sin(), c + b.theta.cos())
        });
    (s != 0.0 || c != 0.0).then(|| s.atan2(c))
}

/// The vehicle's heading from the last bearings' positions (10 m moved at least).
pub fn track_heading(bearings: &[Bearing]) -> Option<f32> {
    let last = bearings.last()?.vehicle;
    bearings.iter().rev().find_map(|b| {
        let (dx, dy) = (last[0] - b.vehicle[0], last[1] - b.vehicle[1]);
        (dx.hypot(dy) > 10.0).then(|| dy.atan2(dx))
    })
}

/// The median of the bearings' sigmas (the planner's noise).
pub fn median_sigma(bearings: &[Bearing]) -> Option<f32> {
    let mut s: Vec<f32> = bearings
        .iter()
        .map(|b| b.sigma)
        .filter(|s| *s > 0.0 && s.is_finite())
        .collect();
    if s.is_empty() {
        return None;
    }
    let mid = s.len() / 2;
    let (_, m, _) = s.select_nth_unstable_by(mid, f32::total_cmp);
    Some(*m)
}

/// The hypotheses a plan is scored over, and their beliefs.
pub fn situation_beliefs(s: &Situation<'_>) -> Result<([Belief; MAX_POINTS], usize), Error> {
    let h = match s.fix {
        Some(f) => Hypotheses::spread(f.position, &f.covariance, s.vehicle, WIDE)?,
        None => {
            let theta = averaged_bearing(s.bearings, 10).ok_or(Error::TooFewMeasurements)?;
            Hypotheses::along(s.vehicle, theta, &RANGES_M)?
        }
    };
    let first = Belief::from_bearings(
        *h.points().first().ok_or(Error::TooFewMeasurements)?,
        s.bearings,
        s.prior,
        POSITION_SD_M,
    )?;
    let mut out = [first; MAX_POINTS];
    let n = beliefs(&h, s.bearings, s.prior, POSITION_SD_M, &mut out);
    if n == 0 {
        return Err(Error::DegenerateGeometry);
    }
    Ok((out, n))
}

/// How a leg turns from `heading`.
pub fn turn_kind(heading: f32, leg: &Leg) -> (TurnKind, f32) {
    let d = wrap(leg.heading() - heading);
    let deg = d.to_degrees();
    let kind = if deg.abs() <= 30.0 {
        TurnKind::Straight
    } else if deg.abs() >= 150.0 {
        TurnKind::UTurn
    } else if deg > 0.0 {
        TurnKind::Left
    } else {
        TurnKind::Right
    };
    (kind, deg)
}

/// Where to drive next and whether to stop. Errors name what is missing (no bearing yet, bad
/// settings).
pub fn advise(
    s: &Situation<'_>,
    roads: Option<&RoadGraph>,
    o: &GuidanceOptions,
) -> Result<Advice, String> {
    median_sigma(s.bearings).ok_or("no usable bearing yet")?;
    let verdict = stop_verdict(s, o)?;
    advise_move(std::slice::from_ref(s), verdict, roads, o).map(|(a, _)| a)
}

/// The stop rule at the situation's fix (`None` without a fix).
pub fn stop_verdict(s: &Situation<'_>, o: &GuidanceOptions) -> Result<Option<Verdict>, String> {
    let Some(f) = s.fix else {
        return Ok(None);
    };
    verdict(
        f.position,
        s.bearings,
        s.prior,
        FixQuality {
            consistent: f.consistent,
            effective: f.effective,
            offset_beyond_prior: f.offset_beyond_prior,
        },
        &o.stop,
    )
    .map(Some)
    .map_err(|e| format!("stop rule: {e}"))
}

/// The one move that serves every emitter of `served` (each its own channel's bearings and
/// fix; the vehicle, its heading and the offset prior are the first's), the goal reached when
/// every one's predicted CEP50 is below the target ([`plan_for`]), the first
/// [`MAX_EMITTERS`] that give a belief counted; with `verdict` (the one its reason is read
/// from). An emitter whose bearings give no belief is left out; with none left, the first
/// one's error. Also: which of `served` the move counted (their indices).
pub fn advise_move(
    served: &[Situation<'_>],
    verdict: Option<Verdict>,
    roads: Option<&RoadGraph>,
    o: &GuidanceOptions,
) -> Result<(Advice, Vec<usize>), String> {
    let s = served.first().ok_or("no emitter to advise for")?;
    let mut pooled = Vec::new();
    let mut emitters: Vec<Emitter> = Vec::new();
    let mut counted = Vec::new();
    let mut failed = None;
    for (i, e) in served.iter().enumerate() {
        if emitters.len() == MAX_EMITTERS {
            break;
        }
        let Some(sigma) = median_sigma(e.bearings) else {
            failed.get_or_insert_with(|| "no usable bearing yet".to_string());
            continue;
        };
        match situation_beliefs(e) {
            Ok((b, n)) => {
                pooled.extend_from_slice(b.get(..n).unwrap_or(&[]));
                emitters.push(Emitter {
                    hypotheses: n,
                    sigma,
                });
                counted.push(i);
            }
            Err(err) => {
                failed.get_or_insert_with(|| format!("guidance: {err}"));
            }
        }
    }
    let Some(sigma) = emitters.first().map(|e| e.sigma) else {
        return Err(failed.unwrap_or_else(|| "no usable bearing yet".into()));
    };
    let heading = s
        .heading
        .or_else(|| track_heading(s.bearings))
        .unwrap_or(0.0);
    let options = o.plan_options(sigma);
    // Before a fix the bearings have not crossed: whatever the planner picks, the reason is
    // the angle.
    let reason = verdict.map(|v| v.reason()).unwrap_or(Reason::WidenAngle);
    let on = roads.and_then(|g| reach::join(g, s.vehicle, Some(heading)).map(|at| (g, at)));
    match on {
        Some((g, at)) => {
            let c = plan_for(&pooled, &emitters, at, &Roads(g), options)
                .map_err(|e| format!("guidance: {e}"))?;
            let (kind, angle_deg) = turn_kind(heading, &c.leg);
            let a = Advice {
                heading: c.leg.heading(),
                waypoint: c.leg.to,
                turn: Some(Turn {
                    at: c.leg.from,
                    node: at.node,
                    kind,
                    angle_deg,
                }),
                reason,
                verdict,
                predicted_cep50_m: c.cep50_m,
                reached_s: c.reached_s,
                on_roads: true,
            };
            Ok((a, counted))
        }
        None => {
            let free = o.free_headings();
            let pose = Pose {
                position: s.vehicle,
                heading,
            };
            let c = plan_for(&pooled, &emitters, pose, &free, options)
                .map_err(|e| format!("guidance: {e}"))?;
            let a = Advice {
                heading: c.leg.heading(),
                waypoint: c.leg.to,
                turn: None,
                reason,
                verdict,
                predicted_cep50_m: c.cep50_m,
                reached_s: c.reached_s,
                on_roads: false,
            };
            Ok((a, counted))
        }
    }
}

/// What a verdict says is missing (`precision`, `consistency`, `bearings`, `offset`; without a
/// fix, `fix`).
pub fn missing_names(verdict: Option<&Verdict>) -> Vec<&'static str> {
    verdict
        .map(|v| {
            let m = v.missing;
            [
                (m.precision, "precision"),
                (m.consistency, "consistency"),
                (m.bearings, "bearings"),
                (m.offset, "offset"),
                (m.offset_measurement, "offset-measurement"),
            ]
            .into_iter()
            .filter(|(on, _)| *on)
            .map(|(_, n)| n)
            .collect()
        })
        .unwrap_or_else(|| vec!["fix"])
}

/// The advice as `--json` and the live map carry it (stable field names).
#[derive(Debug, Clone, Serialize)]
pub struct AdviceReport {
    /// Direction to drive, degrees clockwise from north.
    pub heading_deg: f32,
    /// Its eight-point compass word (`N`, `NE`, ... `NW`).
    pub compass: &'static str,
    /// The point to drive to, local metres east and north.
    pub waypoint: [f32; 2],
    /// The next road turn, if on roads.
    pub turn: Option<Turn>,
    /// Why, machine-readable (`widen-angle`, `get-closer`, `calibration-leg`, `more-bearings`,
    /// `check-unit`, `check-offset`, `good-enough`).
    pub reason: &'static str,
    /// Why, in words.
    pub reason_text: String,
    /// The stop rule holds.
    pub good_enough: bool,
    /// What is missing (`precision`, `consistency`, `bearings`, `offset`).
    pub missing: Vec<&'static str>,
    /// Predicted CEP50 from the bias-aware bound at the fix, metres.
    pub bound_cep50_m: Option<f32>,
    /// The same with the offset known, metres.
    pub offset_known_cep50_m: Option<f32>,
    /// The plan's predicted CEP50 at its horizon, metres.
    pub predicted_cep50_m: f32,
    /// Seconds until the plan expects the target, if within its horizon.
    pub reached_s: Option<f32>,
    /// Road move (false: a free heading in open terrain).
    pub on_roads: bool,
}

impl Advice {
    /// The report form.
    pub fn report(&self) -> AdviceReport {
        let missing = missing_names(self.verdict.as_ref());
        let heading_deg = azimuth_deg(self.heading);
        AdviceReport {
            heading_deg,
            compass: compass(heading_deg),
            waypoint: self.waypoint,
            turn: self.turn,
            reason: self.reason.name(),
            reason_text: self.reason.to_string(),
            good_enough: self.verdict.is_some_and(|v| v.good_enough),
            missing,
            bound_cep50_m: self.verdict.map(|v| v.cep50_m),
            offset_known_cep50_m: self.verdict.map(|v| v.offset_known_cep50_m),
            predicted_cep50_m: self.predicted_cep50_m,
            reached_s: self.reached_s,
            on_roads: self.on_roads,
        }
    }

    /// One line for a live update: the move and why.
    pub fn line(&self) -> String {
        self.line_to(None)
    }

    /// [`Advice::line`], naming the point to drive to (`to`, as the caller writes places).
    pub fn line_to(&self, to: Option<&str>) -> String {
        let r = self.report();
        if r.good_enough {
            return "good enough: stop".into();
        }
        format!(
            "{}: {} (missing: {})",
            self.move_to(to),
            r.reason_text,
            r.missing.join(", ")
        )
    }

    /// The move alone in words ("head 45 deg (NE) to ...", or the next junction's turn).
    pub fn move_to(&self, to: Option<&str>) -> String {
        let heading_deg = azimuth_deg(self.heading);
        let to = to.map(|t| format!(" to {t}")).unwrap_or_default();
        match self.turn {
            Some(t) => format!(
                "at the next junction {} ({:+.0} deg), then head {} deg ({}){to}",
                match t.kind {
                    TurnKind::Straight => "go straight",
                    TurnKind::Left => "turn left",
                    TurnKind::Right => "turn right",
                    TurnKind::UTurn => "turn back",
                },
                t.angle_deg,
                whole_degrees(heading_deg),
                compass(heading_deg)
            ),
            None => format!(
                "head {} deg ({}){to}",
                whole_degrees(heading_deg),
                compass(heading_deg)
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_core::model::bearing::predicted;

    #[test]
    fn advice_before_a_fix_crosses_the_line_of_bearing() {
        let e = [0.0f32, 3000.0];
        let sigma = 4.0f32.to_radians();
        let bs: Vec<Bearing> = (0..20)
            .map(|k| {
                let v = [0.0, 15.0 * k as f32];
                Bearing {
                    vehicle: v,
                    theta: predicted(&e, &v),
                    sigma,
                }
            })
            .collect();
        // Driving straight at the emitter: no fix (parallel bearings).
        let s = Situation {
            bearings: &bs,
            vehicle: [0.0, 285.0],
            heading: None,
            fix: None,
            prior: BiasPrior::calibrated(0.0),
        };
        let a = advise(&s, None, &GuidanceOptions::default()).unwrap();
        assert_eq!(a.reason, Reason::WidenAngle);
        // Not straight on: across the line of bearing.
        assert!(a.heading.cos().abs() > 0.3, "{}", a.heading.to_degrees());
        assert!(a.report().missing == vec!["fix"] && !a.line().is_empty());
        assert_eq!(azimuth_deg(PI / 2.0 + 1e-4), 0.0);
        assert_eq!(azimuth_deg(0.0), 90.0);
        assert_eq!(
            [0.0, 22.4, 22.6, 90.0, 180.0, 292.0, 337.6, 359.9].map(compass),
            ["N", "N", "NE", "E", "S", "W", "N", "N"]
        );
        assert!(
            advise(
                &Situation { bearings: &[], ..s },
                None,
                &GuidanceOptions::default()
            )
            .is_err()
        );
    }
}
