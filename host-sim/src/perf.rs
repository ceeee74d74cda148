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
    Filter, Gaussian, ParticleSet, Resampling, Roughening, Sir, SirConfig, StaticEmitter, random,
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
    for _ in 0..runs {
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
        elapsed += t.elapsed().as_secs_f64();
        sq += ((est[0] - EMITTER[0]) as f64).powi(2) + ((est[1] - EMITTER[1]) as f64).powi(2);
    }
    Timing {
        particles: N,
        runs,
        seconds_per_run: elapsed / runs as f64,
        rmse: (sq / runs as f64).sqrt(),
    }
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
