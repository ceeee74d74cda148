//! A field run judged against its truth, and a condition's figures over its runs.

use super::drives::simulate;
use super::{CHANNELS, Condition, DEG, FieldDrive, OTHERS, Truth};
use crate::estimate::{PipelineRun, Priors};
use foxhunt_core::Error;
use foxhunt_core::fix::bias::{self, BiasPrior, StationSlot};
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::{
    ChannelOutcome, Item, LocateConfig, Observation, Region, Report, Source, relative_bearings,
};
use foxhunt_core::model::bearing::{Bearing, predicted};
use rayon::prelude::*;

/// What one run of the pipeline gave, judged against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOutcome {
    /// An emitter was reported for the truth's channel.
    pub found: bool,
    /// Error of that emitter, metres.
    pub error: f32,
    /// Its 95 % ellipse holds the truth.
    pub covered: bool,
    /// The probability, under the ellipse's own distribution (chi-square, or 2 F(2, dof) when
    /// the noise was estimated), of a truth at least this far out: below 0.0027 is "beyond
    /// 3 sigma" (the 99.73 % of three sigmas in one dimension).
    pub tail: f32,
    /// The bias-aware bound at the truth (the drive's geometry, true noise, the prior), m.
    pub bound: f32,
    /// A ghost was reported as another source within its own 95 % ellipse (or 200 m).
    pub ghost_reported: bool,
    /// The emitter's reported offset, radians.
    pub bias: f32,
    /// The truth lies within the reported CEP50.
    pub within_cep50: bool,
    /// No emitter but a region for the truth's channel (an open range): whether it holds the
    /// truth (bearing within its half-width, range within its interval).
    pub region: Option<bool>,
}

/// The observations' geometry at the truth with the true noise: the bound's input (each
/// station's own noise in a network).
pub(super) fn truth_geometry(d: &FieldDrive, t: &Truth) -> Vec<Observation> {
    d.observations
        .iter()
        .filter(|o| o.freq_mhz == t.freq_mhz)
        .map(|o| Observation {
            bearing: Bearing {
                vehicle: o.bearing.vehicle,
                theta: predicted(&t.position, &o.bearing.vehicle),
                sigma: d
                    .stations
                    .get(usize::from(o.station))
                    .map_or(d.sigma, |s| s.sigma),
            },
            ..*o
        })
        .collect()
}

/// The bias-aware bound at truth `t`: every station's offset with the prior the run gave it.
pub fn bound_at(d: &FieldDrive, t: &Truth, prior: BiasPrior) -> f32 {
    bound_with(d, t, &d.priors(prior))
}

/// The bias-aware bound at truth `t` with the stations' `priors` (their offsets' and
/// direction-dependent errors' priors integrated out).
pub fn bound_with(d: &FieldDrive, t: &Truth, priors: &Priors) -> f32 {
    let geometry = truth_geometry(d, t);
    let n = geometry
        .iter()
        .map(|o| usize::from(o.station) + 1)
        .max()
        .unwrap_or(0);
    let mut table: Vec<StationSlot> = (0..n).map(|s| priors.row(s)).collect();
    // Each bearing relative to its antenna, as the pipeline takes it.
    let mut items: Vec<Item> = geometry
        .iter()
        .enumerate()
        .map(|(i, o)| Item::new(*o, i as u32))
        .collect();
    relative_bearings(&mut items, &mut table);
    bias::crlb_stations(&t.position, &items, &mut table)
        .map(|b| b.rmse)
        .unwrap_or(f32::INFINITY)
}

/// Run the pipeline on one drive, every station with the drive's prior or `prior`.
pub fn run_locate(
    d: &FieldDrive,
    config: &LocateConfig,
    prior: BiasPrior,
    seed: u64,
) -> Result<PipelineRun, Error> {
    run_with(d, config, &d.priors(prior), seed)
}

/// Run the pipeline on one drive with the stations' `priors` (a condition's,
/// [`Condition::priors`]).
pub fn run_with(
    d: &FieldDrive,
    config: &LocateConfig,
    priors: &Priors,
    seed: u64,
) -> Result<PipelineRun, Error> {
    crate::estimate::pipeline(&d.observations, config, priors, seed)
}

/// The emitter reported for the channel of truth `t`.
pub fn emitter_for<'a>(r: &'a Report<CHANNELS, OTHERS>, t: &Truth) -> Option<&'a Source> {
    let same = |f: Option<f32>| match (f, t.freq_mhz) {
        (None, None) => true,
        (Some(a), Some(b)) => (a - b).abs() < 0.05,
        _ => false,
    };
    r.channels().iter().find_map(|c| match c.outcome {
        ChannelOutcome::Emitter(i) if same(c.freq_mhz) => r.emitters().get(i),
        _ => None,
    })
}

/// The region reported for the channel of truth `t` (an open range), if any.
pub fn region_for<'a>(r: &'a Report<CHANNELS, OTHERS>, t: &Truth) -> Option<&'a Region> {
    let same = |f: Option<f32>| match (f, t.freq_mhz) {
        (None, None) => true,
        (Some(a), Some(b)) => (a - b).abs() < 0.05,
        _ => false,
    };
    r.channels().iter().find_map(|c| match c.outcome {
        ChannelOutcome::Region(i) if same(c.freq_mhz) => r.regions().get(i),
        _ => None,
    })
}

/// Whether the source's ellipse holds `truth`, and the tail probability of its distance.
fn sigmas_of(s: &Source, truth: &[f32; 2]) -> (bool, f32) {
    let m = mahalanobis(&s.covariance, &s.position, truth).unwrap_or(f32::INFINITY);
    let m2 = (m * m) as f64;
    let covered = m * m <= s.ellipse_scale;
    // P(2 F(2, d) > m^2) = (1 + m^2 / d)^(-d/2); P(chi2(2) > m^2) = exp(-m^2 / 2).
    let tail = if s.sigma_estimated {
        let d = s.dof as f64;
        (1.0 + m2 / d).powf(-d / 2.0)
    } else {
        (-m2 / 2.0).exp()
    };
    (covered, tail as f32)
}

/// The tail probability of three sigmas in one dimension.
pub const THREE_SIGMA_TAIL: f32 = 0.0027;

/// Judge one run: for each truth, its channel's emitter (none when the pipeline failed).
pub fn judge(
    d: &FieldDrive,
    r: Option<&Report<CHANNELS, OTHERS>>,
    prior: BiasPrior,
) -> Vec<RunOutcome> {
    judge_with(d, r, &d.priors(prior))
}

/// [`judge`] with the bound taken at the stations' `priors`.
pub fn judge_with(
    d: &FieldDrive,
    r: Option<&Report<CHANNELS, OTHERS>>,
    priors: &Priors,
) -> Vec<RunOutcome> {
    d.emitters
        .iter()
        .map(|t| {
            let bound = bound_with(d, t, priors);
            let ghost_reported = d.ghost.is_some_and(|g| {
                r.into_iter().flat_map(|r| r.others()).any(|o| {
                    let (inside, _) = sigmas_of(&o.source, &g);
                    let near = (o.source.position[0] - g[0]).hypot(o.source.position[1] - g[1]);
                    inside || near < 200.0
                })
            });
            match r.and_then(|r| emitter_for(r, t)) {
                Some(s) => {
                    let (covered, tail) = sigmas_of(s, &t.position);
                    let error =
                        (s.position[0] - t.position[0]).hypot(s.position[1] - t.position[1]);
                    RunOutcome {
                        found: true,
                        error,
                        covered,
                        tail,
                        bound,
                        ghost_reported,
                        bias: s.bias,
                        within_cep50: error <= s.cep50,
                        region: None,
                    }
                }
                None => RunOutcome {
                    found: false,
                    error: f32::NAN,
                    covered: false,
                    tail: f32::NAN,
                    bound,
                    ghost_reported,
                    bias: f32::NAN,
                    within_cep50: false,
                    region: r
                        .and_then(|r| region_for(r, t))
                        .map(|g| g.contains(&t.position)),
                },
            }
        })
        .collect()
}

/// A condition's figures over its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The condition.
    pub condition: Condition,
    /// Runs.
    pub runs: usize,
    /// Per truth emitter (one for most conditions, two for two-emitters): the figures below.
    pub per_emitter: Vec<EmitterSummary>,
    /// Runs with no consistent emitter in any channel.
    pub no_emitter: usize,
    /// Runs in which the ghost was reported as another source.
    pub ghost_reported: usize,
    /// Runs in which a direction-dependent error no one stated was found and modelled.
    pub direction_found: usize,
}

/// Figures for one truth emitter over the runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmitterSummary {
    /// Runs with an emitter reported for its channel.
    pub found: usize,
    /// Of those, runs whose 95 % ellipse holds the truth.
    pub covered: usize,
    /// Of those, runs with the truth beyond 3 sigma (the 99.73 % region) of the ellipse.
    pub beyond_3_sigma: usize,
    /// Root mean square error of the found fixes, metres.
    pub rmse: f64,
    /// Root mean square of the bias-aware bound over the runs, metres.
    pub bound: f64,
    /// Mean reported offset, degrees.
    pub mean_bias_deg: f64,
    /// Of the found runs, those with the truth within the reported CEP50.
    pub within_cep50: usize,
    /// Runs with a region (an open range) instead of an emitter for its channel.
    pub regions: usize,
    /// Of those, runs whose region holds the truth.
    pub regions_covered: usize,
}

impl EmitterSummary {
    /// Share of found runs whose ellipse holds the truth.
    pub fn coverage(&self) -> f64 {
        self.covered as f64 / self.found.max(1) as f64
    }
    /// Share of answers (emitters and regions) that hold the truth.
    pub fn answer_coverage(&self) -> f64 {
        (self.covered + self.regions_covered) as f64 / (self.found + self.regions).max(1) as f64
    }
    /// rmse / bound.
    pub fn ratio(&self) -> f64 {
        self.rmse / self.bound
    }
}

/// Measure `condition` over `runs` seeded runs with `config`, every station's offset with the
/// drive's prior or `prior` (which also set the bound).
pub fn measure(
    condition: Condition,
    runs: usize,
    config: &LocateConfig,
    prior: BiasPrior,
) -> Summary {
    let outcomes: Vec<(Vec<RunOutcome>, bool, bool)> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let d = simulate(condition, run);
            let priors = condition.priors(&d, prior);
            let r = run_with(&d, config, &priors, run as u64).ok();
            let none = r.as_ref().is_none_or(|r| r.emitters().is_empty());
            let found = r.as_ref().is_some_and(|r| !r.found.is_empty());
            let bound = condition.bound_priors(&d, prior);
            (
                judge_with(&d, r.as_ref().map(|r| &r.report), &bound),
                none,
                found,
            )
        })
        .collect();
    let emitters = outcomes.first().map(|o| o.0.len()).unwrap_or(0);
    let per_emitter = (0..emitters)
        .map(|e| {
            let mut s = EmitterSummary {
                found: 0,
                covered: 0,
                beyond_3_sigma: 0,
                rmse: 0.0,
                bound: 0.0,
                mean_bias_deg: 0.0,
                within_cep50: 0,
                regions: 0,
                regions_covered: 0,
            };
            let mut sq = 0.0f64;
            let mut bound_sq = 0.0f64;
            for (o, ..) in &outcomes {
                let Some(o) = o.get(e) else { continue };
                bound_sq += (o.bound as f64).powi(2);
                if o.found {
                    s.found += 1;
                    s.covered += o.covered as usize;
                    s.beyond_3_sigma += (o.tail < THREE_SIGMA_TAIL) as usize;
                    sq += (o.error as f64).powi(2);
                    s.mean_bias_deg += (o.bias / DEG) as f64;
                    s.within_cep50 += o.within_cep50 as usize;
                }
                if let Some(held) = o.region {
                    s.regions += 1;
                    s.regions_covered += held as usize;
                }
            }
            s.rmse = (sq / s.found.max(1) as f64).sqrt();
            s.bound = (bound_sq / runs.max(1) as f64).sqrt();
            s.mean_bias_deg /= s.found.max(1) as f64;
            s
        })
        .collect();
    Summary {
        condition,
        runs,
        per_emitter,
        no_emitter: outcomes.iter().filter(|o| o.1).count(),
        direction_found: outcomes.iter().filter(|o| o.2).count(),
        ghost_reported: outcomes
            .iter()
            .filter(|o| o.0.first().is_some_and(|r| r.ghost_reported))
            .count(),
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<26} runs {:>3}  no-emitter {:>3}",
            self.condition.name(),
            self.runs,
            self.no_emitter
        )?;
        for e in &self.per_emitter {
            write!(
                f,
                "  | found {:>3} coverage {:>5.1} % >3sd {:>2} rmse {:>8.1} m bound {:>8.1} m ratio {:>5.2} bias {:>5.2} deg",
                e.found,
                100.0 * e.coverage(),
                e.beyond_3_sigma,
                e.rmse,
                e.bound,
                e.ratio(),
                e.mean_bias_deg
            )?;
            if e.regions > 0 {
                write!(
                    f,
                    " regions {:>3} held {:>3} answers held {:>5.1} %",
                    e.regions,
                    e.regions_covered,
                    100.0 * e.answer_coverage()
                )?;
            }
        }
        if self.condition == Condition::Multipath {
            write!(f, "  | ghost reported {}", self.ghost_reported)?;
        }
        Ok(())
    }
}
