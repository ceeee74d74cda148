//! Bench tables for the terminal, Markdown and JSON.

use crate::montecarlo::Row;
use std::fmt::Write;

/// The seed paper's own figure for a row, printed beside ours (their routes are unpublished;
/// SCENARIOS.md explains why only loop300 reaches their regime).
pub fn paper_figure(scenario: &str, method: &str) -> Option<String> {
    let text = match (scenario, method) {
        ("aoa-afsa", "sir-seed") => "seed 002 PF: rel_x 0.266 %, rel_y 0.206 %, 0.183 s",
        ("aoa-afsa", "afsa-pf") => "seed 002 AFSA-PF: rel_x 0.101 %, rel_y 0.091 %, 0.352 s",
        ("aoa-firefly", "sir-seed") => "seed 001 PF: about 4x the improved FA-PF's error",
        ("aoa-firefly", "fa-pf-imp") => "seed 001 improved FA-PF: largest error 0.23 %, < 0.3 s",
        ("aoa-pf-vs-kf", "sir-seed") => "seed 004: PF (N = 500) beats the linearised KF",
        ("aoa-pf-vs-kf", "ekf") => "seed 004: worse than the PF",
        ("ungm", "pf") => "seed 001 PF: 3.0190",
        ("ungm", "fa-pf-imp") => "seed 001 improved FA-PF: 1.4322",
        _ => return rssi_figure(scenario, method),
    };
    Some(text.to_string())
}

/// Seed 003 table 1 (rssi-sim, 50 runs): RMSE in metres by N and method.
fn rssi_figure(scenario: &str, method: &str) -> Option<String> {
    let n: usize = scenario.strip_prefix("rssi-sim/N=")?.parse().ok()?;
    let row = match n {
        50 => [1.2539, 0.6094, 0.5374, 0.4502],
        100 => [0.7443, 0.5006, 0.4515, 0.3599],
        200 => [0.6356, 0.3836, 0.3503, 0.3119],
        _ => return None,
    };
    let col = ["pf", "gpf", "pso-gpf", "gsa-gpf"]
        .iter()
        .position(|m| *m == method)?;
    Some(format!("seed 003: {}", row[col]))
}

/// A fixed-width table for the terminal.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<16} {:<16} {:>5} {:>9} {:>7} {:>7} {:>8} {:>6} {:>9} {:>9}  paper",
        "scenario", "method", "N", "rmse", "rel_x%", "rel_y%", "bound", "ratio", "time_s", "evals"
    );
    for r in rows {
        let fail = if r.failures > 0 {
            format!(" [{} runs gave no estimate]", r.failures)
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "{:<16} {:<16} {:>5} {:>9.3} {:>7} {:>7} {:>8.3} {:>6.3} {:>9.2e} {:>9.2e}  {}{}",
            r.scenario,
            r.method,
            count(r.particles),
            r.rmse,
            pct(r.rel_x),
            pct(r.rel_y),
            r.crlb,
            r.ratio,
            r.time_s,
            r.evaluations,
            r.paper.as_deref().unwrap_or(""),
            fail
        );
    }
    out
}

/// The same rows as a Markdown table (for the README).
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| scenario | method | N | rmse | rel_x % | rel_y % | bound | ratio | time/run (s) | paper |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.3} | {} | {} | {:.3} | {:.3} | {:.2e} | {} |",
            r.scenario,
            r.method,
            count(r.particles),
            r.rmse,
            pct(r.rel_x),
            pct(r.rel_y),
            r.crlb,
            r.ratio,
            r.time_s,
            r.paper.as_deref().unwrap_or("")
        );
    }
    out
}

fn count(n: Option<usize>) -> String {
    n.map(|n| n.to_string()).unwrap_or_else(|| "-".into())
}

fn pct(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into())
}
