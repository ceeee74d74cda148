//! `foxhunt locate` on an emitter that moves says so (docs/src/field.md, "An emitter that
//! moves"), and never on one that stands still.
//!
//! Draft: prints the figures.

use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, NoEmitter};
use foxhunt_sim::runs::field::{Condition, run_locate};
use foxhunt_sim::runs::moving::MovingScenario;
use foxhunt_sim::runs::moving::locate::{Said, locate_runs};

#[test]
fn moving_emitters_are_named() {
    let runs: usize = std::env::var("MOVING_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
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
        let said = locate_runs(&s, runs);
        let moving = said.iter().filter(|x| matches!(x, Said::Moving(_))).count();
        let wrong = said
            .iter()
            .filter(|x| matches!(x, Said::Fix { wrong: true, .. }))
            .count();
        let fixes = said
            .iter()
            .filter(|x| matches!(x, Said::Fix { .. }))
            .count();
        println!("{name}: moving {moving}/{runs} fixes {fixes} wrong {wrong}");
        for x in &said {
            println!("   {x:?}");
        }
    }
}

#[test]
fn still_emitters_are_not_moving() {
    let runs: usize = std::env::var("FIELD_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    for c in Condition::ALL {
        let mut moving = 0;
        let mut ps = Vec::new();
        for run in 0..runs {
            let d = foxhunt_sim::runs::field::simulate(c, run);
            let Ok(r) = run_locate(
                &d,
                &LocateConfig::default(),
                BiasPrior::default(),
                run as u64,
            ) else {
                continue;
            };
            for ch in r.channels() {
                if let ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m)) = ch.outcome {
                    moving += 1;
                    println!("  {} run {run}: moving {m:?}", c.name());
                }
            }
            for e in r.emitters() {
                ps.push(e.motion_p.unwrap_or(f32::NAN));
            }
        }
        ps.retain(|p| p.is_finite());
        ps.sort_by(f32::total_cmp);
        let below = |a: f32| ps.iter().filter(|p| **p < a).count();
        println!(
            "{}: moving {moving}/{runs}, checked {} p<0.05 {} p<0.01 {} lowest p {:?}",
            c.name(),
            ps.len(),
            below(0.05),
            below(0.01),
            &ps[..ps.len().min(3)]
        );
    }
}

#[test]
fn still_networks_are_not_moving() {
    use foxhunt_sim::runs::network::{NetworkCondition, locate_network};
    let runs: usize = std::env::var("NET_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    for c in NetworkCondition::ALL {
        let mut moving = 0;
        let mut ps = Vec::new();
        for run in 0..runs {
            let (_, r) = locate_network(c, run);
            let Some(r) = r else { continue };
            for ch in r.channels() {
                if let ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m)) = ch.outcome {
                    moving += 1;
                    println!("  {} run {run}: moving {m:?}", c.name());
                }
            }
            for e in r.emitters() {
                ps.push(e.motion_p.unwrap_or(f32::NAN));
            }
        }
        ps.retain(|p| p.is_finite());
        ps.sort_by(f32::total_cmp);
        let below = |a: f32| ps.iter().filter(|p| **p < a).count();
        println!(
            "{}: moving {moving}/{runs}, checked {} p<0.05 {} p<0.01 {} lowest p {:?}",
            c.name(),
            ps.len(),
            below(0.05),
            below(0.01),
            &ps[..ps.len().min(3)]
        );
    }
}
