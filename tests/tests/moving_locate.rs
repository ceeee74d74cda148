//! `foxhunt locate` on an emitter that moves says so, and on one that stands still does not
//! (docs/src/field.md, "An emitter that moves"): the field pipeline's motion check on the
//! moving scenarios (a drone crossing a city, seen by four masts, by two cars, or both), the
//! single-vehicle field conditions and the network conditions, over seeded runs.
//!
//! Bars, and why:
//! - Moving far (every scenario but `move-fixed-hover`): "moving" in at least 90 % of the runs
//!   (the product's promise). Measured 100 %: the early and late thirds lie 1.7-4.8 km apart,
//!   tens of sds; a miss would take a still model within noise of a drone's whole path.
//! - No confident wrong fix on any moving scenario: a fix whose ellipse's 3 sigma region
//!   (99.73 %) holds no point of the path. Measured 0.
//! - `move-fixed-hover` stands still: it is a false-alarm run like the field's; reported, and
//!   held to the same bar.
//! - Still emitters (every field and network condition): "moving" in at most 2 % of the runs
//!   (the promise). The check's own level is 0.001 %, so over 100 runs a condition expects
//!   0.001 false alarms: 2 means the check is miscalibrated there.
//!   Measured 0 everywhere; the share of fixes with p < 0.05 (0-9 %) is printed to show the
//!   p-values are about uniform on still emitters, not merely tiny on moving ones.

use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, NoEmitter, Report};
use foxhunt_sim::runs::field::{Condition, run_with, simulate};
use foxhunt_sim::runs::moving::MovingScenario;
use foxhunt_sim::runs::moving::locate::{Said, locate_runs};
use foxhunt_sim::runs::network::{NetworkCondition, locate_network};

/// Runs per moving scenario.
const MOVING_RUNS: usize = 40;
/// Runs per field condition.
const FIELD_RUNS: usize = 100;
/// Runs per network condition.
const NETWORK_RUNS: usize = 50;

#[test]
fn an_emitter_that_moves_is_named_not_fixed() {
    let mut failed = Vec::new();
    for name in [
        "move-fixed-straight",
        "move-fixed-turning",
        "move-fixed-stop-and-go",
        "move-fixed-hover",
        "move-vehicles-turning",
        "move-mixed-stop-and-go",
        "move-mixed-both",
    ] {
        let s = MovingScenario::named(name).expect("scenario");
        let said = locate_runs(&s, MOVING_RUNS);
        let count = |f: fn(&Said) -> bool| said.iter().filter(|x| f(x)).count();
        let moving = count(|x| matches!(x, Said::Moving(_)));
        let fixes = count(|x| matches!(x, Said::Fix { .. }));
        let held = count(|x| matches!(x, Said::Fix { held: true, .. }));
        let wrong = count(|x| matches!(x, Said::Fix { wrong: true, .. }));
        let regions = count(|x| matches!(x, Said::Region));
        let none = count(|x| matches!(x, Said::None(_) | Said::Failed));
        let apart: Vec<f32> = said
            .iter()
            .filter_map(|x| match x {
                Said::Moving(a) => Some(*a),
                _ => None,
            })
            .collect();
        let median_apart = {
            let mut a = apart.clone();
            a.sort_by(f32::total_cmp);
            a.get(a.len() / 2).copied().unwrap_or(f32::NAN)
        };
        println!(
            "{name:<24} runs {MOVING_RUNS}: moving {moving} ({:.0} %, early-late median {:.0} m) \
             fixes {fixes} (held {held}, confident wrong {wrong}) regions {regions} none {none}",
            100.0 * moving as f64 / MOVING_RUNS as f64,
            median_apart
        );
        if wrong > 0 {
            failed.push(format!("{name}: {wrong} confident wrong fixes"));
        }
        if name == "move-fixed-hover" {
            if moving * 50 > MOVING_RUNS {
                failed.push(format!("{name} stands still: moving in {moving} runs"));
            }
        } else if moving * 10 < 9 * MOVING_RUNS {
            failed.push(format!(
                "{name}: moving in {moving} of {MOVING_RUNS} runs only"
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("; "));
}

/// Runs whose report calls a channel's emitter moving, and the motion check's p-values of the
/// fixes.
fn tally<const C: usize, const O: usize>(r: &Report<C, O>, moving: &mut usize, p: &mut Vec<f32>) {
    let mut said = false;
    for ch in r.channels() {
        said |= matches!(
            ch.outcome,
            ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(_))
        );
    }
    *moving += said as usize;
    p.extend(r.emitters().iter().filter_map(|e| e.motion_p));
}

/// One line of the still table, and the bar (2 % of the runs).
fn judge_still(name: &str, runs: usize, moving: usize, p: &[f32], failed: &mut Vec<String>) {
    let below = p.iter().filter(|p| **p < 0.05).count();
    println!(
        "{name:<26} runs {runs:>3}: moving {moving} ({:.1} %); fixes checked {} of which p < 0.05: {below} ({:.1} %)",
        100.0 * moving as f64 / runs as f64,
        p.len(),
        100.0 * below as f64 / p.len().max(1) as f64
    );
    if moving * 50 > runs {
        failed.push(format!("{name}: moving in {moving} of {runs} runs"));
    }
}

#[test]
fn an_emitter_that_stands_still_is_not_called_moving() {
    let mut failed = Vec::new();
    for c in Condition::ALL {
        let (mut moving, mut p) = (0, Vec::new());
        for run in 0..FIELD_RUNS {
            let d = simulate(c, run);
            let config = LocateConfig::default();
            // Each condition as the field bench runs it: with what its stations file states
            // (a direction-dependent error, where a condition has one).
            let priors = c.priors(&d, BiasPrior::default());
            if let Ok(r) = run_with(&d, &config, &priors, run as u64) {
                tally(&r.report, &mut moving, &mut p);
            }
        }
        judge_still(c.name(), FIELD_RUNS, moving, &p, &mut failed);
    }
    for c in NetworkCondition::ALL {
        let (mut moving, mut p) = (0, Vec::new());
        for run in 0..NETWORK_RUNS {
            if let (_, Some(r)) = locate_network(c, run) {
                tally(&r.report, &mut moving, &mut p);
            }
        }
        judge_still(c.name(), NETWORK_RUNS, moving, &p, &mut failed);
    }
    assert!(failed.is_empty(), "{}", failed.join("; "));
}
