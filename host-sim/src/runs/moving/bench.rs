//! The moving scenarios' table: every tracking method over seeded Monte Carlo runs, against
//! the posterior Cramér-Rao bound.
//!
//! Figures, over the runs and the updates after the warm-up (docs/src/tracking.md):
//! `rmse` = sqrt(mean |x_hat - x|^2) of the position; `crlb` = the PCRB given the true motion
//! ([`foxhunt_core::track::bound`]), sqrt(mean tr P_pos) over the same updates with the
//! information averaged over the runs' own measurements; `coverage` = the share of updates
//! whose 95 % ellipse holds the truth (0.95 if honest); the note adds the median and 90th
//! percentile error, how often P(moving) > 0.5 was right, and for the default method its
//! smoothed figures.

use super::triangulate::triangulate;
use super::{MovingRun, MovingScenario};
use crate::estimate::Priors;
use crate::estimate::pool;
use crate::outputs::tables::Row;
use crate::runs::montecarlo::Progress;
use crate::track::direction::Directions;
use crate::track::moving::{
    DEFAULT_METHOD, K, PARTICLES, STATE_SIZES, Settings, TRACK_METHODS, TRACK_PARTICLES,
    TrackPoint, TrackRun, track,
};
use crate::track::noise::{Unstated, track_estimating};
use foxhunt_core::track::MODE;
use foxhunt_core::track::bound::{estimated, information, position_rmse, prior, step, transition};
use foxhunt_core::{Error, Method};
use rayon::prelude::*;

/// Particles of the swarm rows: their moves cost tens to hundreds of likelihoods per particle
/// per update (AFSA's up to 50 tries, the firefly's O(N^2) pairs), so they run at N = 200
/// over [`SWARM_RUNS`] runs, beside the default SIR at the same N.
pub const SWARM_PARTICLES: usize = 200;
/// Runs of the swarm rows.
pub const SWARM_RUNS: usize = 20;

/// What one run gave: per counted update, the error, whether the ellipse held the truth and
/// whether P(moving) was on the right side of 1/2; the smoothed errors and coverage.
#[derive(Debug, Clone, Default)]
pub struct RunFigures {
    /// Position errors, metres.
    pub errors: Vec<f32>,
    /// Whether each 95 % ellipse held the truth.
    pub covered: Vec<bool>,
    /// Whether each P(moving) said what the emitter did.
    pub mode_right: Vec<bool>,
    /// Smoothed errors and coverage (empty unless smoothed).
    pub smoothed: Vec<(f32, bool)>,
    /// Seconds the tracker took.
    pub seconds: f64,
    /// Likelihood evaluations.
    pub evaluations: u64,
}

/// The figures of one tracked run against its truth, from `warmup` seconds on.
pub fn judge(run: &MovingRun, t: &TrackRun, warmup: f32) -> RunFigures {
    let mut f = RunFigures::default();
    let count = |p: &TrackPoint| p.t_s >= warmup;
    for (p, (x, _, moving)) in t.points.iter().zip(&run.truth) {
        if !count(p) {
            continue;
        }
        f.errors
            .push((p.position[0] - x[0]).hypot(p.position[1] - x[1]));
        f.covered.push(p.covers(*x));
        f.mode_right.push((p.p_moving > 0.5) == *moving);
    }
    for (p, (x, _, _)) in t.smoothed.iter().zip(&run.truth) {
        if count(p) {
            let e = (p.position[0] - x[0]).hypot(p.position[1] - x[1]);
            f.smoothed.push((e, p.covers(*x)));
        }
    }
    f.evaluations = t.evaluations;
    f
}

/// One run of `method` with `particles` on scenario `s`.
pub fn one(
    s: &MovingScenario,
    method: Method,
    particles: usize,
    smooth: bool,
    run: usize,
) -> Result<RunFigures, Error> {
    let mut sim = s.simulate(run);
    told_directions(&mut sim);
    let mut settings = s.settings();
    settings.method = method;
    settings.particles = particles;
    settings.smooth = smooth;
    settings.seed = run as u64 + 1;
    let t0 = std::time::Instant::now();
    // Told a noise of the records' and nothing else, the tracker estimates each unit's, as
    // `track` does with no stations file.
    let unstated = vec![Unstated::Everything; s.stations.len()];
    let tracked = match s.told_sigma {
        Some(_) => track_estimating(&sim.updates, &settings, &unstated)?.0,
        None => track(&sim.updates, &settings)?,
    };
    let seconds = t0.elapsed().as_secs_f64();
    let mut f = judge(&sim, &tracked, s.warmup_s);
    f.seconds = seconds;
    Ok(f)
}

/// Take each station's told direction-dependent error out of the run's bearings, as `track`
/// does with a stations file's table ([`Directions`]).
fn told_directions(sim: &mut MovingRun) {
    if sim.tables.iter().all(Option::is_none) {
        return;
    }
    let priors = Priors {
        direction: sim.tables.iter().map(|t| t.map(|p| (p, None))).collect(),
        ..Priors::default()
    };
    let mut directions = Directions::default();
    for u in sim.updates.iter_mut() {
        for o in u.epoch.bearings_mut() {
            directions.correct(o, &priors);
        }
    }
}

/// The PCRB of scenario `s` given its true motion: sqrt(mean over the updates after the
/// warm-up of tr P_pos), the information averaged over the measurements of up to 20 runs.
pub fn pcrb(s: &MovingScenario) -> Option<f64> {
    bound(s).map(|b| b.rmse)
}

/// The PCRB of a scenario: its time-averaged position figure and, at the last update, the
/// bound's sd of each parameter ([`Layout::means`](foxhunt_core::track::Layout::means) order).
#[derive(Debug, Clone, PartialEq)]
pub struct Bound {
    /// sqrt(mean tr P_pos) over the updates after the warm-up, metres.
    pub rmse: f64,
    /// Each parameter's bound at the end (offsets in radians).
    pub parameters: Vec<f64>,
}

/// [`pcrb`] with the parameters' bounds.
pub fn bound(s: &MovingScenario) -> Option<Bound> {
    // The bound of the noise the bearings have, whatever the trackers are told.
    let truth = MovingScenario {
        told_sigma: None,
        ..s.clone()
    };
    let s = &truth;
    let settings = s.settings();
    let used = settings.layout.dims();
    let size = *STATE_SIZES.iter().find(|d| **d >= used)?;
    match size {
        7 => pcrb_with::<7>(s, &settings),
        10 => pcrb_with::<10>(s, &settings),
        13 => pcrb_with::<13>(s, &settings),
        18 => pcrb_with::<18>(s, &settings),
        _ => None,
    }
}

fn pcrb_with<const D: usize>(s: &MovingScenario, settings: &Settings) -> Option<Bound> {
    let model = settings.mover();
    let mut vars = vec![0.0f32; D];
    let prior_of = foxhunt_core::track::init::Prior {
        moving: settings.moving,
        speed_sd: settings.motion.start_speed_sd,
        offsets: &settings.offsets,
        power_sd: settings.power_sd,
        exponent_sd: settings.exponent_sd,
    };
    prior_of.parameter_vars(&settings.layout, &mut vars);
    let est = estimated::<D, K>(&model, &vars);
    let runs: Vec<MovingRun> = (0..s.runs.min(20)).map(|r| s.simulate(r)).collect();
    let first = runs.first()?;
    // The prior: the first update's position known to a kilometre, the start speed's sd.
    let speed = settings.motion.start_speed_sd;
    let mut j = prior::<D, K>(&model, 1e6, speed * speed, &vars, &est).ok()?;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for k in 0..first.updates.len() {
        let mut info = [[0.0f32; D]; D];
        for r in &runs {
            let (p, v, moving) = r.truth[k];
            let mut x = [0.0f32; D];
            x[0] = p[0];
            x[1] = p[1];
            x[2] = v[0];
            x[3] = v[1];
            x[MODE] = f32::from(u8::from(moving));
            let one = information(&model, &x, &r.updates[k].epoch, &est);
            for a in 0..D {
                for b in 0..D {
                    info[a][b] += one[a][b] / runs.len() as f32;
                }
            }
        }
        let was = if k == 0 {
            first.truth[0].2
        } else {
            first.truth[k - 1].2
        };
        let (f, q) = transition::<D>(
            &model.motion,
            first.updates[k].epoch.dt,
            was,
            first.truth[k].2,
        );
        j = step(&j, &f, &q, &info, &est).ok()?;
        if first.updates[k].t_s >= s.warmup_s {
            let b = position_rmse(&j).ok()?;
            sum += f64::from(b) * f64::from(b);
            n += 1;
        }
    }
    let p = foxhunt_core::linalg::inverse_scaled(&j)?;
    let parameters = settings
        .layout
        .means()
        .filter(|m| *m < D)
        .map(|m| f64::from(p[m][m].max(0.0)).sqrt())
        .collect();
    (n > 0).then(|| Bound {
        rmse: (sum / n as f64).sqrt(),
        parameters,
    })
}

/// A row from the runs' figures.
fn row(
    s: &MovingScenario,
    label: &str,
    method: Method,
    particles: usize,
    runs: &[Result<RunFigures, Error>],
    bound: Option<f64>,
) -> Row {
    let mut row = Row::new(s.name.clone(), method, particles, runs.len());
    row.method = label.to_string();
    row.crlb = bound;
    let ok: Vec<&RunFigures> = runs.iter().filter_map(|r| r.as_ref().ok()).collect();
    row.failures = runs.len() - ok.len();
    let n = ok.len().max(1) as f64;
    row.time_s = ok.iter().map(|f| f.seconds).sum::<f64>() / n;
    row.evaluations = ok.iter().map(|f| f.evaluations as f64).sum::<f64>() / n;
    let errors: Vec<f32> = ok.iter().flat_map(|f| f.errors.iter().copied()).collect();
    if errors.is_empty() {
        row.note = Some(format!("failed: none of {} runs gave a track", runs.len()));
        return row;
    }
    let ms = errors.iter().map(|e| f64::from(*e).powi(2)).sum::<f64>() / errors.len() as f64;
    row.rmse = Some(ms.sqrt());
    row.ratio = bound.filter(|b| *b > 0.0).map(|b| ms.sqrt() / b);
    let share = |v: &mut dyn Iterator<Item = bool>| {
        let (mut yes, mut all) = (0usize, 0usize);
        for b in v {
            yes += usize::from(b);
            all += 1;
        }
        yes as f64 / all.max(1) as f64
    };
    row.coverage = Some(share(
        &mut ok.iter().flat_map(|f| f.covered.iter().copied()),
    ));
    let (median, p90) = quantiles(&errors);
    let mut note = format!("median {median:.1} m, p90 {p90:.1} m");
    if ok.iter().any(|f| !f.mode_right.is_empty()) {
        let mode = share(&mut ok.iter().flat_map(|f| f.mode_right.iter().copied()));
        note.push_str(&format!("; P(moving) right {:.0} %", 100.0 * mode));
    }
    let smoothed: Vec<(f32, bool)> = ok.iter().flat_map(|f| f.smoothed.iter().copied()).collect();
    if !smoothed.is_empty() {
        let ms = smoothed
            .iter()
            .map(|(e, _)| f64::from(*e).powi(2))
            .sum::<f64>()
            / smoothed.len() as f64;
        let cov = smoothed.iter().filter(|(_, c)| *c).count() as f64 / smoothed.len() as f64;
        note.push_str(&format!(
            "; smoothed (lag {}) rmse {:.1} m, coverage {:.0} %",
            crate::track::moving::LAG,
            ms.sqrt(),
            100.0 * cov
        ));
    }
    row.note = Some(note);
    row
}

/// Median and 90th percentile.
pub fn quantiles(values: &[f32]) -> (f32, f32) {
    let mut v = values.to_vec();
    v.sort_by(f32::total_cmp);
    let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
    (at(0.5), at(0.9))
}

/// `method` at `particles` over `runs` runs of `s`, in parallel.
pub fn measure(
    s: &MovingScenario,
    method: Method,
    particles: usize,
    runs: usize,
    smooth: bool,
    progress: &Progress,
) -> Vec<Result<RunFigures, Error>> {
    progress.set_label(&format!("{} {}", s.name, method.name()));
    pool().install(|| {
        (0..runs)
            .into_par_iter()
            .map(|r| {
                let f = one(s, method, particles, smooth, r);
                progress.tick();
                f
            })
            .collect()
    })
}

/// The per-epoch triangulation's row ([`super::triangulate`]) on the scenario's runs, its note
/// saying how many epochs gave no fix.
fn triangulation_row(s: &MovingScenario, bound: Option<f64>) -> Row {
    let runs: Vec<(RunFigures, usize)> = pool().install(|| {
        (0..s.runs)
            .into_par_iter()
            .map(|r| triangulate(&s.simulate(r), s.warmup_s))
            .collect()
    });
    let missed: usize = runs.iter().map(|(_, m)| m).sum();
    let figures: Vec<Result<RunFigures, Error>> = runs.into_iter().map(|(f, _)| Ok(f)).collect();
    let mut r = row(s, TRIANGULATION, Method::Ml, 0, &figures, bound);
    if let Some(note) = r.note.as_mut() {
        note.push_str(&format!("; {missed} epochs without a fix"));
    }
    r
}

/// The triangulation row's method label.
pub const TRIANGULATION: &str = "triangulation";

/// Runs a scenario's table takes (for the progress bar; `only`: those methods' rows alone).
pub fn total_runs(s: &MovingScenario, only: &[Method]) -> u64 {
    if !only.is_empty() {
        return (only.len() * s.runs) as u64;
    }
    let swarms = TRACK_METHODS.iter().filter(|m| m.is_swarm()).count();
    ((TRACK_METHODS.len() - swarms) * s.runs + (swarms + 1) * SWARM_RUNS.min(s.runs)) as u64
}

/// The table of scenario `s`: every tracking method with `particles` (the default smoothed
/// too), the swarms at [`SWARM_PARTICLES`] over [`SWARM_RUNS`] runs beside the default at the
/// same settings; with `only`, those methods' rows alone, each at `particles` over every run.
pub fn bench(
    s: &MovingScenario,
    particles: usize,
    only: &[Method],
    progress: &Progress,
) -> Vec<Row> {
    let bound = pcrb(s);
    let mut rows = Vec::new();
    if !only.is_empty() {
        for m in only {
            let runs = measure(s, *m, particles, s.runs, *m == DEFAULT_METHOD, progress);
            rows.push(row(s, m.name(), *m, particles, &runs, bound));
        }
        return rows;
    }
    for m in TRACK_METHODS {
        if m.is_swarm() {
            continue;
        }
        let smooth = m == DEFAULT_METHOD;
        let runs = measure(s, m, particles, s.runs, smooth, progress);
        rows.push(row(s, m.name(), m, particles, &runs, bound));
    }
    let few = SWARM_RUNS.min(s.runs);
    let base = measure(s, DEFAULT_METHOD, SWARM_PARTICLES, few, false, progress);
    rows.push(row(
        s,
        DEFAULT_METHOD.name(),
        DEFAULT_METHOD,
        SWARM_PARTICLES,
        &base,
        bound,
    ));
    if s.bearings && s.stations.len() >= 2 {
        rows.push(triangulation_row(s, bound));
    }
    for m in TRACK_METHODS.iter().filter(|m| m.is_swarm()) {
        let runs = measure(s, *m, SWARM_PARTICLES, few, false, progress);
        rows.push(row(s, m.name(), *m, SWARM_PARTICLES, &runs, bound));
    }
    rows
}

/// `foxhunt bench --scenario moving` (every scenario) or `moving/NAME`: the tables, with
/// `runs` and the non-swarm rows' `particles` overridden where given, and `only` those
/// methods' rows when some are named.
pub fn bench_named(
    name: &str,
    runs: Option<usize>,
    particles: Option<usize>,
    rate_hz: Option<f32>,
    told_sigma: Option<f32>,
    only: &[Method],
    show: bool,
) -> Result<Vec<Row>, String> {
    let mut list = match name.strip_prefix("moving").unwrap_or(name) {
        "" => MovingScenario::all(),
        rest => {
            let n = rest.strip_prefix('/').unwrap_or(rest);
            vec![MovingScenario::named(n).ok_or_else(|| {
                format!(
                    "unknown moving scenario `{n}`; known: {}",
                    super::NAMES.join(", ")
                )
            })?]
        }
    };
    let particles = particles.unwrap_or(PARTICLES);
    if !TRACK_PARTICLES.contains(&particles) {
        return Err(format!(
            "--particles {particles}: the tracker is compiled for {TRACK_PARTICLES:?}"
        ));
    }
    for s in list.iter_mut() {
        if let Some(r) = runs {
            s.runs = r;
        }
        if let Some(hz) = rate_hz {
            s.rate_hz = hz;
        }
        if told_sigma.is_some() && s.aoa.is_none() {
            s.told_sigma = told_sigma;
        }
    }
    let progress = Progress::new(list.iter().map(|s| total_runs(s, only)).sum(), show);
    let rows = list
        .iter()
        .flat_map(|s| bench(s, particles, only, &progress))
        .collect();
    progress.finish();
    Ok(rows)
}
