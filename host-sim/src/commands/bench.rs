//! `foxhunt bench`: Monte Carlo of every method of a scenario's table against its bound.

use crate::outputs::tables as report;
use crate::outputs::terminal::{Out, Outcome, Stop};
use crate::runs::field::Condition;
use crate::runs::montecarlo::{Progress, bench, total_runs};
use crate::runs::network::NetworkCondition;
use crate::runs::scenario::{NAMES, Scenario, ScenarioModel};
use std::path::PathBuf;

/// Options of `foxhunt bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A canonical scenario, `all` of them, the field conditions (`field`: every one, or
    /// `field/NAME`), the network conditions (`network`: every one, or `network/fixed3` and
    /// the like: the default pipeline beside df-aggregator's algorithm), `small-n` (every
    /// noise-estimating method's coverage with 4 to 50 bearings), the moving emitters
    /// (`moving`: every one, or `moving/NAME`) or the closed-loop guidance sets (`guidance`:
    /// every one, or `guidance/SET`).
    #[arg(long, default_value = "aoa-afsa", conflicts_with = "scenario_file",
          value_parser = super::one_of(super::bench_scenarios()))]
    pub scenario: String,
    /// A scenario file (TOML; docs/src/formats/files.md).
    #[arg(long)]
    pub scenario_file: Option<PathBuf>,
    /// Monte Carlo runs (at least 1; default: the scenario's).
    #[arg(long, value_parser = super::values::count_at_least(1, "runs"))]
    pub runs: Option<usize>,
    /// Particles, one of the compiled counts 50, 80, 100, 200, 500, 1000, 2000, 5000, 10000,
    /// 100000 (default: the scenario's table).
    #[arg(long, value_parser = super::values::particles)]
    pub particles: Option<usize>,
    /// Moving scenarios: only this method's rows (repeatable), each at --particles (default
    /// 10000, the tracker's) over every run, e.g. `--method sir-robust` for the default's row
    /// alone.
    #[arg(long, value_name = "NAME")]
    pub method: Vec<String>,
    /// Moving scenarios: updates a second from every station (default: the scenario's, 1 Hz
    /// outdoors), each update's bearings as noisy as at any rate.
    #[arg(long, value_name = "HZ", value_parser = super::values::f32_where(|hz| hz > 0.0 && hz <= 100.0, "a rate in Hz above 0 and at most 100"))]
    pub rate_hz: Option<f32>,
    /// Moving scenarios: the trackers are told every bearing's noise is this many degrees (a
    /// PFOXB's or KrakenSDR record's default is 1) and estimate each unit's own from its
    /// bearings, as `track` does (the indoor arrays' scenario keeps its own).
    #[arg(long, value_name = "DEG", value_parser = super::values::f32_where(|d| d > 0.0 && d <= 90.0, "degrees above 0 and at most 90"))]
    pub told_sigma: Option<f32>,
    /// Print JSON (an array of rows with stable field names).
    #[arg(long, conflicts_with = "markdown")]
    pub json: bool,
    /// Print a Markdown table.
    #[arg(long)]
    pub markdown: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
    /// When stderr is not a terminal, a progress line at most every this many seconds.
    #[arg(long, default_value_t = 5.0, value_parser = super::values::seconds())]
    pub progress_secs: f64,
}

/// The scenarios `a` asks for, with its overrides applied and checked.
pub fn scenarios(a: &Args) -> Result<Vec<Scenario>, String> {
    let mut list = match &a.scenario_file {
        Some(path) => vec![Scenario::load(path)?],
        None if a.scenario == "all" => Scenario::all(),
        None => vec![Scenario::named(&a.scenario).ok_or_else(|| {
            format!(
                "unknown scenario `{}`; known: all, {}",
                a.scenario,
                NAMES.join(", ")
            )
        })?],
    };
    for s in list.iter_mut() {
        if let Some(r) = a.runs {
            s.runs = r;
        }
        if let Some(n) = a.particles {
            s.particles = vec![n];
        }
        s.validate()?;
    }
    Ok(list)
}

/// One line per scenario saying what is run.
fn header(s: &Scenario) -> String {
    let counts: Vec<String> = s.particles.iter().map(|n| n.to_string()).collect();
    let what = match &s.model {
        ScenarioModel::Bearing(d) => format!(
            "emitter ({}, {}) m, {} bearings, sigma {:.3} deg, wild {:.0} %; bound = CRLB",
            d.emitter[0],
            d.emitter[1],
            d.route.len(),
            d.sigma().to_degrees(),
            100.0 * d.wild_fraction
        ),
        _ => format!("{} steps; bound = posterior CRB", s.steps()),
    };
    format!(
        "{}: {what}; N = {}, {} runs, seed {}",
        s.name,
        counts.join(", "),
        s.runs,
        s.seed
    )
}

/// The field conditions `a` asks for, if it asks for them.
fn field_conditions(a: &Args) -> Result<Option<Vec<Condition>>, String> {
    if a.scenario_file.is_some() {
        return Ok(None);
    }
    match a.scenario.strip_prefix("field") {
        Some("") => Ok(Some(Condition::ALL.to_vec())),
        Some(rest) => {
            let name = rest.strip_prefix('/').unwrap_or(rest);
            let c = crate::runs::field::condition(name).ok_or_else(|| {
                let names: Vec<&str> = Condition::ALL.iter().map(|c| c.name()).collect();
                format!(
                    "unknown field condition `{name}`; known: {}",
                    names.join(", ")
                )
            })?;
            Ok(Some(vec![c]))
        }
        None => Ok(None),
    }
}

/// The network conditions `a` asks for, if it asks for them (the names are checked by the
/// argument parser).
fn network_conditions(a: &Args) -> Option<Vec<NetworkCondition>> {
    if a.scenario_file.is_some() {
        return None;
    }
    match a.scenario.strip_prefix("network") {
        Some("") => Some(NetworkCondition::ALL.to_vec()),
        Some(rest) => NetworkCondition::named(&format!("network-{}", rest.strip_prefix('/')?))
            .map(|c| vec![c]),
        None => None,
    }
}

/// Print bench rows as `a` asks.
fn print(a: &Args, rows: &[crate::outputs::tables::Row], out: &mut Out) -> Outcome {
    if a.json {
        let text = serde_json::to_string_pretty(rows).map_err(|e| e.to_string())?;
        out.line(&text)
    } else if a.markdown {
        out.text(&report::markdown(rows))
    } else {
        out.text(&report::table(rows))
    }
}

/// Run `foxhunt bench`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let moving = a.scenario_file.is_none() && a.scenario.starts_with("moving");
    if !a.method.is_empty() && !moving {
        return Err(Stop::usage(
            "--method picks rows of the moving scenarios (--scenario moving...)",
        ));
    }
    if let Some(conditions) = field_conditions(a)? {
        if a.particles.is_some() {
            return Err(Stop::usage(
                "--particles does not apply to the field conditions (N = 1000)",
            ));
        }
        let rows = crate::runs::field::bench(&conditions, a.runs.unwrap_or(100));
        return print(a, &rows, out);
    }
    if let Some(conditions) = network_conditions(a) {
        if a.runs == Some(0) {
            return Err("--runs must be at least 1, not 0".into());
        }
        if a.particles.is_some() {
            return Err("--particles does not apply to the network conditions".into());
        }
        let rows = crate::runs::network::bench(&conditions, a.runs.unwrap_or(100));
        return print(a, &rows, out);
    }
    if a.scenario_file.is_none() && a.scenario == "small-n" {
        if a.runs == Some(0) {
            return Err("--runs must be at least 1, not 0".into());
        }
        if a.particles.is_some() {
            return Err("--particles does not apply to small-n (N = 1000)".into());
        }
        let rows = crate::runs::small_n::bench(a.runs.unwrap_or(400));
        return print(a, &rows, out);
    }
    if moving {
        if a.runs == Some(0) {
            return Err("--runs must be at least 1, not 0".into());
        }
        let only = a
            .method
            .iter()
            .map(|n| {
                foxhunt_core::Method::from_name(n)
                    .filter(|m| crate::track::moving::TRACK_METHODS.contains(m))
                    .ok_or_else(|| Stop::usage(format!("--method {n}: not a tracking method")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let rows = crate::runs::moving::bench::bench_named(
            &a.scenario,
            a.runs,
            a.particles,
            a.rate_hz,
            a.told_sigma.map(f32::to_radians),
            &only,
            !a.quiet,
        )?;
        return print(a, &rows, out);
    }
    if a.scenario_file.is_none() && a.scenario.starts_with("guidance") {
        return crate::runs::guidance::bench::bench(
            &a.scenario,
            a.runs,
            a.json,
            a.markdown,
            a.quiet,
            out,
        );
    }
    let list = scenarios(a)?;
    let every = std::time::Duration::from_secs_f64(a.progress_secs);
    let progress = Progress::every(list.iter().map(total_runs).sum(), !a.quiet, every);
    let rows: Vec<_> = list.iter().flat_map(|s| bench(s, &progress)).collect();
    progress.finish();
    if !a.json && !a.markdown {
        for s in &list {
            out.line(&header(s))?;
        }
    }
    print(a, &rows, out)
}
