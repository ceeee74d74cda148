//! The `foxhunt` command.

use clap::{Parser, Subcommand};
use foxhunt_sim::methods::{Method, PARTICLE_COUNTS};
use foxhunt_sim::montecarlo::bench;
use foxhunt_sim::report;
use foxhunt_sim::scenario::{NAMES, Scenario};
use std::process::ExitCode;

/// Find radio transmitters from bearings: benchmarks of every method against the CRLB.
#[derive(Parser)]
#[command(name = "foxhunt", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Monte Carlo benchmark of every method on a scenario, against the CRLB.
    ///
    /// Examples:
    ///   foxhunt bench                              # aoa-afsa, 100 seeded runs
    ///   foxhunt bench --scenario all --markdown    # every canonical scenario, README table
    ///   foxhunt bench --scenario-file my.toml --json
    #[command(verbatim_doc_comment)]
    Bench {
        /// Canonical scenario name, or `all`.
        #[arg(long, default_value = "aoa-afsa", conflicts_with = "scenario_file")]
        scenario: String,
        /// A scenario file (TOML; see SCENARIOS.md).
        #[arg(long)]
        scenario_file: Option<std::path::PathBuf>,
        /// Override the number of Monte Carlo runs.
        #[arg(long)]
        runs: Option<usize>,
        /// Override the number of particles.
        #[arg(long)]
        particles: Option<usize>,
        /// Print JSON (an array of rows with stable field names).
        #[arg(long, conflicts_with = "markdown")]
        json: bool,
        /// Print a Markdown table.
        #[arg(long)]
        markdown: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("foxhunt: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Bench {
            scenario,
            scenario_file,
            runs,
            particles,
            json,
            markdown,
        } => {
            let mut scenarios = match scenario_file {
                Some(path) => {
                    let text = std::fs::read_to_string(&path)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                    vec![
                        Scenario::from_toml(&text)
                            .map_err(|e| format!("{}: {e}", path.display()))?,
                    ]
                }
                None if scenario == "all" => {
                    NAMES.iter().filter_map(|n| Scenario::named(n)).collect()
                }
                None => vec![Scenario::named(&scenario).ok_or_else(|| {
                    format!(
                        "unknown scenario `{scenario}`; known: all, {}",
                        NAMES.join(", ")
                    )
                })?],
            };
            for s in scenarios.iter_mut() {
                if let Some(r) = runs {
                    s.runs = r.max(1);
                }
                if let Some(n) = particles {
                    s.particles = n;
                }
                if !PARTICLE_COUNTS.contains(&s.particles) {
                    return Err(format!(
                        "{} particles is not a compiled size; use one of {PARTICLE_COUNTS:?}",
                        s.particles
                    ));
                }
            }
            let progress =
                !json && !markdown && std::io::IsTerminal::is_terminal(&std::io::stderr());
            let rows: Vec<_> = scenarios
                .iter()
                .flat_map(|s| bench(s, &Method::ALL, progress))
                .collect();
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
                );
            } else if markdown {
                print!("{}", report::markdown(&rows));
            } else {
                for s in &scenarios {
                    println!(
                        "{}: emitter ({}, {}) m, {} bearings, sigma {:.3} deg, wild {:.0} %, N = {}, {} runs, seed {}",
                        s.name,
                        s.emitter[0],
                        s.emitter[1],
                        s.route.len(),
                        s.sigma().to_degrees(),
                        100.0 * s.wild_fraction,
                        s.particles,
                        s.runs,
                        s.seed
                    );
                }
                print!("{}", report::table(&rows));
            }
            Ok(())
        }
    }
}
