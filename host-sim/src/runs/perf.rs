//! `foxhunt perf`: speed against the numpy peer, how each filter's cost grows with N, and how
//! `locate` scales with the size of a capture (time and peak memory).
//!
//! The peer is `benches/numpy_sir.py`: the registry's `sir-seed` on the same scenario, written
//! the way users write it today (numpy, filterpy's `systematic_resample`). This module installs
//! it (numpy, scipy, filterpy from PyPI into `target/peer-venv`, at the versions pinned in
//! `benches/peer-requirements.txt`), runs it, runs the identical
//! Rust filter single-threaded in the same invocation, and prints the ratio. Timing is
//! wall-clock over whole runs; it is reported, never asserted.

use crate::estimate::Steps;
use crate::estimate::pool;
use crate::outputs::tables::human_seconds;
use foxhunt_core::canonical::{AOA_EMITTER, AOA_SIGMA};
use foxhunt_core::estimator::with_bearing_filter;
use foxhunt_core::fix::{init::initial_particles, intersection::MIN_CROSSING};
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{
    Bearing, Error, Estimate, Filter, Method, ParticleSet, WithFilter, random, with_particles,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Deserialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One speed measurement.
#[derive(Debug, Clone, Deserialize)]
pub struct Timing {
    /// Particles.
    pub particles: usize,
    /// Runs timed.
    pub runs: usize,
    /// Mean seconds per whole run (60 bearings).
    pub seconds_per_run: f64,
    /// rmse of the final estimate over the runs (shows both sides run the same filter).
    pub rmse: f64,
}

/// The peer's jitter, m^2 per step.
const PEER_JITTER: f32 = 1.0;

/// aoa-afsa's route.
fn route() -> Vec<[f32; 2]> {
    (0..60)
        .map(|k| foxhunt_core::canonical::loop300(AOA_EMITTER, k))
        .collect()
}

/// The peer's algorithm in Rust: `sir-seed` (1 m^2 jitter, Gaussian likelihood, systematic
/// resampling every step) from the initial cloud N(emitter, 50^2 I). Single thread.
fn rust_sir<const N: usize>(runs: usize) -> Result<Timing, Error> {
    let vehicles = route();
    let mut rng = XorShiftRng::seed_from_u64(1);
    let (mut sq, mut elapsed) = (0.0f64, 0.0f64);
    let mut cloud = Box::new(ParticleSet::<N, 2>::new());
    // Run 0 is an untimed warm-up, as on the numpy side.
    for run in 0..=runs {
        let bearings: Vec<Bearing> = vehicles
            .iter()
            .map(|v| Bearing {
                vehicle: *v,
                theta: wrap(predicted(&AOA_EMITTER, v) + AOA_SIGMA * random::normal(&mut rng)),
                sigma: AOA_SIGMA,
            })
            .collect();
        let t = Instant::now();
        cloud.draw_gaussian(&AOA_EMITTER, &[[2500.0, 0.0], [0.0, 2500.0]], &mut rng)?;
        let steps = Steps {
            cloud: &cloud.states,
            measurements: &bearings,
            rng: &mut rng,
            each: |_, _: &Estimate<2>| {},
            keep_cloud: false,
        };
        let est = with_bearing_filter::<N, _>(Method::SirSeed, PEER_JITTER, steps)??
            .estimate
            .mean;
        if run > 0 {
            elapsed += t.elapsed().as_secs_f64();
            sq += f64::from(est[0] - AOA_EMITTER[0]).powi(2)
                + f64::from(est[1] - AOA_EMITTER[1]).powi(2);
        }
    }
    Ok(Timing {
        particles: N,
        runs,
        seconds_per_run: elapsed / runs as f64,
        rmse: (sq / runs as f64).sqrt(),
    })
}

/// Runs to time at `n` particles: at least `runs`, and below N = 1 000 proportionally more, so
/// that every row times at least as many particle updates as the N = 1 000 row (20 runs at
/// N = 100 are about a millisecond of Rust: too little to time against clock and frequency noise).
pub fn runs_at(n: usize, runs: usize) -> usize {
    runs.max(runs * 1000 / n.max(1))
}

/// Time the Rust SIR at `n` particles (a compiled count).
pub fn rust_timing(n: usize, runs: usize) -> Result<Timing, Error> {
    // On the big-stack pool: a 100 000-particle filter is built on the stack.
    pool().install(|| with_particles!(n, N => rust_sir::<N>(runs)))
}

/// The peer's virtual environment, made on first use with the versions pinned in
/// `benches/peer-requirements.txt` (a venv made from another pin is made again).
fn peer_python(target: &Path) -> Result<PathBuf, String> {
    let pins = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peer-requirements.txt");
    let wanted = std::fs::read_to_string(&pins)
        .map_err(|e| format!("cannot read {}: {e}", pins.display()))?;
    let venv = target.join("peer-venv");
    let stamp = venv.join("foxhunt-pins.txt");
    let python = venv.join("bin").join("python");
    if python.exists() && std::fs::read_to_string(&stamp).is_ok_and(|s| s == wanted) {
        return Ok(python);
    }
    let run = |cmd: &mut Command| -> Result<(), String> {
        let out = cmd
            .output()
            .map_err(|e| format!("cannot run {cmd:?}: {e}"))?;
        if out.status.success() {
            Ok(())
        } else {
            Err(format!(
                "{cmd:?} failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ))
        }
    };
    run(Command::new("python3")
        .args(["-m", "venv", "--clear"])
        .arg(&venv))?;
    let pip = venv.join("bin").join("pip");
    // --no-deps: filterpy's resampling needs numpy and scipy (pinned beside it), not its
    // plotting dependency.
    run(Command::new(&pip)
        .args(["install", "-q", "--no-deps", "-r"])
        .arg(&pins))?;
    std::fs::write(&stamp, wanted).map_err(|e| format!("cannot write {}: {e}", stamp.display()))?;
    Ok(python)
}

fn target_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target")
}

/// Run the numpy peer at each particle count.
pub fn peer_timings(counts: &[usize], runs: usize) -> Result<Vec<Timing>, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = peer_python(&target_dir())?;
    let out = Command::new(python)
        .arg(root.join("benches/numpy_sir.py"))
        .arg("--runs")
        .arg(runs.to_string())
        .args(counts.iter().map(|n| n.to_string()))
        .output()
        .map_err(|e| format!("cannot run the numpy peer: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "numpy peer failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).map_err(|e| format!("peer output {l:?}: {e}")))
        .collect()
}

/// The Rust-against-numpy table (Markdown), at N = 100, 1 000 and 10 000.
pub fn numpy_table(runs: usize) -> Result<String, String> {
    let mut out = format!(
        "Bootstrap SIR (sir-seed) on aoa-afsa (60 bearings), one thread, the same runs on both \
         sides (at least {runs}; more below N = 1 000):\n\n\
         | N | runs | Rust s/run | numpy s/run | Rust / numpy speed | Rust particle updates/s | Rust rmse m | numpy rmse m |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for n in [100, 1000, 10_000] {
        let runs = runs_at(n, runs);
        let peer = peer_timings(&[n], runs)?;
        let p = peer.first().ok_or("the numpy peer printed nothing")?;
        let r = rust_timing(n, runs).map_err(|e| format!("Rust SIR at N = {n}: {e}"))?;
        let updates = (r.particles * 60) as f64 / r.seconds_per_run;
        let _ = writeln!(
            out,
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
    Ok(out)
}

/// The filters of the growth table, on the bearing model (aoa-afsa's bearings).
pub const GROWTH_FILTERS: [Method; 7] = [
    Method::Sir,
    Method::Gpf,
    Method::FaPfImp,
    Method::PsoGpf,
    Method::GsaGpf,
    Method::AfsaPf,
    Method::FaPf,
];

/// Particle counts of the growth table (compiled counts).
pub const GROWTH_SIZES: [usize; 4] = [100, 1000, 10_000, 100_000];

/// Mean seconds per step of one filter at one N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepTime {
    /// Measured over `steps` steps.
    Measured {
        /// Mean seconds per step.
        seconds: f64,
        /// Steps timed.
        steps: usize,
    },
    /// Not run: the exponent so far predicts more than the time limit per step.
    Skipped {
        /// Predicted seconds per step.
        predicted: f64,
    },
    /// The filter has no such size (AFSA-PF indexes its fish by u16: at most 65 535).
    Unsupported,
}

/// One filter's row: step time at each N and the fitted exponent of time ~ N^k.
#[derive(Debug, Clone)]
pub struct GrowthRow {
    /// The filter.
    pub filter: Method,
    /// (N, time) pairs in ascending N.
    pub times: Vec<(usize, StepTime)>,
    /// Least-squares slope of log time against log N over the measured N >= 1 000 (at N = 100
    /// fixed per-step costs still show), or over every measured N when fewer reach 1 000.
    pub exponent: f64,
}

/// The visitor that steps a started filter over the bearings, cyclically, until `budget`
/// seconds have passed (at least one step).
struct TimeSteps<'a> {
    cloud: &'a [[f32; 2]],
    bearings: &'a [Bearing],
    rng: &'a mut XorShiftRng,
    budget: f64,
}

impl WithFilter<2, Bearing> for TimeSteps<'_> {
    type Output = Result<StepTime, Error>;
    fn visit<F: Filter<2, Measurement = Bearing>>(self, f: &mut F) -> Self::Output {
        f.initialise(self.cloud, self.rng)?;
        let start = Instant::now();
        let mut steps = 0;
        while steps == 0 || start.elapsed().as_secs_f64() < self.budget {
            let z = &self.bearings[steps % self.bearings.len()];
            let _ = std::hint::black_box(f.step(z, self.rng));
            steps += 1;
        }
        Ok(StepTime::Measured {
            seconds: start.elapsed().as_secs_f64() / steps as f64,
            steps,
        })
    }
}

/// Time one filter at `n` particles, started from aoa-afsa's bearing-pair cloud.
fn step_time(filter: Method, n: usize, budget: f64) -> Result<StepTime, Error> {
    let s = crate::runs::scenario::Scenario::named("aoa-afsa").ok_or(Error::Unsupported)?;
    let d = s.drive().ok_or(Error::Unsupported)?;
    let mut rng = s.rng(0);
    let bearings = d.simulate(&mut rng);
    pool().install(|| {
        with_particles!(n, N => {
            let mut cloud = Box::new(ParticleSet::<N, 2>::new());
            initial_particles(&bearings, MIN_CROSSING, &mut cloud, &mut rng)?;
            let t = TimeSteps { cloud: &cloud.states, bearings: &bearings, rng: &mut rng, budget };
            with_bearing_filter::<N, _>(filter, 0.0, t)?
        })
    })
}

/// Slope of log t against log N (least squares) over measured points with N >= 1 000, or
/// over all measured points when fewer than two are that large.
fn exponent(times: &[(usize, StepTime)]) -> f64 {
    let points = |min: usize| -> Vec<(f64, f64)> {
        times
            .iter()
            .filter_map(|(n, t)| match t {
                StepTime::Measured { seconds, .. } if *n >= min => {
                    Some(((*n as f64).ln(), seconds.ln()))
                }
                _ => None,
            })
            .collect()
    };
    let mut pts = points(1000);
    if pts.len() < 2 {
        pts = points(0);
    }
    if pts.len() < 2 {
        return f64::NAN;
    }
    let k = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / k,
        pts.iter().map(|p| p.1).sum::<f64>() / k,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

/// Time every filter of [`GROWTH_FILTERS`] at every N of [`GROWTH_SIZES`], each cell for about
/// `budget` seconds, single thread. A cell whose time, extrapolated from the previous two,
/// exceeds `limit` seconds per step is skipped (and the larger N after it).
pub fn growth(budget: f64, limit: f64, mut progress: impl FnMut(Method, usize)) -> Vec<GrowthRow> {
    GROWTH_FILTERS
        .iter()
        .map(|&filter| {
            let mut times: Vec<(usize, StepTime)> = Vec::new();
            for &n in &GROWTH_SIZES {
                if crate::runs::montecarlo::not_run(filter, n).is_some() && filter == Method::AfsaPf
                {
                    times.push((n, StepTime::Unsupported));
                    continue;
                }
                let predicted = predict(&times, n);
                if predicted > limit {
                    times.push((n, StepTime::Skipped { predicted }));
                    continue;
                }
                progress(filter, n);
                if let Ok(t) = step_time(filter, n, budget) {
                    times.push((n, t));
                }
            }
            let exponent = exponent(&times);
            GrowthRow {
                filter,
                times,
                exponent,
            }
        })
        .collect()
}

/// Time per step at `n` extrapolated from the last two entries (measured or predicted), or 0
/// when there are fewer than two.
fn predict(times: &[(usize, StepTime)], n: usize) -> f64 {
    let secs = |t: &StepTime| match t {
        StepTime::Measured { seconds, .. } => *seconds,
        StepTime::Skipped { predicted } => *predicted,
        StepTime::Unsupported => f64::NAN,
    };
    match times {
        [.., (n0, t0), (n1, t1)] => {
            let (a, b) = (secs(t0), secs(t1));
            let k = ((b / a).ln() / (*n1 as f64 / *n0 as f64).ln()).max(1.0);
            b * (n as f64 / *n1 as f64).powf(k)
        }
        _ => 0.0,
    }
}

/// The growth table (Markdown).
pub fn growth_table(rows: &[GrowthRow]) -> String {
    let mut out = String::from(
        "Step time against N on aoa-afsa's bearings (one thread; time per step, then million \
         particle updates per second):\n\n",
    );
    let header: Vec<String> = GROWTH_SIZES.iter().map(|n| format!("N = {n}")).collect();
    let _ = writeln!(out, "| filter | {} | exponent |", header.join(" | "));
    let _ = writeln!(out, "|---|{}---:|", "---:|".repeat(GROWTH_SIZES.len()));
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
        let _ = writeln!(
            out,
            "| {} | {} | {:.2} |",
            row.filter,
            cells.join(" | "),
            row.exponent
        );
    }
    out
}

/// One `locate` run on a large capture: its size, bearings, seconds and peak memory.
#[derive(Debug, Clone)]
pub struct ScaleRow {
    /// What the capture is.
    pub what: String,
    /// Its size, bytes.
    pub bytes: u64,
    /// Bearings located.
    pub bearings: u64,
    /// Wall seconds of the whole command.
    pub seconds: f64,
    /// Peak resident memory of the command, bytes.
    pub peak_bytes: u64,
}

/// Write `path` with an L-shaped drive of `seconds` at 10 m/s and `rate` bearings a second,
/// unless it already holds that drive; its size.
fn scale_capture(path: &Path, seconds: usize, rate: usize) -> Result<u64, String> {
    use crate::runs::simulate::{CaptureOptions, drive_capture};
    let mut s =
        crate::runs::scenario::Scenario::named("aoa-drive").ok_or("aoa-drive is built in")?;
    let crate::runs::scenario::ScenarioModel::Bearing(d) = &mut s.model else {
        return Err("aoa-drive is a drive".into());
    };
    // An L-shaped drive at 10 m/s, one route point (and bearing) per 1/rate s.
    let points = seconds * rate;
    let step = 10.0 / rate as f32;
    d.route = (0..points)
        .map(|k| {
            let t = k as f32 * step;
            let leg = 0.5 * points as f32 * step;
            if t < leg { [t, 0.0] } else { [leg, t - leg] }
        })
        .collect();
    d.emitter = [3000.0, 2000.0];
    let options = CaptureOptions {
        interval_ms: (1000 / rate) as u32,
        ..CaptureOptions::default()
    };
    let one = drive_capture(&s, &options)?;
    let size = one.len() as u64;
    if std::fs::metadata(path).is_ok_and(|m| m.len() == size) {
        return Ok(size);
    }
    let mut f = std::io::BufWriter::new(
        std::fs::File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?,
    );
    std::io::Write::write_all(&mut f, &one)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    std::io::Write::flush(&mut f).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(size)
}

/// Time `foxhunt locate --stats` on `path` as a child process (one thread), reading its
/// own report of bearings and peak memory.
fn time_locate(path: &Path) -> Result<(u64, f64, u64), String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find the command: {e}"))?;
    let t = Instant::now();
    let out = Command::new(exe)
        .env("RAYON_NUM_THREADS", "1")
        .arg("locate")
        .arg(path)
        .args(["--json", "--stats"])
        .output()
        .map_err(|e| format!("cannot run locate: {e}"))?;
    let seconds = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    let stats = err
        .lines()
        .find_map(|l| l.strip_prefix("stats: "))
        .ok_or_else(|| format!("locate printed no stats: {}", err.trim()))?;
    let field = |key: &str| -> Option<u64> {
        stats
            .split(", ")
            .find_map(|kv| kv.strip_prefix(key))
            .and_then(|v| v.trim().parse().ok())
    };
    Ok((
        field("bearings ").unwrap_or(0),
        seconds,
        field("peak_bytes ").unwrap_or(0),
    ))
}

/// `locate` on large captures: a 1-hour drive at 20 bearings a second, and one of 14.5 hours
/// (about 200 MB). The captures are written once under `target/`.
pub fn scale() -> Result<Vec<ScaleRow>, String> {
    let dir = target_dir().join("scale");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut rows = Vec::new();
    for (what, file, seconds) in [
        ("1-hour drive, 20 bearings/s", "hour-20hz.nmea", 3600),
        (
            "14.5-hour drive, 20 bearings/s (about 200 MB)",
            "long-20hz.nmea",
            52_200,
        ),
    ] {
        let path = dir.join(file);
        let bytes = scale_capture(&path, seconds, 20)?;
        let (bearings, seconds, peak_bytes) = time_locate(&path)?;
        rows.push(ScaleRow {
            what: what.to_string(),
            bytes,
            bearings,
            seconds,
            peak_bytes,
        });
    }
    Ok(rows)
}

/// The scale table (Markdown).
pub fn scale_table(rows: &[ScaleRow]) -> String {
    let mut out = String::from(
        "`foxhunt locate --json` on large captures (one thread, the whole command):\n\n\
         | capture | size | bearings | time | peak memory |\n|---|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {:.1} MB | {} | {:.2} s | {:.1} MB |",
            r.what,
            r.bytes as f64 / 1e6,
            r.bearings,
            r.seconds,
            r.peak_bytes as f64 / 1e6
        );
    }
    out
}
