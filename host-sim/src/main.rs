//! The `foxhunt` command.

use clap::{Parser, Subcommand};
use foxhunt_sim::methods::{Method, PARTICLE_COUNTS};
use foxhunt_sim::montecarlo::bench;
use foxhunt_sim::report;
use foxhunt_sim::scenario::{NAMES, Scenario};
use foxhunt_sim::tracking::{self, Tracking};
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
    /// Monte Carlo benchmark of every method on a scenario, against the CRLB (or PCRB).
    ///
    /// Bearing scenarios: aoa-afsa, aoa-firefly, aoa-pf-vs-kf, aoa-drive, aoa-afsa-wild.
    /// Tracking scenarios: rssi-sim (N = 50, 100, 200), rssi-lab, ungm.
    ///
    /// Examples:
    ///   foxhunt bench                              # aoa-afsa, 100 seeded runs
    ///   foxhunt bench --scenario all --markdown    # every canonical scenario, README table
    ///   foxhunt bench --scenario rssi-sim --runs 20
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
    /// Locate the emitter of a recorded drive (NMEA GGA/RMC + $PFOXB bearings).
    ///
    /// With no CAPTURE, locates the bundled sample drive (foxhunt simulate --scenario
    /// aoa-drive) and writes its maps to foxhunt-sample.{geojson,kml,svg} unless map paths
    /// are given. `-` reads standard input. Exit status: 0 with a fix, 1 when the capture
    /// gives none (the message says why), 2 on a usage error.
    ///
    /// Examples:
    ///   foxhunt locate                                  # the bundled sample drive
    ///   foxhunt locate drive.nmea --json
    ///   foxhunt locate drive.nmea --method sir --geojson fix.geojson
    ///   cat /dev/ttyUSB0 | foxhunt locate - --sigma-deg 2
    #[command(verbatim_doc_comment)]
    Locate {
        /// Capture files (concatenated in order), or `-` for standard input.
        captures: Vec<std::path::PathBuf>,
        /// Fix method.
        #[arg(long, value_enum, default_value = "ml")]
        method: foxhunt_sim::locate::LocateMethod,
        /// Bearing noise of the DF unit, degrees (default: estimated from the residuals).
        #[arg(long)]
        sigma_deg: Option<f32>,
        /// Print one JSON object (stable field names).
        #[arg(long)]
        json: bool,
        /// Write the emitter, ellipse, track and bearing lines as GeoJSON.
        #[arg(long)]
        geojson: Option<std::path::PathBuf>,
        /// Write the same as KML.
        #[arg(long)]
        kml: Option<std::path::PathBuf>,
        /// Draw the track, bearing rays, particle cloud, ellipse and emitter as SVG.
        #[arg(long)]
        svg: Option<std::path::PathBuf>,
        /// Seed of the particle methods.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Read CAPTURE as a serial device at this baud rate, updating the fix as bytes arrive
        /// (4800 is NMEA 0183's usual rate).
        #[arg(long)]
        baud: Option<u32>,
        /// With --baud: stop after this many seconds without a byte (default: until the
        /// device closes).
        #[arg(long, requires = "baud")]
        quiet_exit: Option<f32>,
    },
    /// Track a ZigBee node indoors from a coordinator's capture (AF_INCOMING_MSG frames).
    ///
    /// The anchors file (TOML) gives each anchor's short address and position, and the
    /// room, path loss and noise. Prints the track as CSV (or --json); --svg draws it.
    ///
    /// Examples:
    ///   foxhunt track serial-bridge/captures/rssi-sim.znp --anchors serial-bridge/captures/rssi-sim.anchors.toml
    ///   foxhunt track node.cap --anchors lab.toml --json --svg track.svg
    #[command(verbatim_doc_comment)]
    Track {
        /// Capture file, or `-` for standard input.
        capture: std::path::PathBuf,
        /// The anchors file.
        #[arg(long)]
        anchors: std::path::PathBuf,
        /// Print JSON (an array of track points) instead of CSV.
        #[arg(long)]
        json: bool,
        /// Draw the room, anchors and track as SVG.
        #[arg(long)]
        svg: Option<std::path::PathBuf>,
        /// Seed of the particle filter.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Every decoded frame of a capture as a JSON line, then the counters.
    ///
    /// Kinds: gga, rmc, pfoxb, af_incoming_msg, mt (other MT frames), nmea (other sentences);
    /// the last line has kind counters.
    ///
    /// Example:
    ///   foxhunt frames drive.nmea | grep pfoxb
    #[command(verbatim_doc_comment)]
    Frames {
        /// Capture file, or `-` for standard input.
        capture: std::path::PathBuf,
    },
    /// Write a capture as the radios would send it (GGA + RMC + PFOXB for a drive).
    ///
    /// Local (0, 0) of the scenario sits at --origin (default 47.0,8.0). The GPS reports
    /// each route point at a whole second, the DF unit half a second later.
    ///
    /// Examples:
    ///   foxhunt simulate --scenario aoa-drive --out drive.nmea
    ///   foxhunt simulate --scenario-file my.toml --origin 53.35,-6.26 --out my.nmea
    #[command(verbatim_doc_comment)]
    Simulate {
        /// Canonical bearing scenario name.
        #[arg(long, default_value = "aoa-drive", conflicts_with = "scenario_file")]
        scenario: String,
        /// A scenario file (TOML).
        #[arg(long)]
        scenario_file: Option<std::path::PathBuf>,
        /// Where to write the capture.
        #[arg(long)]
        out: std::path::PathBuf,
        /// Latitude,longitude of local (0, 0), decimal degrees.
        #[arg(long, allow_hyphen_values = true)]
        origin: Option<String>,
        /// Which Monte Carlo run's noise to write.
        #[arg(long, default_value_t = 0)]
        run: usize,
        /// Share of wild bearings, uniform over the circle (default: the scenario's).
        #[arg(long)]
        wild: Option<f32>,
        /// Constant multipath bias on every bearing, degrees.
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        bias_deg: f32,
        /// Share of bytes corrupted after writing (0.01 = 1 %).
        #[arg(long, default_value_t = 0.0)]
        corrupt: f32,
        /// Share of bytes dropped after writing.
        #[arg(long, default_value_t = 0.0)]
        drop: f32,
    },
    /// Speed: the bootstrap SIR against the same filter in numpy (filterpy), and how every
    /// filter's step time grows with N (100 to 100 000). Single thread; markdown tables.
    ///
    /// Installs numpy, scipy and filterpy from PyPI into target/peer-venv on first use.
    /// Example: foxhunt perf --runs 20
    Perf {
        /// Runs timed per particle count against the numpy peer.
        #[arg(long, default_value_t = 20)]
        runs: usize,
        /// Seconds spent timing each cell of the growth table.
        #[arg(long, default_value_t = 0.5)]
        budget: f64,
        /// Skip a growth cell whose extrapolated step time exceeds this many seconds.
        #[arg(long, default_value_t = 30.0)]
        limit: f64,
        /// Only the numpy comparison.
        #[arg(long)]
        no_growth: bool,
    },
}

/// The bundled sample drive (`foxhunt simulate --scenario aoa-drive`).
const SAMPLE_DRIVE: &[u8] = include_bytes!("../../serial-bridge/captures/aoa-drive.nmea");

/// The bytes of the captures, in order; none means the bundled sample; `-` is stdin.
fn read_captures(paths: &[std::path::PathBuf]) -> Result<Vec<u8>, String> {
    use std::io::Read;
    if paths.is_empty() {
        return Ok(SAMPLE_DRIVE.to_vec());
    }
    let mut bytes = Vec::new();
    for p in paths {
        if p.as_os_str() == "-" {
            std::io::stdin()
                .read_to_end(&mut bytes)
                .map_err(|e| format!("cannot read standard input: {e}"))?;
        } else {
            use std::os::unix::fs::FileTypeExt;
            if std::fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device()) {
                return Err(format!(
                    "{} is a serial device: give --baud (4800 for NMEA 0183, 115200 for a ZNP)",
                    p.display()
                ));
            }
            let b = std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
            bytes.extend_from_slice(&b);
        }
    }
    if bytes.is_empty() {
        return Err("the capture is empty: no bytes to decode".into());
    }
    Ok(bytes)
}

/// `foxhunt track`.
fn track(
    capture: &std::path::Path,
    anchors: &std::path::Path,
    json: bool,
    svg: Option<&std::path::Path>,
    seed: u64,
) -> Result<(), String> {
    use foxhunt_sim::indoor::{AnchorsFile, track};
    let bytes = read_captures(&[capture.to_path_buf()])?;
    let text = std::fs::read_to_string(anchors)
        .map_err(|e| format!("cannot read {}: {e}", anchors.display()))?;
    let file = AnchorsFile::from_toml(&text).map_err(|e| format!("{}: {e}", anchors.display()))?;
    let t = track(&bytes, &file, seed)?;
    if t.unknown.0 > 0 {
        let addrs: Vec<String> = t.unknown.1.iter().map(|a| format!("0x{a:04x}")).collect();
        eprintln!(
            "foxhunt: skipped {} frames from addresses not in {}: {}",
            t.unknown.0,
            anchors.display(),
            addrs.join(", ")
        );
    }
    if let Some(p) = svg {
        std::fs::write(p, foxhunt_sim::maps::track_svg(&t, &file))
            .map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    if json {
        println!(
            "{}",
            serde_json::to_string(&t.points).map_err(|e| e.to_string())?
        );
    } else {
        println!("step,t_s,x_m,y_m,vx_mps,vy_mps,sd_x_m,sd_y_m,heard");
        for p in &t.points {
            println!(
                "{},{:.2},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{}",
                p.step, p.t_s, p.x_m, p.y_m, p.vx_mps, p.vy_mps, p.sd_x_m, p.sd_y_m, p.heard
            );
        }
    }
    Ok(())
}

/// Where `locate` writes its maps.
struct Maps {
    geojson: Option<std::path::PathBuf>,
    kml: Option<std::path::PathBuf>,
    svg: Option<std::path::PathBuf>,
}

/// `foxhunt locate`.
fn locate(
    paths: &[std::path::PathBuf],
    method: foxhunt_sim::locate::LocateMethod,
    sigma_deg: Option<f32>,
    json: bool,
    maps: &Maps,
    seed: u64,
) -> Result<(), String> {
    use foxhunt_sim::locate as l;
    let bytes = read_captures(paths)?;
    let decoded = l::decode(&bytes, foxhunt_bridge::BridgeConfig::default());
    let (report, solution) = l::locate(&decoded, method, sigma_deg, seed)?;
    finish_locate(&report, &solution, &decoded, json, maps)
}

/// Write the maps and print the fix.
fn finish_locate(
    report: &foxhunt_sim::locate::LocateReport,
    solution: &foxhunt_sim::locate::Solution,
    decoded: &foxhunt_sim::locate::Decoded,
    json: bool,
    maps: &Maps,
) -> Result<(), String> {
    use foxhunt_sim::{locate as l, maps as m};
    let write = |path: &Option<std::path::PathBuf>, text: String| -> Result<(), String> {
        if let Some(p) = path {
            std::fs::write(p, text).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
            eprintln!("wrote {}", p.display());
        }
        Ok(())
    };
    write(
        &maps.geojson,
        l::geojson(report, solution, decoded).to_string(),
    )?;
    write(&maps.kml, m::kml(report, solution, decoded))?;
    if maps.svg.is_some() && solution.cloud.is_empty() {
        // A batch fix has no particles: draw the SIR's cloud on the same bearings for the
        // picture (the fix, ellipse and numbers stay the chosen method's).
        let sigma = report.sigma_deg.to_radians();
        let bearings: Vec<_> = decoded
            .bearings
            .iter()
            .map(|b| foxhunt_core::Bearing { sigma, ..*b })
            .collect();
        let cloud = l::solve(l::LocateMethod::Sir, &bearings, 1)
            .map(|s| s.cloud)
            .unwrap_or_default();
        let with_cloud = l::Solution {
            cloud,
            ..solution.clone()
        };
        write(&maps.svg, m::svg(report, &with_cloud, decoded))?;
    } else {
        write(&maps.svg, m::svg(report, solution, decoded))?;
    }
    if json {
        println!(
            "{}",
            serde_json::to_string(&report).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    let r = &report;
    println!(
        "emitter     {:.6}, {:.6}  ({:.1} m east, {:.1} m north of {:.6}, {:.6})",
        r.lat, r.lon, r.east_m, r.north_m, r.origin.lat, r.origin.lon
    );
    println!(
        "95 % ellipse {:.1} x {:.1} m, major axis {:.0} deg from north; CEP50 {:.1} m",
        r.ellipse.major_m, r.ellipse.minor_m, r.ellipse.orientation_deg, r.cep50_m
    );
    println!(
        "CRLB        {:.1} m for this drive's geometry (best any unbiased fix can do)",
        r.crlb_m
    );
    println!(
        "method      {}, bearing noise {:.2} deg ({})",
        serde_json::to_value(r.method)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default(),
        r.sigma_deg,
        if r.sigma_estimated {
            "estimated from the residuals"
        } else {
            "given"
        }
    );
    let rejected: Vec<String> = r
        .rejected
        .iter()
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{k} {n}"))
        .collect();
    println!(
        "bearings    {} used; rejected: {}",
        r.used,
        if rejected.is_empty() {
            "none".to_string()
        } else {
            rejected.join(", ")
        }
    );
    Ok(())
}

/// `foxhunt simulate`: one run of a bearing scenario as a capture file.
fn simulate(
    name: &str,
    file: Option<&std::path::Path>,
    out: &std::path::Path,
    origin: Option<&str>,
    mut options: foxhunt_sim::simulate::CaptureOptions,
) -> Result<(), String> {
    use foxhunt_sim::simulate::drive_capture;
    if file.is_none() && foxhunt_sim::tracking::NAMES.contains(&name) {
        let (bytes, anchors, _) = foxhunt_sim::indoor::simulate_capture(name, options.run)?;
        let anchors_path = out.with_extension("anchors.toml");
        let text = format!(
            "# Anchors of `foxhunt simulate --scenario {name}`: short address (0x0101 works as\n\
             # well as 257), position in metres; room, epoch, noise and path loss of the model.\n{}",
            toml::to_string(&anchors).map_err(|e| e.to_string())?
        );
        std::fs::write(out, &bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        std::fs::write(&anchors_path, text)
            .map_err(|e| format!("cannot write {}: {e}", anchors_path.display()))?;
        eprintln!(
            "wrote {} ({} bytes of AF_INCOMING_MSG frames) and {}",
            out.display(),
            bytes.len(),
            anchors_path.display()
        );
        return Ok(());
    }
    let scenario = match file {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            Scenario::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))?
        }
        None => Scenario::named(name)
            .ok_or_else(|| format!("unknown scenario `{name}`; known: {}", NAMES.join(", ")))?,
    };
    if let Some(o) = origin {
        let bad = || format!("--origin wants LAT,LON in decimal degrees, not `{o}`");
        let (lat, lon) = o.split_once(',').ok_or_else(bad)?;
        options.origin = foxhunt_bridge::nmea::LatLon {
            lat: lat.trim().parse().map_err(|_| bad())?,
            lon: lon.trim().parse().map_err(|_| bad())?,
        };
    }
    let bytes = drive_capture(&scenario, &options)?;
    std::fs::write(out, &bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    eprintln!(
        "wrote {} ({} bytes, {} bearings; local (0, 0) at {:.6},{:.6})",
        out.display(),
        bytes.len(),
        scenario.route.len(),
        options.origin.lat,
        options.origin.lon
    );
    Ok(())
}

/// `foxhunt perf`: the Rust SIR against the numpy peer, then the growth table.
fn perf(runs: usize, growth: Option<(f64, f64)>) -> Result<(), String> {
    use foxhunt_sim::perf::runs_at;
    use foxhunt_sim::perf::{GROWTH_SIZES, StepTime};
    println!(
        "Bootstrap SIR on aoa-afsa (60 bearings), one thread, the same runs on both sides \
         (at least {runs}; more below N = 1 000):\n"
    );
    println!(
        "| N | runs | Rust s/run | numpy s/run | Rust / numpy speed | Rust particle updates/s | Rust rmse m | numpy rmse m |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for n in [100, 1000, 10_000] {
        let runs = runs_at(n, runs);
        let peer = foxhunt_sim::perf::peer_timings(&[n], runs)?;
        let p = peer.first().ok_or("the numpy peer printed nothing")?;
        let r = foxhunt_sim::perf::rust_timing(n, runs)
            .ok_or_else(|| format!("{n} particles is not a compiled size"))?;
        let updates = (r.particles * 60) as f64 / r.seconds_per_run;
        println!(
            "| {} | {runs} | {:.3e} | {:.3e} | {:.1}x | {:.3e} | {:.2} | {:.2} |",
            p.particles,
            r.seconds_per_run,
            p.seconds_per_run,
            p.seconds_per_run / r.seconds_per_run,
            updates,
            r.rmse,
            p.rmse
        );
    }
    let Some((budget, limit)) = growth else {
        return Ok(());
    };
    let bar = indicatif::ProgressBar::new(
        (foxhunt_sim::perf::GROWTH_FILTERS.len() * GROWTH_SIZES.len()) as u64,
    );
    let rows = foxhunt_sim::perf::growth(budget, limit, |f, n| {
        bar.set_message(format!("{f} N={n}"));
        bar.inc(1);
    });
    bar.finish_and_clear();
    println!("\nStep time against N on aoa-afsa's bearings (one thread; time per step, then");
    println!("million particle updates per second):\n");
    let header: Vec<String> = GROWTH_SIZES.iter().map(|n| format!("N = {n}")).collect();
    println!("| filter | {} | exponent |", header.join(" | "));
    println!("|---|{}---:|", "---:|".repeat(GROWTH_SIZES.len()));
    for row in rows {
        let cells: Vec<String> = row
            .times
            .iter()
            .map(|(n, t)| match t {
                StepTime::Measured { seconds, .. } => format!(
                    "{} ({:.1})",
                    human_seconds(*seconds),
                    *n as f64 / seconds / 1e6
                ),
                StepTime::Skipped { predicted } => {
                    format!("not run (~{})", human_seconds(*predicted))
                }
                StepTime::Unsupported => "n/a (u16 fish index)".to_string(),
            })
            .collect();
        println!(
            "| {} | {} | {:.2} |",
            row.filter,
            cells.join(" | "),
            row.exponent
        );
    }
    Ok(())
}

/// Seconds in the unit that keeps 3 significant digits readable.
fn human_seconds(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.1} us", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line that names the problem; 1 = the input gave no result (clap exits 2 on
            // usage errors).
            eprintln!("foxhunt: {e}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Perf {
            runs,
            budget,
            limit,
            no_growth,
        } => perf(runs.max(1), (!no_growth).then_some((budget, limit))),
        Command::Locate {
            captures,
            method,
            sigma_deg,
            json,
            geojson,
            kml,
            svg,
            seed,
            baud,
            quiet_exit,
        } => {
            let maps = if captures.is_empty() && geojson.is_none() && kml.is_none() && svg.is_none()
            {
                let p = |ext: &str| Some(std::path::PathBuf::from(format!("foxhunt-sample.{ext}")));
                Maps {
                    geojson: p("geojson"),
                    kml: p("kml"),
                    svg: p("svg"),
                }
            } else {
                Maps { geojson, kml, svg }
            };
            match baud {
                Some(baud) => {
                    let [path] = captures.as_slice() else {
                        return Err("--baud reads one serial device: give exactly one path".into());
                    };
                    let o = foxhunt_sim::live::LiveOptions {
                        path: path.to_string_lossy().into_owned(),
                        baud,
                        quiet_exit: quiet_exit
                            .map(|s| std::time::Duration::from_secs_f32(s.max(0.0))),
                        method,
                        sigma_deg,
                        json,
                        seed,
                    };
                    let stdout = std::io::stdout();
                    let (report, solution, decoded) =
                        foxhunt_sim::live::run(&o, &mut stdout.lock())?;
                    finish_locate(&report, &solution, &decoded, json, &maps)
                }
                None => locate(&captures, method, sigma_deg, json, &maps, seed),
            }
        }
        Command::Track {
            capture,
            anchors,
            json,
            svg,
            seed,
        } => track(&capture, &anchors, json, svg.as_deref(), seed),
        Command::Frames { capture } => {
            let bytes = read_captures(std::slice::from_ref(&capture))?;
            let stdout = std::io::stdout();
            foxhunt_sim::frames::write_frames(&bytes, &mut stdout.lock())
                .map_err(|e| format!("cannot write: {e}"))
        }
        Command::Simulate {
            scenario,
            scenario_file,
            out,
            origin,
            run,
            wild,
            bias_deg,
            corrupt,
            drop,
        } => {
            let fraction = |name: &str, v: f32| {
                if (0.0..=1.0).contains(&v) {
                    Ok(v)
                } else {
                    Err(format!("--{name} is a share between 0 and 1, not {v}"))
                }
            };
            let options = foxhunt_sim::simulate::CaptureOptions {
                run,
                wild_fraction: wild.map(|w| fraction("wild", w)).transpose()?,
                bias_deg,
                corrupt_fraction: fraction("corrupt", corrupt)?,
                drop_fraction: fraction("drop", drop)?,
                ..Default::default()
            };
            let (file, origin) = (scenario_file.as_deref(), origin.as_deref());
            simulate(&scenario, file, &out, origin, options)
        }
        Command::Bench {
            scenario,
            scenario_file,
            runs,
            particles,
            json,
            markdown,
        } => {
            let names: Vec<&str> = NAMES
                .iter()
                .chain(tracking::NAMES.iter())
                .copied()
                .collect();
            let mut bearing: Vec<Scenario> = Vec::new();
            let mut tracks: Vec<Tracking> = Vec::new();
            match scenario_file {
                Some(path) => {
                    let text = std::fs::read_to_string(&path)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                    bearing.push(
                        Scenario::from_toml(&text)
                            .map_err(|e| format!("{}: {e}", path.display()))?,
                    );
                }
                None if scenario == "all" => {
                    bearing.extend(NAMES.iter().filter_map(|n| Scenario::named(n)));
                    tracks.extend(tracking::NAMES.iter().filter_map(|n| Tracking::named(n)));
                }
                None => match (Scenario::named(&scenario), Tracking::named(&scenario)) {
                    (Some(s), _) => bearing.push(s),
                    (None, Some(t)) => tracks.push(t),
                    (None, None) => {
                        return Err(format!(
                            "unknown scenario `{scenario}`; known: all, {}",
                            names.join(", ")
                        ));
                    }
                },
            }
            if let Some(n) = particles
                && !PARTICLE_COUNTS.contains(&n)
            {
                return Err(format!(
                    "{n} particles is not a compiled size; use one of {PARTICLE_COUNTS:?}"
                ));
            }
            for s in bearing.iter_mut() {
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
            for t in tracks.iter_mut() {
                if let Some(r) = runs {
                    t.runs = r.max(1);
                }
            }
            let progress =
                !json && !markdown && std::io::IsTerminal::is_terminal(&std::io::stderr());
            let mut rows: Vec<_> = bearing
                .iter()
                .flat_map(|s| bench(s, &Method::for_scenario(&s.name), progress))
                .collect();
            for t in &tracks {
                let counts = particles
                    .map(|n| vec![n])
                    .unwrap_or_else(|| t.particle_counts());
                rows.extend(tracking::bench(t, &counts, progress));
            }
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
                );
            } else if markdown {
                print!("{}", report::markdown(&rows));
            } else {
                for s in &bearing {
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
                for t in &tracks {
                    println!(
                        "{}: {} steps, {} runs, seed {}; bound = posterior CRB",
                        t.name, t.steps, t.runs, t.seed
                    );
                }
                print!("{}", report::table(&rows));
            }
            Ok(())
        }
    }
}
