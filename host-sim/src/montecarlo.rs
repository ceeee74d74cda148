//! Seeded, parallel Monte Carlo runs and the metrics of SCENARIOS.md.

use crate::methods::Method;
use crate::scenario::Scenario;
use foxhunt_core::fix::crlb::crlb;
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// One row of the bench: a method on a scenario.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// Method name.
    pub method: String,
    /// Particles (null for batch fixes and the EKF).
    pub particles: Option<usize>,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Root mean square position error, metres.
    pub rmse: f64,
    /// Mean relative error along x, percent.
    pub rel_x: f64,
    /// Mean relative error along y, percent.
    pub rel_y: f64,
    /// CRLB rmse of the scenario's geometry, metres.
    pub crlb: f64,
    /// rmse / crlb.
    pub ratio: f64,
    /// Mean wall time per run, seconds.
    pub time_s: f64,
    /// Runs in which the method returned no estimate (counted, excluded from the metrics).
    pub failures: usize,
    /// The seed paper's figure for this row, if it printed one.
    pub paper: Option<String>,
}

/// Run every method on `scenario`, `scenario.runs` times each, in parallel over runs.
pub fn bench(scenario: &Scenario, methods: &[Method], progress: bool) -> Vec<Row> {
    let bound = crlb(&scenario.emitter, &scenario.geometry())
        .map(|c| c.rmse as f64)
        .unwrap_or(f64::INFINITY);
    let total = (scenario.runs * methods.len()) as u64;
    let bar = if progress {
        ProgressBar::new(total).with_style(
            ProgressStyle::with_template("{msg:>14} [{bar:30}] {pos}/{len} runs {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        )
    } else {
        ProgressBar::hidden()
    };
    bar.set_message(scenario.name.clone());
    let rows = methods
        .iter()
        .map(|&m| {
            let outcomes: Vec<(Option<[f32; 2]>, f64)> = (0..scenario.runs)
                .into_par_iter()
                .progress_with(bar.clone())
                .map(|run| {
                    let mut rng = scenario.rng(run);
                    let bearings = scenario.simulate(&mut rng);
                    let t = Instant::now();
                    let est = m.run(scenario, &bearings, &mut rng).ok();
                    (est, t.elapsed().as_secs_f64())
                })
                .collect();
            summarise(scenario, m, bound, &outcomes)
        })
        .collect();
    bar.finish_and_clear();
    rows
}

fn summarise(s: &Scenario, m: Method, bound: f64, outcomes: &[(Option<[f32; 2]>, f64)]) -> Row {
    let (ex, ey) = (s.emitter[0] as f64, s.emitter[1] as f64);
    let mut sq = 0.0;
    let (mut rx, mut ry) = (0.0, 0.0);
    let mut ok = 0usize;
    for (est, _) in outcomes {
        if let Some(p) = est {
            let dx = p[0] as f64 - ex;
            let dy = p[1] as f64 - ey;
            sq += dx * dx + dy * dy;
            rx += dx.abs() / ex.abs().max(1e-9);
            ry += dy.abs() / ey.abs().max(1e-9);
            ok += 1;
        }
    }
    let n = ok.max(1) as f64;
    let rmse = if ok > 0 { (sq / n).sqrt() } else { f64::NAN };
    let time_s = outcomes.iter().map(|o| o.1).sum::<f64>() / outcomes.len().max(1) as f64;
    Row {
        scenario: s.name.clone(),
        method: m.name().to_string(),
        particles: m.uses_particles().then_some(s.particles),
        runs: outcomes.len(),
        rmse,
        rel_x: 100.0 * rx / n,
        rel_y: 100.0 * ry / n,
        crlb: bound,
        ratio: rmse / bound,
        time_s,
        failures: outcomes.len() - ok,
        paper: crate::report::paper_figure(s, m),
    }
}
