//! The network bench: the default pipeline, as `locate --stations` runs it, beside
//! df-aggregator's algorithm on the same runs of each network condition.

use super::{EMITTER_MHZ, NetworkCondition, NetworkDrive, peer, simulate};
use crate::estimate::stations::{PriorOrigin, StationSetup, calibrate_on_references};
use crate::estimate::{PipelineRun, pipeline};
use crate::outputs::tables::Row;
use crate::runs::field::{FieldDrive, THREE_SIGMA_TAIL, bound_at, judge};
use foxhunt_core::Method;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::locate::LocateConfig;
use rayon::prelude::*;

/// One run of a condition judged, both ways.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NetworkRun {
    /// The pipeline's error (m; NaN without a fix), whether its 95 % ellipse held the truth,
    /// whether the truth lay beyond its 3 sigma, whether the truth lay within its CEP50.
    pub error: f32,
    /// Its 95 % ellipse holds the truth.
    pub covered: bool,
    /// The truth is beyond the ellipse's 99.73 % region.
    pub beyond_3_sigma: bool,
    /// The truth is within the reported CEP50.
    pub within_cep50: bool,
    /// The bias-aware bound with the priors the run had (after any reference's
    /// calibration), m.
    pub bound: f32,
    /// The bound with every offset known, m.
    pub plain_bound: f32,
    /// The peer's error (m; NaN when it found no cluster).
    pub peer_error: f32,
    /// The peer's "3 sigma" ellipse holds the truth.
    pub peer_holds: bool,
    /// The peer's ellipse's semi-major axis, m.
    pub peer_major: f32,
    /// The pipeline's wall time (with the reference's calibration), seconds.
    pub seconds: f64,
    /// The peer's wall time, seconds.
    pub peer_seconds: f64,
}

/// The stations file of a network drive: each station's stated prior.
fn setup_of(d: &FieldDrive) -> StationSetup {
    StationSetup {
        priors: d.priors(BiasPrior::default()),
        origins: vec![PriorOrigin::StationsFile; d.stations.len()],
        noise: vec![None; d.stations.len()],
        classes: vec![None; d.stations.len()],
    }
}

/// The default pipeline on run `run` of `c`, as `locate --stations` runs it (any reference
/// transmitter's calibration first): the drive (its priors after the calibration) and the
/// report (`None` when the pipeline failed).
pub fn locate_network(c: NetworkCondition, run: usize) -> (FieldDrive, Option<PipelineRun>) {
    let NetworkDrive {
        mut drive,
        references,
        ..
    } = simulate(c, run);
    let config = LocateConfig::default();
    let mut setup = setup_of(&drive);
    if !references.is_empty() {
        let (rest, _) = calibrate_on_references(
            &drive.observations,
            &references,
            config.channel_width_mhz,
            &mut setup,
        );
        drive.observations = rest;
        for (s, st) in drive.stations.iter_mut().enumerate() {
            st.prior = setup.priors.of(s);
        }
    }
    let r = pipeline(&drive.observations, &config, &setup.priors, run as u64).ok();
    (drive, r)
}

/// Run both methods on run `run` of `c`.
pub fn run_network(c: NetworkCondition, run: usize) -> NetworkRun {
    let clock = std::time::Instant::now();
    let (drive, r) = locate_network(c, run);
    let seconds = clock.elapsed().as_secs_f64();
    let j = judge(&drive, r.as_ref().map(|r| &r.report), BiasPrior::default());
    let j = j.first().copied();
    let mut known = drive.clone();
    for st in &mut known.stations {
        st.prior = BiasPrior::calibrated(st.offset);
    }
    let truth = drive.emitters[0];
    let plain_bound = bound_at(&known, &truth, BiasPrior::calibrated(0.0));
    let channel: Vec<_> = drive
        .observations
        .iter()
        .filter(|o| o.freq_mhz == Some(EMITTER_MHZ))
        .copied()
        .collect();
    let moving: Vec<bool> = drive.stations.iter().map(|s| !s.fixed).collect();
    let clock = std::time::Instant::now();
    let p = peer::locate(&channel, &moving);
    let peer_seconds = clock.elapsed().as_secs_f64();
    let found = j.filter(|j| j.found);
    NetworkRun {
        error: found.map_or(f32::NAN, |j| j.error),
        covered: found.is_some_and(|j| j.covered),
        beyond_3_sigma: found.is_some_and(|j| j.tail < THREE_SIGMA_TAIL),
        within_cep50: found.is_some_and(|j| j.within_cep50),
        bound: j.map_or(f32::INFINITY, |j| j.bound),
        plain_bound,
        peer_error: p.map_or(f32::NAN, |p| {
            (p.position[0] - truth.position[0]).hypot(p.position[1] - truth.position[1])
        }),
        peer_holds: p.is_some_and(|p| p.holds(&truth.position)),
        peer_major: p.map_or(f32::NAN, |p| p.major()),
        seconds,
        peer_seconds,
    }
}

/// A condition's figures over its runs, both methods.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkSummary {
    /// The condition.
    pub condition: NetworkCondition,
    /// Runs.
    pub runs: usize,
    /// Runs with a pipeline fix.
    pub found: usize,
    /// Of those, whose 95 % ellipse held the truth.
    pub covered: usize,
    /// Of those, with the truth beyond 3 sigma.
    pub beyond_3_sigma: usize,
    /// Of those, with the truth within CEP50.
    pub within_cep50: usize,
    /// The pipeline's rmse, m.
    pub rmse: f64,
    /// The root mean square of the bias-aware bound, m.
    pub bound: f64,
    /// The root mean square of the bound with every offset known, m.
    pub plain_bound: f64,
    /// Runs the peer gave a location.
    pub peer_found: usize,
    /// Of those, whose "3 sigma" ellipse held the truth.
    pub peer_covered: usize,
    /// The peer's rmse, m.
    pub peer_rmse: f64,
    /// The peer's median error, m.
    pub peer_median: f64,
    /// The pipeline's median error, m.
    pub median: f64,
    /// The peer's median ellipse semi-major axis, m.
    pub peer_major: f64,
    /// The pipeline's mean wall time a run, seconds.
    pub seconds: f64,
    /// The peer's mean wall time a run, seconds.
    pub peer_seconds: f64,
}

impl NetworkSummary {
    /// The pipeline's coverage.
    pub fn coverage(&self) -> f64 {
        self.covered as f64 / self.found.max(1) as f64
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    (s / n.max(1) as f64).sqrt()
}

/// Measure `c` over `runs` seeded runs.
pub fn measure_network(c: NetworkCondition, runs: usize) -> NetworkSummary {
    let all: Vec<NetworkRun> = crate::estimate::pool().install(|| {
        (0..runs)
            .into_par_iter()
            .map(|r| run_network(c, r))
            .collect()
    });
    let found: Vec<&NetworkRun> = all.iter().filter(|r| r.error.is_finite()).collect();
    let peer: Vec<&NetworkRun> = all.iter().filter(|r| r.peer_error.is_finite()).collect();
    NetworkSummary {
        condition: c,
        runs,
        found: found.len(),
        covered: found.iter().filter(|r| r.covered).count(),
        beyond_3_sigma: found.iter().filter(|r| r.beyond_3_sigma).count(),
        within_cep50: found.iter().filter(|r| r.within_cep50).count(),
        rmse: rms(found.iter().map(|r| f64::from(r.error))),
        bound: rms(all.iter().map(|r| f64::from(r.bound))),
        plain_bound: rms(all.iter().map(|r| f64::from(r.plain_bound))),
        median: median(found.iter().map(|r| f64::from(r.error)).collect()),
        peer_found: peer.len(),
        peer_covered: peer.iter().filter(|r| r.peer_holds).count(),
        peer_rmse: rms(peer.iter().map(|r| f64::from(r.peer_error))),
        peer_median: median(peer.iter().map(|r| f64::from(r.peer_error)).collect()),
        peer_major: median(peer.iter().map(|r| f64::from(r.peer_major)).collect()),
        seconds: all.iter().map(|r| r.seconds).sum::<f64>() / runs.max(1) as f64,
        peer_seconds: all.iter().map(|r| r.peer_seconds).sum::<f64>() / runs.max(1) as f64,
    }
}

/// The bench rows of `conditions`: per condition the pipeline's row and the peer's.
pub fn bench(conditions: &[NetworkCondition], runs: usize) -> Vec<Row> {
    conditions
        .iter()
        .flat_map(|&c| {
            let s = measure_network(c, runs);
            let label = c.name().to_string();
            let mut r = Row::new(label.clone(), Method::MlRobust, 0, runs);
            r.time_s = s.seconds;
            r.failures = runs - s.found;
            r.found = Some(s.found as f64 / runs.max(1) as f64);
            if s.found > 0 {
                r.rmse = Some(s.rmse);
                r.coverage = Some(s.coverage());
                r.cep50_share = Some(s.within_cep50 as f64 / s.found as f64);
                r.beyond_3_sigma = Some(s.beyond_3_sigma);
            }
            r.crlb = Some(s.bound).filter(|b| b.is_finite());
            r.ratio = r.rmse.zip(r.crlb).map(|(e, b)| e / b);
            r.note = Some(format!(
                "median {:.0} m; bound with every offset known {:.0} m (rmse {:.2}x it)",
                s.median,
                s.plain_bound,
                s.rmse / s.plain_bound
            ));
            let mut p = Row::new(label, Method::MlRobust, 0, runs);
            p.method = "df-aggregator".into();
            p.time_s = s.peer_seconds;
            p.failures = runs - s.peer_found;
            p.found = Some(s.peer_found as f64 / runs.max(1) as f64);
            if s.peer_found > 0 {
                p.rmse = Some(s.peer_rmse);
                p.coverage = Some(s.peer_covered as f64 / s.peer_found as f64);
            }
            p.crlb = r.crlb;
            p.ratio = p.rmse.zip(p.crlb).map(|(e, b)| e / b);
            p.note = Some(format!(
                "coverage of its \"3 sigma\" ellipse (claims 98.9 %); median {:.0} m; median semi-major axis {:.0} m",
                s.peer_median, s.peer_major
            ));
            [r, p]
        })
        .collect()
}
