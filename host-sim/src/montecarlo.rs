//! Seeded, parallel Monte Carlo runs and the metrics of SCENARIOS.md.

use crate::methods::{Method, PARTICLE_COUNTS};
use crate::scenario::Scenario;
use foxhunt_core::fix::crlb::crlb;
use indicatif::{ParallelProgressIterator, ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::OnceLock;
use std::time::Instant;

/// The Monte Carlo thread pool: one worker per core, with 64 MiB stacks. Filters are sized at
/// compile time and a 10 000-particle filter is built on the stack before it is boxed; a rayon
/// worker that waits on a join can also run a stolen run on top of its own, so the default
/// 2 MiB stacks overflow. The reservation is virtual: only touched pages cost memory.
pub fn pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .stack_size(64 << 20)
            .thread_name(|i| format!("foxhunt-mc-{i}"))
            .build()
            .expect("the Monte Carlo thread pool starts")
    })
}

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
    /// Root mean square position error, metres (tracking: over every step of every run).
    pub rmse: f64,
    /// Mean relative error along x, percent (static emitter only).
    pub rel_x: Option<f64>,
    /// Mean relative error along y, percent (static emitter only).
    pub rel_y: Option<f64>,
    /// The bound: CRLB rmse of the geometry, or the PCRB for tracking.
    pub crlb: f64,
    /// rmse / crlb.
    pub ratio: f64,
    /// Mean wall time per run, seconds.
    pub time_s: f64,
    /// Mean likelihood evaluations per run (0 for batch fixes).
    pub evaluations: f64,
    /// Runs in which the method returned no estimate (counted, excluded from the metrics).
    pub failures: usize,
    /// The seed paper's figure for this row, if it printed one.
    pub paper: Option<String>,
}

/// A progress bar on stderr when asked for, hidden otherwise.
pub fn progress_bar(total: u64, label: &str, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("{msg:>14} [{bar:30}] {pos}/{len} runs {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(label.to_string());
    bar
}

/// The outcome of one run: the estimate (if any), seconds, likelihood evaluations.
type Outcome = (Option<[f32; 2]>, f64, u64);

/// Run every method on `scenario`, `scenario.runs` times each, in parallel over runs. Each swarm
/// method is followed by the tuned SIR at the particle count that spends the same likelihood
/// evaluations per step (the largest compiled count not above it): the equal-cost comparison.
pub fn bench(scenario: &Scenario, methods: &[Method], progress: bool) -> Vec<Row> {
    let bound = crlb(&scenario.emitter, &scenario.geometry())
        .map(|c| c.rmse as f64)
        .unwrap_or(f64::INFINITY);
    let bar = progress_bar(
        (scenario.runs * methods.len()) as u64,
        &scenario.name,
        progress,
    );
    let mut rows = Vec::new();
    for &m in methods {
        let outcomes = run_all(scenario, m, &bar);
        let row = summarise(scenario, m, bound, &outcomes);
        let per_step = row.evaluations / scenario.route.len().max(1) as f64;
        let swarm = matches!(m, Method::AfsaPf | Method::FaPf | Method::FaPfImproved);
        rows.push(row);
        if swarm {
            let n = PARTICLE_COUNTS
                .iter()
                .copied()
                .filter(|n| *n as f64 <= per_step)
                .max()
                .unwrap_or(scenario.particles);
            let equal = Scenario {
                particles: n,
                ..scenario.clone()
            };
            let outcomes = run_all(&equal, Method::Sir, &bar);
            let mut r = summarise(&equal, Method::Sir, bound, &outcomes);
            r.method = format!("sir={}", m.name());
            rows.push(r);
        }
    }
    bar.finish_and_clear();
    rows
}

fn run_all(scenario: &Scenario, m: Method, bar: &ProgressBar) -> Vec<Outcome> {
    pool().install(|| {
        (0..scenario.runs)
            .into_par_iter()
            .progress_with(bar.clone())
            .map(|run| {
                let mut rng = scenario.rng(run);
                let bearings = scenario.simulate(&mut rng);
                let t = Instant::now();
                let est = m.run_counted(scenario, &bearings, &mut rng).ok();
                let secs = t.elapsed().as_secs_f64();
                (est.map(|e| e.0), secs, est.map(|e| e.1).unwrap_or(0))
            })
            .collect()
    })
}

fn summarise(s: &Scenario, m: Method, bound: f64, outcomes: &[Outcome]) -> Row {
    let (ex, ey) = (s.emitter[0] as f64, s.emitter[1] as f64);
    let mut sq = 0.0;
    let (mut rx, mut ry) = (0.0, 0.0);
    let mut ok = 0usize;
    for (est, _, _) in outcomes {
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
    let runs = outcomes.len().max(1) as f64;
    Row {
        scenario: s.name.clone(),
        method: m.name().to_string(),
        particles: m.uses_particles().then_some(s.particles),
        runs: outcomes.len(),
        rmse,
        rel_x: Some(100.0 * rx / n),
        rel_y: Some(100.0 * ry / n),
        crlb: bound,
        ratio: rmse / bound,
        time_s: outcomes.iter().map(|o| o.1).sum::<f64>() / runs,
        evaluations: outcomes.iter().map(|o| o.2 as f64).sum::<f64>() / runs,
        failures: outcomes.len() - ok,
        paper: crate::report::paper_figure(&s.name, m.name()),
    }
}
