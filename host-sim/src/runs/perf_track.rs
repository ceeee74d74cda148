//! `foxhunt perf --track`: how fast the moving-emitter tracker runs against real time, with
//! its peak memory (docs/src/speed.md, "Tracking a moving emitter").
//!
//! The load the users were promised: four fixed stations each reporting a bearing ten times a
//! second, the default tracker (`sir-robust`, four offsets Rao-Blackwellised: 13 components)
//! at 1 000 and 10 000 particles, on `move-fixed-turning` (the drone crossing the 8 km city
//! with a full circle, 600 s) simulated at 10 Hz. Each row is one whole run of the tracker as
//! `foxhunt track` runs it (first cloud, 6 000 updates of four bearings, every point kept),
//! on one thread, its time set against the 600 s it covers; beside it, in the same
//! invocation, the plain SIR's step on one bearing at the same N (the numpy table's filter,
//! [`crate::runs::perf::rust_timing`]), so the ratio of the two survives a change of machine
//! better than either time. Times are the thread's own CPU time (the kernel's count in
//! /proc/thread-self/schedstat, nanoseconds): on a machine shared with other work the wall
//! clock says how busy the machine was, not how fast the tracker is; the wall time is
//! printed beside it. The run's rmse and coverage show the timed tracker still tracks.
//! Peak memory is the process's resident high-water mark after the row (`--track` runs alone,
//! rows in growing N, so it is that row's peak) and the filter's own state, N x (D + 2) floats.

use crate::runs::moving::MovingScenario;
use crate::runs::moving::bench::judge;
use crate::runs::perf::rust_timing;
use crate::track::moving::{STATE_SIZES, track};
use std::fmt::Write;
use std::time::Instant;

/// The scenario timed.
pub const SCENARIO: &str = "move-fixed-turning";
/// Bearings a second from each station.
pub const RATE_HZ: f32 = 10.0;
/// Particle counts timed, in growing order (the memory column relies on it).
pub const COUNTS: [usize; 2] = [1000, 10_000];
/// Runs of the plain SIR's 60 steps timed per row (enough for a tenth of a second at N =
/// 10 000: [`crate::runs::perf::runs_at`] scales it up below).
const SIR_RUNS: usize = 20;

/// One timed row.
#[derive(Debug, Clone)]
pub struct TrackTiming {
    /// Particles.
    pub particles: usize,
    /// State components (the compiled size).
    pub dims: usize,
    /// Updates stepped (each with one bearing from every station).
    pub updates: usize,
    /// Bearings in the run.
    pub bearings: usize,
    /// Seconds of the run's data.
    pub covered_s: f64,
    /// CPU seconds of the tracker's run.
    pub seconds: f64,
    /// Wall seconds of the tracker's run.
    pub wall: f64,
    /// CPU seconds of one plain SIR step on one bearing at the same N.
    pub sir_step: f64,
    /// rmse of the run after its warm-up, metres.
    pub rmse: f64,
    /// Share of the updates after the warm-up whose 95 % ellipse held the truth.
    pub coverage: f64,
    /// The process's peak resident memory after the row, bytes (0 where unknown).
    pub peak_bytes: u64,
    /// The filter's particle state, bytes.
    pub state_bytes: usize,
}

impl TrackTiming {
    /// Seconds per update.
    pub fn step(&self) -> f64 {
        self.seconds / self.updates as f64
    }

    /// Times faster than real time.
    pub fn real_time(&self) -> f64 {
        self.covered_s / self.seconds
    }
}

/// CPU seconds this thread has run (0 where the system does not say).
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0.0, |ns| ns as f64 * 1e-9)
}

/// `f`'s result and the CPU seconds it took, on the big-stack pool's thread that runs it
/// (the tracker and the SIR run there: a nested `install` runs in place).
fn cpu_timed<T: Send>(f: impl FnOnce() -> T + Send) -> (T, f64) {
    crate::estimate::pool().install(|| {
        let start = thread_cpu_s();
        let out = f();
        (out, thread_cpu_s() - start)
    })
}

/// Time the tracker at every N of [`COUNTS`], one thread, `progress` told before each row.
pub fn measure(mut progress: impl FnMut(usize)) -> Result<Vec<TrackTiming>, String> {
    let mut s = MovingScenario::named(SCENARIO).ok_or("the scenario is built in")?;
    s.rate_hz = RATE_HZ;
    let run = s.simulate(0);
    let bearings = run.updates.iter().map(|u| u.epoch.bearings().len()).sum();
    let mut rows = Vec::new();
    for n in COUNTS {
        progress(n);
        let mut settings = s.settings();
        settings.particles = n;
        let dims = settings.layout.dims();
        // The compiled state size that holds them (13 for four offsets).
        let size = STATE_SIZES
            .iter()
            .copied()
            .find(|d| *d >= dims)
            .unwrap_or(dims);
        // An untimed warm-up over the first tenth, then the whole run timed.
        track(&run.updates[..run.updates.len() / 10], &settings).map_err(|e| e.to_string())?;
        let t = Instant::now();
        let (tracked, seconds) = cpu_timed(|| track(&run.updates, &settings));
        let wall = t.elapsed().as_secs_f64();
        let tracked = tracked.map_err(|e| e.to_string())?;
        let f = judge(&run, &tracked, s.warmup_s);
        let k = f.errors.len().max(1) as f64;
        let sir_runs = crate::runs::perf::runs_at(n, SIR_RUNS);
        let (sir, sir_cpu) = cpu_timed(|| rust_timing(n, sir_runs));
        sir.map_err(|e| e.to_string())?;
        rows.push(TrackTiming {
            particles: n,
            dims: size,
            updates: run.updates.len(),
            bearings,
            covered_s: f64::from(s.duration_s),
            seconds,
            wall,
            // Its runs and the untimed warm-up, 60 bearings each, one step a bearing (the
            // draw of each run's cloud and bearings, about one step's cost, counted too).
            sir_step: sir_cpu / ((sir_runs + 1) * 60) as f64,
            rmse: (f.errors.iter().map(|e| f64::from(*e).powi(2)).sum::<f64>() / k).sqrt(),
            coverage: f.covered.iter().filter(|c| **c).count() as f64 / k,
            peak_bytes: crate::outputs::terminal::peak_bytes(),
            // States, log-weights and weights.
            state_bytes: n * (size + 2) * 4,
        });
    }
    Ok(rows)
}

/// The table (Markdown).
pub fn table(rows: &[TrackTiming]) -> String {
    let mut out = format!(
        "The tracker (sir-robust) on {SCENARIO} with four fixed stations at {RATE_HZ} Hz each \
         (one thread, CPU time):\n\n| N | D | updates | bearings | CPU s | wall s | \
         ms/update | x real time | SIR step ms | update / SIR step | rmse m | coverage | \
         peak MB | state MB |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.1}x | {:.3} | {:.1} | {:.1} | \
             {:.3} | {:.1} | {:.2} |",
            r.particles,
            r.dims,
            r.updates,
            r.bearings,
            r.seconds,
            r.wall,
            1e3 * r.step(),
            r.real_time(),
            1e3 * r.sir_step,
            r.step() / r.sir_step,
            r.rmse,
            r.coverage,
            r.peak_bytes as f64 / 1e6,
            r.state_bytes as f64 / 1e6,
        );
    }
    out
}
