//! `foxhunt perf`: speed against the numpy peer, and how each filter's cost grows with N.
//!
//! The peer is `benches/numpy_sir.py`: the same bootstrap SIR on the same scenario, written the
//! way users write it today (numpy, filterpy's `systematic_resample`). This module installs it
//! (numpy, scipy, filterpy from PyPI into `target/peer-venv`), runs it, runs the identical Rust
//! filter single-threaded in the same invocation, and prints the ratio. Timing is wall-clock
//! over whole runs; it is reported, never asserted.

use crate::montecarlo::pool;
use foxhunt_core::Bearing;
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{
    Filter, Gaussian, Gpf, ParticleSet, Resampling, Roughening, Sir, SirConfig, StaticEmitter,
    random,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const EMITTER: [f32; 2] = [1200.0, 800.0];
const SIGMA: f32 = 0.019_496; // sqrt(3.801e-4)

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

fn route() -> Vec<[f32; 2]> {
    let start = libm::atan2f(-EMITTER[1], -EMITTER[0]);
    (0..60)
        .map(|k| {
            let a = start + 2.0 * std::f32::consts::PI * k as f32 / 60.0;
            [EMITTER[0] + 300.0 * a.cos(), EMITTER[1] + 300.0 * a.sin()]
        })
        .collect()
}

/// The peer's algorithm in Rust: 1 m^2 jitter, Gaussian likelihood, systematic resampling when
/// ESS < N/2, initial cloud N(emitter, 50^2 I). Single thread.
fn rust_sir<const N: usize>(runs: usize) -> Timing {
    let vehicles = route();
    let config = SirConfig {
        resampling: Resampling::Systematic,
        ess_threshold: 0.5,
        roughening: Roughening::None,
    };
    let mut rng = XorShiftRng::seed_from_u64(1);
    let (mut sq, mut elapsed) = (0.0f64, 0.0f64);
    let mut cloud = Box::new(ParticleSet::<N, 2>::new());
    // Run 0 is an untimed warm-up, as on the numpy side.
    for run in 0..=runs {
        let bearings: Vec<Bearing> = vehicles
            .iter()
            .map(|v| Bearing {
                vehicle: *v,
                theta: wrap(predicted(&EMITTER, v) + SIGMA * random::normal(&mut rng)),
                sigma: SIGMA,
            })
            .collect();
        let t = Instant::now();
        let _ = cloud.draw_gaussian(&EMITTER, &[[2500.0, 0.0], [0.0, 2500.0]], &mut rng);
        let model = StaticEmitter { process_var: 1.0 };
        let mut f = Box::new(Sir::<_, _, N, 2>::new(model, Gaussian, config));
        let _ = f.initialise(&cloud.states, &mut rng);
        for b in &bearings {
            let _ = f.step(b, &mut rng);
        }
        let est = f.estimate().mean;
        if run > 0 {
            elapsed += t.elapsed().as_secs_f64();
            sq += ((est[0] - EMITTER[0]) as f64).powi(2) + ((est[1] - EMITTER[1]) as f64).powi(2);
        }
    }
    Timing {
        particles: N,
        runs,
        seconds_per_run: elapsed / runs as f64,
        rmse: (sq / runs as f64).sqrt(),
    }
}

/// Runs to time at `n` particles: at least `runs`, and below N = 1 000 proportionally more, so
/// that every row times at least as many particle updates as the N = 1 000 row (20 runs at
/// N = 100 are about a millisecond of Rust: too little to time against clock and frequency noise).
pub fn runs_at(n: usize, runs: usize) -> usize {
    runs.max(runs * 1000 / n.max(1))
}

/// Time the Rust SIR at `n` particles (a compiled size: 100, 1000, 10 000 or 100 000).
pub fn rust_timing(n: usize, runs: usize) -> Option<Timing> {
    // Run on the big-stack pool: a 100 000-particle filter is built on the stack before boxing.
    pool().install(|| match n {
        100 => Some(rust_sir::<100>(runs)),
        1000 => Some(rust_sir::<1000>(runs)),
        10_000 => Some(rust_sir::<10_000>(runs)),
        100_000 => Some(rust_sir::<100_000>(runs)),
        _ => None,
    })
}

/// The peer's virtual environment, made on first use.
fn peer_python(target: &Path) -> Result<PathBuf, String> {
    let venv = target.join("peer-venv");
    let python = venv.join("bin").join("python");
    if python.exists() {
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
                String::from_utf8_lossy(&out.stderr)
            ))
        }
    };
    run(Command::new("python3").args(["-m", "venv"]).arg(&venv))?;
    let pip = venv.join("bin").join("pip");
    // filterpy's resampling needs numpy and scipy, not its plotting dependency.
    run(Command::new(&pip).args(["install", "-q", "numpy", "scipy"]))?;
    run(Command::new(&pip).args(["install", "-q", "--no-deps", "filterpy"]))?;
    Ok(python)
}

/// Run the numpy peer at each particle count.
pub fn peer_timings(counts: &[usize], runs: usize) -> Result<Vec<Timing>, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = root.join("../target");
    let python = peer_python(&target)?;
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
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).map_err(|e| format!("peer output {l:?}: {e}")))
        .collect()
}

/// The filters of the growth table, on the bearing model (aoa-afsa's bearings).
pub const GROWTH_FILTERS: [&str; 7] = [
    "sir",
    "gpf",
    "fa-pf-imp",
    "pso-gpf",
    "gsa-gpf",
    "afsa-pf",
    "fa-pf",
];

/// Particle counts of the growth table (compiled sizes).
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
    /// Filter name.
    pub filter: &'static str,
    /// (N, time) pairs in ascending N.
    pub times: Vec<(usize, StepTime)>,
    /// Least-squares slope of log time against log N over the measured N >= 1 000 (at N = 100
    /// fixed per-step costs still show), or over every measured N when fewer reach 1 000.
    pub exponent: f64,
}

/// Step `filter` (started from aoa-afsa's bearing-pair cloud) over the scenario's bearings,
/// cyclically, until `budget` has passed (at least one step).
fn time_steps<const N: usize, F: Filter<2, Measurement = Bearing>>(
    make: impl FnOnce() -> F,
    budget: f64,
) -> StepTime {
    use foxhunt_core::fix::{init::initial_particles, intersection::MIN_CROSSING};
    let s = crate::scenario::Scenario::named("aoa-afsa").expect("aoa-afsa is built in");
    let mut rng = s.rng(0);
    let bearings = s.simulate(&mut rng);
    let mut cloud = Box::new(ParticleSet::<N, 2>::new());
    if initial_particles(&bearings, MIN_CROSSING, &mut cloud, &mut rng).is_err() {
        return StepTime::Skipped { predicted: 0.0 };
    }
    let mut f = Box::new(make());
    let _ = f.initialise(&cloud.states, &mut rng);
    let start = Instant::now();
    let mut steps = 0;
    while steps == 0 || start.elapsed().as_secs_f64() < budget {
        let _ = std::hint::black_box(f.step(&bearings[steps % bearings.len()], &mut rng));
        steps += 1;
    }
    StepTime::Measured {
        seconds: start.elapsed().as_secs_f64() / steps as f64,
        steps,
    }
}

/// Time one filter at one compiled N.
fn step_time<const N: usize>(filter: &str, budget: f64) -> Option<StepTime> {
    use foxhunt_core::{Afsa, Firefly, Gsa, ImprovedFirefly, Pso};
    let model = StaticEmitter { process_var: 0.0 };
    let config = SirConfig::default();
    Some(match filter {
        "sir" => time_steps::<N, _>(|| Sir::<_, _, N, 2>::new(model, Gaussian, config), budget),
        "gpf" => time_steps::<N, _>(|| Gpf::<_, _, N, 2>::new(model, Gaussian), budget),
        "afsa-pf" => time_steps::<N, _>(
            || Sir::<_, _, N, 2, _>::with_swarm(model, Gaussian, config, Afsa::default()),
            budget,
        ),
        "fa-pf" => time_steps::<N, _>(
            || Sir::<_, _, N, 2, _>::with_swarm(model, Gaussian, config, Firefly::default()),
            budget,
        ),
        "fa-pf-imp" => time_steps::<N, _>(
            || {
                Sir::<_, _, N, 2, _>::with_swarm(
                    model,
                    Gaussian,
                    config,
                    ImprovedFirefly::default(),
                )
            },
            budget,
        ),
        "pso-gpf" => time_steps::<N, _>(
            || Gpf::<_, _, N, 2, _>::with_swarm(model, Gaussian, Pso::default()),
            budget,
        ),
        "gsa-gpf" => time_steps::<N, _>(
            || Gpf::<_, _, N, 2, _>::with_swarm(model, Gaussian, Gsa::default()),
            budget,
        ),
        _ => return None,
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
pub fn growth(budget: f64, limit: f64, mut progress: impl FnMut(&str, usize)) -> Vec<GrowthRow> {
    GROWTH_FILTERS
        .iter()
        .map(|&filter| {
            let mut times: Vec<(usize, StepTime)> = Vec::new();
            for &n in &GROWTH_SIZES {
                if filter == "afsa-pf" && n > u16::MAX as usize {
                    times.push((n, StepTime::Unsupported));
                    continue;
                }
                let predicted = predict(&times, n);
                if predicted > limit {
                    times.push((n, StepTime::Skipped { predicted }));
                    continue;
                }
                progress(filter, n);
                // Big filters are built on the stack before boxing: run on the big-stack pool.
                let t = pool().install(|| match n {
                    100 => step_time::<100>(filter, budget),
                    1000 => step_time::<1000>(filter, budget),
                    10_000 => step_time::<10_000>(filter, budget),
                    _ => step_time::<100_000>(filter, budget),
                });
                if let Some(t) = t {
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
