//! Seeded, parallel Monte Carlo runs of a scenario's table and the metrics of
//! docs/src/scenarios.md: one skeleton for bearing and tracking scenarios alike.

use crate::estimate::pool;
use crate::outputs::tables::Row;
use crate::runs::run::{bearing_run_timed, tracking_run};
use crate::runs::scenario::{Scenario, ScenarioModel};
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::{Method, PARTICLE_COUNTS};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Progress on stderr: a bar on a terminal, a short line every few seconds otherwise (a CI
/// log or a redirected stderr), nothing when quiet.
pub struct Progress {
    bar: Option<ProgressBar>,
    done: AtomicU64,
    total: u64,
    last_line: Mutex<Instant>,
    label: Mutex<String>,
    lines: bool,
    every: Duration,
}

/// How often a non-terminal progress line is written unless told otherwise.
pub const LINE_EVERY: Duration = Duration::from_secs(5);

impl Progress {
    /// Progress over `total` runs; `show` false keeps it silent.
    pub fn new(total: u64, show: bool) -> Self {
        Self::every(total, show, LINE_EVERY)
    }

    /// [`Progress::new`] writing its non-terminal lines at most every `every`.
    pub fn every(total: u64, show: bool, every: Duration) -> Self {
        let terminal = show && std::io::stderr().is_terminal();
        let bar = terminal.then(|| {
            let bar = ProgressBar::new(total);
            if let Ok(style) =
                ProgressStyle::with_template("{msg:>16} [{bar:30}] {pos}/{len} runs {elapsed}")
            {
                bar.set_style(style);
            }
            bar
        });
        Self {
            bar,
            done: AtomicU64::new(0),
            total,
            last_line: Mutex::new(Instant::now()),
            label: Mutex::new(String::new()),
            lines: show && !terminal,
            every,
        }
    }

    /// Name what is running now.
    pub fn set_label(&self, label: &str) {
        if let Some(b) = &self.bar {
            b.set_message(label.to_string());
        }
        if let Ok(mut l) = self.label.lock() {
            *l = label.to_string();
        }
    }

    /// One run finished.
    pub fn tick(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(b) = &self.bar {
            b.inc(1);
        }
        if !self.lines {
            return;
        }
        let Ok(mut last) = self.last_line.lock() else {
            return;
        };
        if last.elapsed() >= self.every {
            *last = Instant::now();
            let label = self.label.lock().map(|l| l.clone()).unwrap_or_default();
            crate::outputs::terminal::note(&format!(
                "bench: {done}/{} runs done ({label})",
                self.total
            ));
        }
    }

    /// Clear the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// Runs a whole table will take: every method at every count, and the equal-cost rows (an
/// upper bound: a swarm row that cannot run has none).
pub fn total_runs(s: &Scenario) -> u64 {
    let swarms = s.methods.iter().filter(|m| m.is_swarm()).count();
    ((s.methods.len() + swarms) * s.particles.len() * s.runs) as u64
}

/// The scenario's table: every method at every particle count, each swarm method followed by
/// the baseline filter at the particle count that spends the same likelihood evaluations per
/// step (the largest compiled count not above it): the equal-cost comparison.
pub fn bench(s: &Scenario, progress: &Progress) -> Vec<Row> {
    let bound = bound(s);
    let mut rows = Vec::new();
    for &n in &s.particles {
        for &m in &s.methods {
            let row = measure(s, m, n, bound, progress);
            let per_step = row.evaluations / s.steps().max(1) as f64;
            let ran = row.rmse.is_some();
            rows.push(row);
            if m.is_swarm() && ran {
                let equal = PARTICLE_COUNTS
                    .iter()
                    .copied()
                    .filter(|c| *c as f64 <= per_step)
                    .max()
                    .unwrap_or(n);
                let mut r = measure(s, s.baseline, equal, bound, progress);
                r.scenario = s.label(n);
                r.method = format!("{}={}", s.baseline.name(), m.name());
                r.paper = None;
                rows.push(r);
            }
        }
    }
    rows
}

/// The bound rows are measured against: the CRLB of a drive's geometry (infinite when the
/// geometry cannot locate the emitter), or the average PCRB of a tracking scenario.
pub fn bound(s: &Scenario) -> Option<f64> {
    match &s.model {
        ScenarioModel::Bearing(d) => crlb(&d.emitter, &d.geometry())
            .ok()
            .map(|c| c.rmse as f64)
            .filter(|b| b.is_finite()),
        _ => crate::runs::tracking::pcrb(s).filter(|b| b.is_finite()),
    }
}

/// Whether `method` at `n` particles runs at all, and if not why: the O(N^2) swarms are not
/// run above 1 000 particles (minutes to hours per run; `foxhunt perf` times their growth),
/// and AFSA indexes its fish by u16.
pub fn not_run(method: Method, n: usize) -> Option<String> {
    let quadratic = matches!(method, Method::FaPf | Method::GsaGpf);
    if quadratic && n > 1000 {
        return Some(format!(
            "not run: its O(N^2) step at N = {n} takes minutes to hours per run"
        ));
    }
    if method == Method::AfsaPf && n > u16::MAX as usize {
        return Some(format!(
            "not run: AFSA indexes its fish by u16 (at most 65 535, not {n})"
        ));
    }
    None
}

/// One run's outcome: the static fix's error vector or the tracking run's summed error,
/// seconds and likelihood evaluations.
struct Outcome {
    error: Option<Error>,
    seconds: f64,
    evaluations: u64,
}

/// What a run's error is.
enum Error {
    /// Static emitter: estimate minus truth, whether the reported 95 % ellipse holds the
    /// truth, and whether the truth is within the reported CEP50.
    Fix([f64; 2], bool, bool),
    /// Tracking: error summed over the steps.
    Track(f64),
}

/// One method at one particle count over every run.
fn measure(s: &Scenario, m: Method, n: usize, bound: Option<f64>, p: &Progress) -> Row {
    let label = s.label(n);
    p.set_label(&format!("{label} {}", m.name()));
    let mut row = Row::new(label, m, n, s.runs);
    row.crlb = bound;
    row.paper = s.paper(m, n).map(str::to_string);
    if let Some(why) = not_run(m, n) {
        row.note = Some(why);
        for _ in 0..s.runs {
            p.tick();
        }
        return row;
    }
    let outcomes: Vec<Outcome> = pool().install(|| {
        (0..s.runs)
            .into_par_iter()
            .map(|run| {
                let o = one(s, m, n, run);
                p.tick();
                o
            })
            .collect()
    });
    summarise(s, &mut row, &outcomes);
    row
}

fn one(s: &Scenario, m: Method, n: usize, run: usize) -> Outcome {
    match &s.model {
        ScenarioModel::Bearing(d) => {
            let (r, seconds) = bearing_run_timed(d, m, n, &mut s.rng(run));
            let finite = |f: &crate::estimate::BearingFix| f.position.iter().all(|v| v.is_finite());
            match r {
                Ok(f) if finite(&f) => Outcome {
                    error: Some(Error::Fix(
                        [
                            f64::from(f.position[0] - d.emitter[0]),
                            f64::from(f.position[1] - d.emitter[1]),
                        ],
                        mahalanobis(&f.covariance, &f.position, &d.emitter)
                            .is_some_and(|m| m * m <= f.ellipse_scale),
                        (f.position[0] - d.emitter[0]).hypot(f.position[1] - d.emitter[1])
                            <= f.cep50,
                    )),
                    seconds,
                    evaluations: f.evaluations,
                },
                _ => Outcome {
                    error: None,
                    seconds,
                    evaluations: 0,
                },
            }
        }
        _ => {
            let (r, seconds) = tracking_run(s, m, n, run);
            Outcome {
                error: r.as_ref().ok().map(|(e, _)| Error::Track(*e)),
                seconds,
                evaluations: r.map(|(_, ev)| ev).unwrap_or(0),
            }
        }
    }
}

fn summarise(s: &Scenario, row: &mut Row, outcomes: &[Outcome]) {
    let runs = outcomes.len().max(1) as f64;
    row.time_s = outcomes.iter().map(|o| o.seconds).sum::<f64>() / runs;
    row.evaluations = outcomes.iter().map(|o| o.evaluations as f64).sum::<f64>() / runs;
    let ok: Vec<&Error> = outcomes.iter().filter_map(|o| o.error.as_ref()).collect();
    row.failures = outcomes.len() - ok.len();
    if ok.is_empty() {
        row.note = Some(format!(
            "failed: none of {} runs gave an estimate",
            row.runs
        ));
        return;
    }
    let k = ok.len() as f64;
    match &s.model {
        ScenarioModel::Bearing(d) => {
            let (ex, ey) = (f64::from(d.emitter[0]), f64::from(d.emitter[1]));
            let (mut sq, mut rx, mut ry, mut covered, mut cep) = (0.0, 0.0, 0.0, 0, 0);
            for e in &ok {
                if let Error::Fix([dx, dy], inside, within) = e {
                    sq += dx * dx + dy * dy;
                    rx += dx.abs() / ex.abs().max(1e-9);
                    ry += dy.abs() / ey.abs().max(1e-9);
                    covered += *inside as usize;
                    cep += *within as usize;
                }
            }
            row.rmse = Some((sq / k).sqrt());
            row.rel_x = Some(100.0 * rx / k);
            row.rel_y = Some(100.0 * ry / k);
            row.coverage = Some(covered as f64 / k);
            row.cep50_share = Some(cep as f64 / k);
        }
        _ => {
            let sum: f64 = ok
                .iter()
                .map(|e| if let Error::Track(t) = e { *t } else { 0.0 })
                .sum();
            row.rmse = Some(sum / (k * s.steps().max(1) as f64));
        }
    }
    row.ratio = match (row.rmse, row.crlb) {
        (Some(e), Some(b)) if b > 0.0 => Some(e / b),
        _ => None,
    };
    if row.crlb.is_none() && s.drive().is_some() {
        row.note = Some(
            "unbounded geometry: the CRLB is infinite (the emitter lies on the line of the \
             route's bearings)"
                .into(),
        );
    }
}
