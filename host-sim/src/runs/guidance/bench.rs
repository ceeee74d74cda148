//! The closed-loop benchmark (`foxhunt bench --scenario guidance`): a simulated DF vehicle
//! drives by each policy until its fix is good, and the distance it took is counted.
//!
//! One run: the vehicle starts at a random place (a random road node; on the highway network a
//! node of the highway) with a random heading; the emitter lies 3-5 km away in a random
//! direction (inside the network; on the river network, across the river). The DF unit gives
//! one bearing a second with noise sigma drawn in 3-5 degrees, which it states correctly; in
//! the `-offset4` set every bearing also carries an unknown offset of 4 degrees (random sign)
//! and the fix estimates it with the default prior (sd 6 degrees), where the plain set's unit is
//! calibrated. Every 5 s the fix is the bias-aware ML ([`foxhunt_core::fix::bias::ml`], started
//! from the last fix). The run ends the first time the fix's CEP50 falls below 100 m: reached if
//! its 95 % ellipse then holds the truth, a confident wrong answer if not; or at 20 km / 60 min.
//!
//! Per (network, policy), over the runs: the median distance and time to the goal (runs that
//! never reach it count as infinitely long; null when more than half do not), the share that
//! reached it, the median CEP50 after 2 km, the share whose final ellipse holds the truth, and
//! how often the stop rule found the offset limiting the fix (and so advised a calibration
//! leg).

use super::networks::{HALF_M, Network};
use super::policy::{Decision, GOAL_M, Move, Policy, decide};
use crate::guidance::reach::OnRoad;
use crate::guidance::{FixView, Situation};
use crate::inputs::roads::RoadGraph;
use crate::runs::montecarlo::Progress;
use foxhunt_core::fix::bias::{self, BiasPrior, BiasedFix};
use foxhunt_core::fix::ellipse::cep50;
use foxhunt_core::fix::locate::{
    Buffers, Item, LocateConfig, NoiseModel, Observation, Source, locate,
};
use foxhunt_core::guidance::stop::{FixQuality, Limit, Reason, StopRule, verdict};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::{Gaussian, random};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;
use serde::Serialize;
use std::f32::consts::PI;
use std::fmt::Write;

/// A run gives up after this distance, metres.
pub const MAX_DISTANCE_M: f32 = 20_000.0;
/// ... or this time, seconds.
pub const MAX_TIME_S: f32 = 3600.0;
/// Seconds between fixes.
pub const FIX_EVERY_S: u32 = 5;
/// The offset of the `-offset4` set, radians.
pub const OFFSET: f32 = 4.0 * PI / 180.0;

/// One benchmark set: a network, with or without the offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Set {
    /// The terrain.
    pub network: Network,
    /// Whether the unit has the unknown 4 degree offset.
    pub offset: bool,
}

impl Set {
    /// Every set: the four networks, then the same with the offset.
    pub fn all() -> Vec<Set> {
        [false, true]
            .into_iter()
            .flat_map(|offset| Network::ALL.map(|network| Set { network, offset }))
            .collect()
    }

    /// Its scenario name: `guidance/open`, `guidance/grid-offset4`, ...
    pub fn name(&self) -> String {
        format!(
            "guidance/{}{}",
            self.network.name(),
            if self.offset { "-offset4" } else { "" }
        )
    }

    /// The sets a scenario name asks for: `guidance` (all), `guidance/NET` or
    /// `guidance/NET-offset4`.
    pub fn named(name: &str) -> Option<Vec<Set>> {
        if name == "guidance" {
            return Some(Self::all());
        }
        let rest = name.strip_prefix("guidance/")?;
        let (net, offset) = match rest.strip_suffix("-offset4") {
            Some(n) => (n, true),
            None => (rest, false),
        };
        Network::from_name(net).map(|network| vec![Set { network, offset }])
    }
}

/// What one run came to.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// Distance to the goal, metres (`None`: not reached).
    pub distance_m: Option<f32>,
    /// Time to the goal, seconds.
    pub time_s: Option<f32>,
    /// The fix claimed CEP50 < 100 m with the truth outside its ellipse.
    pub wrong: bool,
    /// CEP50 of the fix after 2 km, metres (`None`: no fix then).
    pub cep50_2km_m: Option<f32>,
    /// The final fix's 95 % ellipse holds the truth (`None`: no final fix).
    pub final_inside: Option<bool>,
    /// Decisions at which the stop rule found the offset limiting (calibration advised).
    pub offset_limited: u32,
    /// Decisions with a fix.
    pub decisions: u32,
    /// (distance driven, CEP50) at every fix.
    pub curve: Vec<(f32, f32)>,
}

/// The seeded generator of run `run` of a set (the same start, emitter and noise for every
/// policy).
fn run_rng(set: Set, run: usize, seed: u64) -> XorShiftRng {
    let salt = Network::ALL
        .iter()
        .position(|n| *n == set.network)
        .unwrap_or(0) as u64
        + if set.offset { 8 } else { 0 };
    XorShiftRng::seed_from_u64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(salt << 32)
            .wrapping_add(run as u64),
    )
}

/// Where a run starts and where its emitter is.
struct Start {
    position: [f32; 2],
    heading: f32,
    on_road: Option<OnRoad>,
    emitter: [f32; 2],
    sigma: f32,
    offset: f32,
}

fn start(set: Set, g: Option<&RoadGraph>, rng: &mut XorShiftRng) -> Start {
    let inner = HALF_M - 4000.0;
    loop {
        let mut p = [
            random::uniform_in(rng, -inner, inner),
            random::uniform_in(rng, -inner, inner),
        ];
        if set.network == Network::Highway {
            // On the highway itself.
            p[1] = 0.0;
        }
        let (position, on_road) = match g {
            None => (p, None),
            Some(g) => match g.nearest(p).and_then(|n| Some((n, g.position(n)?))) {
                Some((n, q)) => (
                    q,
                    Some(OnRoad {
                        node: n,
                        from: None,
                    }),
                ),
                None => continue,
            },
        };
        let r = random::uniform_in(rng, 3000.0, 5000.0);
        let a = random::uniform_in(rng, -PI, PI);
        let emitter = [position[0] + r * a.cos(), position[1] + r * a.sin()];
        let inside = emitter.iter().all(|v| v.abs() < HALF_M - 1000.0);
        // Across the river from the start: the bridges are what the network is about.
        let across = set.network != Network::River || (emitter[0] < 0.0) != (position[0] < 0.0);
        if inside && across {
            return finish_start(set, position, on_road, emitter, rng);
        }
    }
}

fn finish_start(
    set: Set,
    position: [f32; 2],
    on_road: Option<OnRoad>,
    emitter: [f32; 2],
    rng: &mut XorShiftRng,
) -> Start {
    let heading = random::uniform_in(rng, -PI, PI);
    let sigma = random::uniform_in(rng, 3.0, 5.0).to_radians();
    let sign = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
    Start {
        position,
        heading,
        on_road,
        emitter,
        sigma,
        offset: if set.offset { sign * OFFSET } else { 0.0 },
    }
}

/// The fix of `bearings`, started from the last one.
fn fix(bearings: &[Bearing], prior: BiasPrior, last: Option<&BiasedFix>) -> Option<BiasedFix> {
    let options = bias::BiasedOptions::default();
    let warm = last.and_then(|f| {
        bias::ml_sources(
            bearings,
            &bias::same_priors(prior),
            bias::Start {
                position: f.position,
                bias: f.bias,
            },
            &Gaussian,
            options,
        )
        .ok()
    });
    let f = warm.or_else(|| bias::ml(bearings, prior, None, &Gaussian, options).ok())?;
    // A fix tens of kilometres out is the solver lost in a shallow crossing, not a fix.
    let near = bearings
        .last()
        .map(|b| (f.position[0] - b.vehicle[0]).hypot(f.position[1] - b.vehicle[1]) < 50_000.0);
    near.unwrap_or(false).then_some(f)
}

/// The field pipeline's emitter ([`foxhunt_core::fix::locate::locate`], the unit's sigmas
/// trusted and checked) of `bearings`.
fn honest(bearings: &[Bearing], prior: BiasPrior) -> Option<Source> {
    let obs: Vec<Observation> = bearings
        .iter()
        .enumerate()
        .map(|(k, b)| Observation::new(*b, k as f32))
        .collect();
    let n = obs.len();
    let mut items = vec![Item::EMPTY; n];
    let mut scratch = vec![Item::EMPTY; n];
    let mut order = vec![0u32; n];
    let mut tags = vec![0u8; n];
    let mut rng = XorShiftRng::seed_from_u64(n as u64);
    let config = LocateConfig {
        noise: NoiseModel::Known,
        priors: bias::same_priors(prior),
        ..LocateConfig::default()
    };
    let work = Buffers::new(&mut items, &mut scratch, &mut order, &mut tags);
    let r = locate::<1, 1, _>(&obs, &config, work, &mut rng).ok()?;
    r.emitters().first().copied()
}

/// The fix as guidance sees it.
fn view(f: &BiasedFix) -> FixView {
    let dof = (f.used as f32 - f.parameters).max(1.0);
    let p = foxhunt_core::stats::chi2_sf(f.chi2, dof).unwrap_or(0.0);
    FixView {
        position: f.position,
        covariance: f.covariance,
        consistent: p > 1e-3,
        effective: f.used as f32,
    }
}

/// One closed-loop run of `policy` on `set`.
pub fn run(set: Set, policy: Policy, g: Option<&RoadGraph>, run: usize, seed: u64) -> RunResult {
    let mut rng = run_rng(set, run, seed);
    let s = start(set, g, &mut rng);
    let prior = if set.offset {
        BiasPrior::default()
    } else {
        BiasPrior::calibrated(0.0)
    };
    let rule = StopRule {
        target_cep50_m: GOAL_M,
        ..StopRule::default()
    };
    let mut noise = XorShiftRng::seed_from_u64(rng.next_u64());
    let mut pos = s.position;
    let mut heading = s.heading;
    let mut on_road = s.on_road;
    let mut leg: Option<(Move, f32)> = None; // the move and the seconds driven on it
    // The unit's first bearing is in before the vehicle moves off: the first move is a
    // decision too (at a highway exit it is two kilometres of driving).
    // What the unit reports at `at`: the true bearing, its offset and noise.
    let mut observe = |at: [f32; 2]| Bearing {
        vehicle: at,
        theta: wrap(predicted(&s.emitter, &at) + s.offset + s.sigma * random::normal(&mut noise)),
        sigma: s.sigma,
    };
    let mut bearings: Vec<Bearing> = vec![observe(pos)];
    let mut last_fix: Option<BiasedFix> = None;
    let mut out = RunResult {
        distance_m: None,
        time_s: None,
        wrong: false,
        cep50_2km_m: None,
        final_inside: None,
        offset_limited: 0,
        decisions: 0,
        curve: Vec::new(),
    };
    let mut driven = 0.0f32;
    let mut two_km_done = false;
    let mut t = 0u32;
    while (t as f32) < MAX_TIME_S && driven < MAX_DISTANCE_M {
        // One second of driving, across as many legs as it takes.
        let mut left = 1.0f32;
        let mut guard = 0;
        while left > 1e-4 && guard < 8 {
            guard += 1;
            if leg.is_none() {
                let situation = Situation {
                    bearings: &bearings,
                    vehicle: pos,
                    heading: Some(heading),
                    fix: last_fix.as_ref().map(view),
                    prior,
                };
                if let Some(f) = situation.fix {
                    out.decisions += 1;
                    let q = FixQuality {
                        consistent: f.consistent,
                        effective: f.effective,
                    };
                    if let Ok(v) = verdict(f.position, &bearings, prior, q, &rule)
                        && v.limit == Limit::Offset
                        && v.reason() == Reason::CalibrationLeg
                    {
                        out.offset_limited += 1;
                    }
                }
                let d = Decision {
                    situation,
                    heading,
                    driven_m: driven,
                    on_road: g.zip(on_road),
                };
                match decide(policy, &d) {
                    Some(m) => leg = Some((m, 0.0)),
                    None => break,
                }
            }
            let Some((m, done)) = leg.as_mut() else {
                break;
            };
            let remaining = m.leg.seconds - *done;
            let step = remaining.min(left);
            *done += step;
            left -= step;
            let share = (*done / m.leg.seconds).clamp(0.0, 1.0);
            let next = [
                m.leg.from[0] + share * (m.leg.to[0] - m.leg.from[0]),
                m.leg.from[1] + share * (m.leg.to[1] - m.leg.from[1]),
            ];
            driven += (next[0] - pos[0]).hypot(next[1] - pos[1]);
            pos = next;
            heading = m.leg.heading();
            if *done >= m.leg.seconds - 1e-4 {
                if let Some(end) = m.end {
                    on_road = Some(end);
                }
                leg = None;
            }
        }
        t += 1;
        bearings.push(observe(pos));
        if !t.is_multiple_of(FIX_EVERY_S) {
            continue;
        }
        last_fix = fix(&bearings, prior, last_fix.as_ref());
        let Some(f) = last_fix.as_ref() else {
            continue;
        };
        let Ok(c) = cep50(&f.covariance) else {
            continue;
        };
        out.curve.push((driven, c));
        if !two_km_done && driven >= 2000.0 {
            two_km_done = true;
            out.cep50_2km_m = Some(c);
        }
        if c < GOAL_M {
            // The claim is the field pipeline's, as `foxhunt locate` would make it: robust,
            // with the honest ellipse (the ML alone can settle on a point on the track when
            // the bearings run nearly parallel).
            let Some(h) = honest(&bearings, prior) else {
                continue;
            };
            if !(h.cep50 < GOAL_M) {
                continue;
            }
            let inside = h.ellipse.contains(&h.position, &s.emitter);
            if inside {
                out.distance_m = Some(driven);
                out.time_s = Some(t as f32);
                break;
            }
            // A confident wrong answer: counted, and the drive goes on.
            out.wrong = true;
        }
    }
    out.final_inside =
        honest(&bearings, prior).map(|h| h.ellipse.contains(&h.position, &s.emitter));
    out
}

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

/// Every policy's runs on every set: (set, policy, runs).
pub type Results = Vec<(Set, Policy, Vec<RunResult>)>;

/// Run `runs` seeded runs of every policy on every set, in parallel.
pub fn measure(sets: &[Set], runs: usize, seed: u64, progress: &Progress) -> Results {
    let mut out = Vec::new();
    for set in sets {
        let g = set.network.graph();
        for policy in Policy::ALL {
            progress.set_label(&format!("{} {}", set.name(), policy.name()));
            let results: Vec<RunResult> = crate::estimate::pool().install(|| {
                (0..runs)
                    .into_par_iter()
                    .map(|r| {
                        let x = run(*set, policy, g.as_ref(), r, seed);
                        progress.tick();
                        x
                    })
                    .collect()
            });
            out.push((*set, policy, results));
        }
    }
    out
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
/// the README (SVG, log CEP50 axis from 10 m to 10 km, 0-10 km driven).
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

/// `foxhunt bench --scenario guidance[...]`: the table, `--json` rows or `--markdown`; the
/// scenario `guidance/plot` prints the SVG plot of every set.
pub fn bench(
    scenario: &str,
    runs: Option<usize>,
    json: bool,
    markdown_out: bool,
    quiet: bool,
    out: &mut crate::outputs::terminal::Out,
) -> crate::outputs::terminal::Outcome {
    let plot = scenario == "guidance/plot";
    let sets = if plot {
        Set::all()
    } else {
        Set::named(scenario).ok_or_else(|| {
            format!(
                "unknown scenario `{scenario}`; known: guidance, guidance/plot, guidance/NET and guidance/NET-offset4 with NET one of open, grid, highway, river"
            )
        })?
    };
    let runs = runs.unwrap_or(100);
    if runs == 0 {
        return Err("--runs must be at least 1, not 0".into());
    }
    let progress = Progress::new((sets.len() * Policy::ALL.len() * runs) as u64, !quiet);
    let results = measure(&sets, runs, 1, &progress);
    progress.finish();
    if plot {
        return out.text(&svg(&results));
    }
    let rows = rows(&results);
    if json {
        let text = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
        out.line(&text)
    } else if markdown_out {
        out.text(&markdown(&rows))
    } else {
        out.text(&table(&rows))
    }
}
