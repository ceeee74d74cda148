//! The benchmark's rows from its runs: the terminal and Markdown tables and the SVG plot.

use super::{Results, RunResult, Set};
use crate::runs::guidance::policy::{GOAL_M, Policy};
use serde::Serialize;
use std::fmt::Write;

/// One row of the benchmark (`--json`: field names stable).
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// `guidance/open`, `guidance/grid-offset4`, ...
    pub scenario: String,
    /// The policy.
    pub method: String,
    /// Runs.
    pub runs: usize,
    /// Median distance to CEP50 < 100 m with the truth inside, km (null: over half never).
    pub distance_km: Option<f64>,
    /// Median time to it, minutes.
    pub time_min: Option<f64>,
    /// Share of runs that reached it.
    pub reached: f64,
    /// Share of runs that claimed it with the truth outside the ellipse.
    pub wrong: f64,
    /// Median CEP50 after 2 km, metres (null: over half had no fix then).
    pub cep50_2km_m: Option<f64>,
    /// Share of runs (with a final fix) whose final 95 % ellipse holds the truth.
    pub final_inside: f64,
    /// Share of the decisions (with a fix) at which the offset limited the fix and a
    /// calibration leg was advised.
    pub calibration_advice: f64,
}

fn median(mut v: Vec<f32>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f32::total_cmp);
    let m = v[(v.len() - 1) / 2];
    m.is_finite().then_some(f64::from(m))
}

/// The row of a set and policy from its runs.
pub fn row(set: Set, policy: Policy, runs: &[RunResult]) -> Row {
    let n = runs.len().max(1) as f64;
    let inf = |v: Option<f32>| v.unwrap_or(f32::INFINITY);
    let with_final: Vec<bool> = runs.iter().filter_map(|r| r.final_inside).collect();
    let decisions: u32 = runs.iter().map(|r| r.decisions).sum();
    Row {
        scenario: set.name(),
        method: policy.name().into(),
        runs: runs.len(),
        distance_km: median(runs.iter().map(|r| inf(r.distance_m)).collect()).map(|d| d / 1000.0),
        time_min: median(runs.iter().map(|r| inf(r.time_s)).collect()).map(|t| t / 60.0),
        reached: runs.iter().filter(|r| r.distance_m.is_some()).count() as f64 / n,
        wrong: runs.iter().filter(|r| r.wrong).count() as f64 / n,
        cep50_2km_m: median(runs.iter().map(|r| inf(r.cep50_2km_m)).collect()),
        final_inside: with_final.iter().filter(|b| **b).count() as f64
            / with_final.len().max(1) as f64,
        calibration_advice: runs.iter().map(|r| r.offset_limited).sum::<u32>() as f64
            / f64::from(decisions.max(1)),
    }
}

/// The rows of measured results.
pub fn rows(results: &Results) -> Vec<Row> {
    results.iter().map(|(s, p, r)| row(*s, *p, r)).collect()
}

fn cell(v: Option<f64>, digits: usize) -> String {
    v.map(|v| format!("{v:.digits$}"))
        .unwrap_or_else(|| "-".into())
}

/// A row's cells, shared by the Markdown and the terminal tables (shares in percent).
fn cells(r: &Row) -> [String; 10] {
    let pct = |x: f64| format!("{:.0}", 100.0 * x);
    [
        r.scenario.to_string(),
        r.method.to_string(),
        r.runs.to_string(),
        cell(r.distance_km, 2),
        cell(r.time_min, 1),
        pct(r.reached),
        pct(r.wrong),
        cell(r.cep50_2km_m, 0),
        pct(r.final_inside),
        pct(r.calibration_advice),
    ]
}

/// The rows as a Markdown table.
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| scenario | policy | runs | distance to goal, km (median) | time, min | reached | wrong | CEP50 after 2 km, m | final ellipse holds truth | calibration advice |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let c = cells(r);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} % | {} % | {} | {} % | {} % |",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]
        );
    }
    out
}

/// The rows for the terminal.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<24} {:<14} {:>5} {:>8} {:>7} {:>8} {:>6} {:>9} {:>8} {:>7}",
        "scenario",
        "policy",
        "runs",
        "dist_km",
        "min",
        "reached",
        "wrong",
        "cep50_2km",
        "inside",
        "calib"
    );
    for r in rows {
        let c = cells(r);
        let _ = writeln!(
            out,
            "{:<24} {:<14} {:>5} {:>8} {:>7} {:>7}% {:>5}% {:>9} {:>7}% {:>6}%",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]
        );
    }
    out
}

/// Median CEP50 against distance driven, a panel per set and a line per policy: the plot of
/// the book (SVG, log CEP50 axis from 10 m to 10 km, 0-10 km driven).
pub fn svg(results: &Results) -> String {
    const W: f32 = 300.0;
    const H: f32 = 200.0;
    const PAD: f32 = 40.0;
    const COLOURS: [&str; 6] = [
        "#d62728", "#7f7f7f", "#9467bd", "#1f77b4", "#17becf", "#2ca02c",
    ];
    let sets: Vec<Set> = {
        let mut v: Vec<Set> = results.iter().map(|(s, _, _)| *s).collect();
        v.dedup();
        v
    };
    let cols = 4usize;
    let rows_n = sets.len().div_ceil(cols);
    let (tw, th) = (
        cols as f32 * (W + PAD) + PAD,
        rows_n as f32 * (H + PAD) + 2.0 * PAD,
    );
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{tw}\" height=\"{th}\" font-family=\"sans-serif\" font-size=\"10\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let y_of = |c: f32| {
        let l = c.clamp(10.0, 10_000.0).log10();
        H - (l - 1.0) / 3.0 * H
    };
    for (k, set) in sets.iter().enumerate() {
        let ox = PAD + (k % cols) as f32 * (W + PAD);
        let oy = PAD + (k / cols) as f32 * (H + PAD);
        let _ = writeln!(
            out,
            "<g transform=\"translate({ox},{oy})\"><rect width=\"{W}\" height=\"{H}\" fill=\"none\" stroke=\"#444\"/><text x=\"4\" y=\"-4\">{}</text>",
            set.name()
        );
        for c in [10.0f32, 100.0, 1000.0, 10_000.0] {
            let y = y_of(c);
            let _ = writeln!(
                out,
                "<line x1=\"0\" x2=\"{W}\" y1=\"{y}\" y2=\"{y}\" stroke=\"#ddd\"/><text x=\"-4\" y=\"{y}\" text-anchor=\"end\">{c}</text>"
            );
        }
        for km in [0, 2, 4, 6, 8, 10] {
            let x = km as f32 / 10.0 * W;
            let _ = writeln!(
                out,
                "<text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">{km}</text>",
                H + 12.0
            );
        }
        let gy = y_of(GOAL_M);
        let _ = writeln!(
            out,
            "<line x1=\"0\" x2=\"{W}\" y1=\"{gy}\" y2=\"{gy}\" stroke=\"#000\" stroke-dasharray=\"4 3\"/>"
        );
        for (i, policy) in Policy::ALL.iter().enumerate() {
            let Some((_, _, runs)) = results.iter().find(|(s, p, _)| s == set && p == policy)
            else {
                continue;
            };
            let mut pts = String::new();
            for step in 0..=40 {
                let d = 250.0 * step as f32;
                let at: Vec<f32> = runs
                    .iter()
                    .map(|r| {
                        // The last fix at or before d; a run that stopped at the goal keeps its
                        // final CEP50.
                        r.curve
                            .iter()
                            .take_while(|(x, _)| *x <= d)
                            .last()
                            .map(|(_, c)| *c)
                            .unwrap_or(f32::INFINITY)
                    })
                    .collect();
                if let Some(m) = median(at) {
                    let _ = write!(pts, "{:.1},{:.1} ", d / 10_000.0 * W, y_of(m as f32));
                }
            }
            let _ = writeln!(
                out,
                "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{pts}\"/>",
                COLOURS[i]
            );
        }
        out.push_str("</g>\n");
    }
    let ly = th - PAD * 0.6;
    for (i, policy) in Policy::ALL.iter().enumerate() {
        let x = PAD + 110.0 * i as f32;
        let _ = writeln!(
            out,
            "<line x1=\"{x}\" x2=\"{}\" y1=\"{ly}\" y2=\"{ly}\" stroke=\"{}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{}</text>",
            x + 20.0,
            COLOURS[i],
            x + 24.0,
            ly + 3.0,
            policy.name()
        );
    }
    let _ = writeln!(
        out,
        "<text x=\"{PAD}\" y=\"14\">median CEP50 (m, log) against distance driven (km); dashed: the 100 m goal</text>\n</svg>"
    );
    out
}
