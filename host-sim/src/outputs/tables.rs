//! Every table the command prints: bench rows for the terminal, Markdown and JSON, and the
//! speed tables of `foxhunt perf`.

use serde::Serialize;
use std::fmt::Write;

/// One row of the bench: a method on a scenario at one particle count.
///
/// Static-emitter rows give the rmse of the final fix over the runs; tracking rows give the
/// seeds' "average RMSE" (seed 003 eq. 10), the mean Euclidean error over steps and runs, in
/// the same field, and the posterior CRB averaged the same way as the bound.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Scenario name (with `/N=` when its table has several particle counts).
    pub scenario: String,
    /// Method name (`baseline=swarm` for the plain filter given a swarm's cost).
    pub method: String,
    /// Particles (null for batch fixes and the EKF).
    pub particles: Option<usize>,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Static emitter: root mean square error of the final fix, metres. Tracking: the mean
    /// position error over steps and runs. Null when no run gave an estimate.
    pub rmse: Option<f64>,
    /// Mean relative error along x, percent (static emitter only).
    pub rel_x: Option<f64>,
    /// Mean relative error along y, percent (static emitter only).
    pub rel_y: Option<f64>,
    /// The bound: CRLB rmse of the geometry, or the average PCRB for tracking. Null when it is
    /// infinite (the geometry cannot locate the emitter).
    pub crlb: Option<f64>,
    /// rmse / bound; null when either is unknown.
    pub ratio: Option<f64>,
    /// Mean wall time per run, seconds.
    pub time_s: f64,
    /// Mean likelihood evaluations per run (0 for batch fixes).
    pub evaluations: f64,
    /// Runs in which the method returned no estimate (counted, excluded from the metrics).
    pub failures: usize,
    /// Static emitter: share of the runs with an estimate whose reported 95 % ellipse holds
    /// the truth (0.95 if the ellipse is honest).
    pub coverage: Option<f64>,
    /// Static emitter: share of the runs with an estimate within its reported CEP50 of the
    /// truth (0.5 if honest).
    pub cep50_share: Option<f64>,
    /// Field conditions: share of the runs that gave an emitter (for pure noise, the share
    /// that wrongly did).
    pub found: Option<f64>,
    /// Field conditions: runs with the truth beyond the 99.73 % region of the reported
    /// ellipse (a confident wrong answer).
    pub beyond_3_sigma: Option<usize>,
    /// Why the row's figures are missing or partial, when they are.
    pub note: Option<String>,
    /// The seed paper's figure for this row, if it printed one.
    pub paper: Option<String>,
}

impl Row {
    /// A row of `method` at `particles` (shown only for particle methods) over `runs`, with
    /// nothing measured yet.
    pub fn new(
        scenario: String,
        method: foxhunt_core::Method,
        particles: usize,
        runs: usize,
    ) -> Self {
        Self {
            scenario,
            method: method.name().to_string(),
            particles: method.uses_particles().then_some(particles),
            runs,
            rmse: None,
            rel_x: None,
            rel_y: None,
            crlb: None,
            ratio: None,
            time_s: 0.0,
            evaluations: 0.0,
            failures: 0,
            coverage: None,
            cep50_share: None,
            found: None,
            beyond_3_sigma: None,
            note: None,
            paper: None,
        }
    }

    /// The row's note, or the failures counted in words.
    fn remark(&self) -> String {
        match (&self.note, self.failures) {
            (Some(n), _) => n.clone(),
            (None, 0) => String::new(),
            (None, f) => format!("{f} of {} runs gave no estimate", self.runs),
        }
    }
}

fn num(v: Option<f64>, width: usize, digits: usize) -> String {
    match v {
        Some(v) => format!("{v:>width$.digits$}"),
        None => format!("{:>width$}", "-"),
    }
}

/// Whether the rows are field-condition rows (they count detections and 3-sigma misses).
fn field(rows: &[Row]) -> bool {
    rows.iter().any(|r| r.found.is_some())
}

/// Field-condition rows for the terminal or Markdown: detection, accuracy against the
/// bias-aware bound, and how honest the ellipses are.
fn field_table(rows: &[Row], markdown: bool) -> String {
    let mut out = String::new();
    let pct = |v: Option<f64>| {
        v.map(|v| format!("{:.0} %", 100.0 * v))
            .unwrap_or_else(|| "-".into())
    };
    let num = |v: Option<f64>| v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into());
    let head = [
        "condition",
        "method",
        "N",
        "runs",
        "emitter found",
        "rmse m",
        "bound m",
        "ratio",
        "95 % ellipse holds",
        "within CEP50",
        "beyond 3 sigma",
        "note",
    ];
    let cells = |r: &Row| -> [String; 12] {
        [
            r.scenario.trim_start_matches("field/").to_string(),
            r.method.clone(),
            count(r.particles),
            r.runs.to_string(),
            pct(r.found),
            num(r.rmse),
            num(r.crlb),
            num(r.ratio),
            pct(r.coverage),
            pct(r.cep50_share),
            r.beyond_3_sigma
                .map(|n| n.to_string())
                .unwrap_or_else(|| "-".into()),
            r.remark(),
        ]
    };
    if markdown {
        let _ = writeln!(out, "| {} |", head.join(" | "));
        let _ = writeln!(out, "|{}", "---|".repeat(head.len()));
        for r in rows {
            let _ = writeln!(out, "| {} |", cells(r).join(" | "));
        }
        return out;
    }
    let all: Vec<[String; 12]> = rows.iter().map(cells).collect();
    let width: Vec<usize> = (0..12)
        .map(|i| {
            all.iter()
                .map(|c| c[i].len())
                .chain([head[i].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |c: &[String]| -> String {
        c.iter()
            .zip(&width)
            .enumerate()
            .map(|(i, (v, w))| {
                if i < 2 || i == 11 {
                    format!("{v:<w$}")
                } else {
                    format!("{v:>w$}")
                }
            })
            .collect::<Vec<_>>()
            .join("  ")
    };
    let _ = writeln!(out, "{}", line(&head.map(str::to_string)).trim_end());
    for c in &all {
        let _ = writeln!(out, "{}", line(c).trim_end());
    }
    out
}

/// A fixed-width table for the terminal.
pub fn table(rows: &[Row]) -> String {
    if field(rows) {
        return field_table(rows, false);
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<16} {:<18} {:>6} {:>9} {:>7} {:>7} {:>8} {:>6} {:>6} {:>6} {:>9} {:>9}  paper / note",
        "scenario",
        "method",
        "N",
        "rmse",
        "rel_x%",
        "rel_y%",
        "bound",
        "ratio",
        "cover",
        "cep50",
        "time_s",
        "evals"
    );
    for r in rows {
        let note = [r.paper.clone().unwrap_or_default(), r.remark()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("; ");
        let _ = writeln!(
            out,
            "{:<16} {:<18} {:>6} {} {} {} {} {} {} {} {:>9.2e} {:>9.2e}  {note}",
            r.scenario,
            r.method,
            count(r.particles),
            num(r.rmse, 9, 3),
            num(r.rel_x, 7, 3),
            num(r.rel_y, 7, 3),
            num(r.crlb, 8, 3),
            num(r.ratio, 6, 3),
            num(r.coverage.map(|c| 100.0 * c), 6, 1),
            num(r.cep50_share.map(|c| 100.0 * c), 6, 1),
            r.time_s,
            r.evaluations,
        );
    }
    out
}

/// The same rows as a Markdown table (for the book).
pub fn markdown(rows: &[Row]) -> String {
    if field(rows) {
        return field_table(rows, true);
    }
    let mut out = String::from(
        "| scenario | method | N | rmse | rel_x % | rel_y % | bound | ratio | 95 % ellipse holds | within CEP50 | time/run (s) | paper / note |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let cell = |v: Option<f64>| v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into());
    let pct = |v: Option<f64>| {
        v.map(|v| format!("{:.0} %", 100.0 * v))
            .unwrap_or_else(|| "-".into())
    };
    for r in rows {
        let note = [r.paper.clone().unwrap_or_default(), r.remark()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("; ");
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2e} | {note} |",
            r.scenario,
            r.method,
            count(r.particles),
            cell(r.rmse),
            cell(r.rel_x),
            cell(r.rel_y),
            cell(r.crlb),
            cell(r.ratio),
            pct(r.coverage),
            pct(r.cep50_share),
            r.time_s,
        );
    }
    out
}

fn count(n: Option<usize>) -> String {
    n.map(|n| n.to_string()).unwrap_or_else(|| "-".into())
}

/// Seconds in the unit that keeps 3 significant digits readable.
pub fn human_seconds(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.1} us", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}
