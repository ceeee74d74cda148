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

mod drive;
mod table;

pub use drive::run;
pub use table::{Row, markdown, row, rows, svg, table};

use super::networks::Network;
use super::policy::Policy;
use crate::runs::montecarlo::Progress;
use rayon::prelude::*;
use std::f32::consts::PI;

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
