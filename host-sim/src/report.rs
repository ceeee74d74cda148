//! Bench tables for the terminal, Markdown and JSON.

use crate::methods::Method;
use crate::montecarlo::Row;
use crate::scenario::{Paper, Scenario};
use std::fmt::Write;

/// The seed paper's own figure for a row, printed beside ours (their routes are unpublished;
/// SCENARIOS.md explains why only loop300 reaches their regime).
pub fn paper_figure(s: &Scenario, m: Method) -> Option<String> {
    match (s.paper?, m) {
        (Paper::Afsa, Method::SirSeed) => {
            Some("seed 002 PF: rel_x 0.266 %, rel_y 0.206 %, 0.183 s".into())
        }
        (Paper::Firefly, Method::SirSeed) => {
            Some("seed 001 PF: ~4x the improved FA-PF's error; largest error 0.23 % (FA-PF)".into())
        }
        (Paper::PfVsKf, Method::SirSeed) => {
            Some("seed 004: PF (N = 500) beats the linearised KF".into())
        }
        (Paper::PfVsKf, Method::Ekf) => Some("seed 004: worse than the PF".into()),
        _ => None,
    }
}

/// A fixed-width table for the terminal.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<14} {:<9} {:>5} {:>10} {:>8} {:>8} {:>8} {:>7} {:>10}  paper",
        "scenario", "method", "N", "rmse_m", "rel_x%", "rel_y%", "crlb_m", "ratio", "time_s"
    );
    for r in rows {
        let n = r
            .particles
            .map(|n| n.to_string())
            .unwrap_or_else(|| "-".into());
        let fail = if r.failures > 0 {
            format!(" [{} runs gave no fix]", r.failures)
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "{:<14} {:<9} {:>5} {:>10.3} {:>8.4} {:>8.4} {:>8.3} {:>7.3} {:>10.2e}  {}{}",
            r.scenario,
            r.method,
            n,
            r.rmse,
            r.rel_x,
            r.rel_y,
            r.crlb,
            r.ratio,
            r.time_s,
            r.paper.as_deref().unwrap_or(""),
            fail
        );
    }
    out
}

/// The same rows as a Markdown table (for the README).
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| scenario | method | N | rmse (m) | rel_x % | rel_y % | CRLB (m) | ratio | time/run (s) | paper |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let n = r
            .particles
            .map(|n| n.to_string())
            .unwrap_or_else(|| "-".into());
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.3} | {:.4} | {:.4} | {:.3} | {:.3} | {:.2e} | {} |",
            r.scenario,
            r.method,
            n,
            r.rmse,
            r.rel_x,
            r.rel_y,
            r.crlb,
            r.ratio,
            r.time_s,
            r.paper.as_deref().unwrap_or("")
        );
    }
    out
}
