//! The core's estimators driven on the host: the field pipeline with working storage from the
//! heap, any registry method on a set of bearings, a filter stepped through measurements, and
//! the thread pool with stacks large enough for the core's fixed-capacity filters. Every
//! filter comes from the core's registry ([`foxhunt_core::estimator`]); this module only
//! drives it.

pub mod direction;
pub mod noise;
pub mod options;
pub mod stations;
pub mod window;

use foxhunt_core::estimator::{batch_fix, with_bearing_filter};
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior, StationSlot};
use foxhunt_core::fix::ellipse::cep50;
use foxhunt_core::fix::init::initial_particles;
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::fix::locate::{
    Buffers, Item, LocateConfig, Observation, Report, StationOffset, locate,
};
use foxhunt_core::{
    Bearing, Error, Estimate, Filter, Method, ParticleSet, WithFilter, with_particles,
};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use std::sync::OnceLock;

/// A filter run over a sequence of measurements.
#[derive(Debug, Clone)]
pub struct FilterRun<const D: usize> {
    /// The estimate after the last measurement.
    pub estimate: Estimate<D>,
    /// Likelihood evaluations spent.
    pub evaluations: u64,
    /// The particles at the end, when asked for (empty for the EKF).
    pub cloud: Vec<[f32; D]>,
}

/// The visitor that starts a filter from `cloud`, steps it through `measurements` (a rejected
/// measurement is skipped: the filter keeps its estimate) and calls `each` with every step's
/// estimate.
pub struct Steps<'a, const D: usize, Z, C> {
    /// The initial hypotheses.
    pub cloud: &'a [[f32; D]],
    /// The measurements in order.
    pub measurements: &'a [Z],
    /// The run's generator.
    pub rng: &'a mut XorShiftRng,
    /// Called after every step with its index and estimate.
    pub each: C,
    /// Whether to return the final particles.
    pub keep_cloud: bool,
}

impl<const D: usize, Z, C: FnMut(usize, &Estimate<D>)> WithFilter<D, Z> for Steps<'_, D, Z, C> {
    type Output = Result<FilterRun<D>, Error>;

    fn visit<F: Filter<D, Measurement = Z>>(mut self, f: &mut F) -> Self::Output {
        f.initialise(self.cloud, self.rng)?;
        for (k, z) in self.measurements.iter().enumerate() {
            let e = match f.step(z, self.rng) {
                Ok(e) => e,
                Err(_) => f.estimate()?,
            };
            (self.each)(k, &e);
        }
        let estimate = f.estimate()?;
        let finite = estimate
            .mean
            .iter()
            .chain(estimate.covariance.iter().flatten())
            .all(|v| v.is_finite());
        if !finite {
            return Err(Error::NonFinite);
        }
        Ok(FilterRun {
            estimate,
            evaluations: f.evaluations(),
            cloud: if self.keep_cloud {
                f.cloud().to_vec()
            } else {
                Vec::new()
            },
        })
    }
}

/// The field pipeline's report on the host: up to 16 channels and 16 other sources.
pub type Pipeline = Report<16, 16>;

/// What the field pipeline gave on the host: the report, and the offsets table its emitters'
/// [`Source::offsets`](foxhunt_core::fix::locate::Source::offsets) index.
#[derive(Debug, Clone)]
pub struct PipelineRun {
    /// The report.
    pub report: Pipeline,
    /// Every emitter's per-station offsets ([`Pipeline::offsets_of`]).
    pub offsets: Vec<StationOffset>,
    /// The direction-dependent errors no one stated that the first fix's residuals showed:
    /// the report is the fix done again with them modelled ([`direction`]).
    pub found: Vec<direction::FoundDirection>,
}

impl std::ops::Deref for PipelineRun {
    type Target = Pipeline;
    fn deref(&self) -> &Pipeline {
        &self.report
    }
}

/// What is known of each station before the drive: its offset prior (its own where one is
/// known: a stations file, a reference transmitter's calibration; else the default: the
/// `--calibration` file's, or the 6-degree one of an uncalibrated unit), its unmodelled
/// systematic error, and the noise ceiling of the device classes stated.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Priors {
    /// The prior of every station without its own.
    pub default: BiasPrior,
    /// Station index to its own prior.
    pub stations: Vec<Option<BiasPrior>>,
    /// Sd of the unmodelled systematic error of every station without its own, radians.
    pub default_unmodelled: f32,
    /// Station index to its own unmodelled error's sd, radians.
    pub unmodelled: Vec<Option<f32>>,
    /// The widest noise ceiling of the stations' stated device classes, radians (`None`: no
    /// class stated, the configuration's holds).
    pub ceiling: Option<f32>,
    /// Whether every station's noise is stated (a stations file's, or its device class's):
    /// [`LocateConfig::noise_stated`].
    pub noise_stated: bool,
    /// Station index to its direction-dependent error's prior and its antenna's front where
    /// it stands still (theta, radians; `None` where no one stated it: [`Priors::front`]);
    /// `None`: not modelled.
    pub direction: Vec<Option<(DirectionPrior, Option<f32>)>>,
    /// The direction-dependent error of every station without its own (a `--calibration`
    /// file's) and the front of one that stands still; `None`: not modelled.
    pub default_direction: Option<(DirectionPrior, Option<f32>)>,
}

impl Priors {
    /// The same prior for every station.
    pub fn same(prior: BiasPrior) -> Self {
        Self {
            default: prior,
            ..Self::default()
        }
    }

    /// Station `s`'s prior.
    pub fn of(&self, s: usize) -> BiasPrior {
        self.stations
            .get(s)
            .copied()
            .flatten()
            .unwrap_or(self.default)
    }

    /// Station `s`'s unmodelled error's sd, radians.
    pub fn unmodelled_of(&self, s: usize) -> f32 {
        self.unmodelled
            .get(s)
            .copied()
            .flatten()
            .unwrap_or(self.default_unmodelled)
    }

    /// Station `s`'s direction-dependent error as stated (its own, else the default) and its
    /// antenna's front, radians; `None` where nothing states one.
    pub fn direction_of(&self, s: usize) -> Option<(DirectionPrior, Option<f32>)> {
        self.direction
            .get(s)
            .copied()
            .flatten()
            .or(self.default_direction)
    }

    /// Station `s`'s row of the station table: its prior and its unmodelled error.
    pub fn row(&self, s: usize) -> StationSlot {
        let row = StationSlot::new(self.of(s)).with_unmodelled(self.unmodelled_of(s));
        match self.direction_of(s) {
            Some((prior, front)) => row.with_direction(prior, Self::front(front)),
            None => row,
        }
    }

    /// A still antenna's front as a fix takes it: the one stated, else north (the stations
    /// file's `boresight_deg` convention). A batch fix gives a vehicle that stands still its
    /// first course; a track, which cannot look ahead, waits for the course instead
    /// ([`crate::track::direction`]).
    pub fn front(stated: Option<f32>) -> f32 {
        stated.unwrap_or(std::f32::consts::FRAC_PI_2)
    }

    /// `config` with the stated classes' ceiling, if any, and whether the noise is stated.
    pub fn config(&self, config: &LocateConfig) -> LocateConfig {
        LocateConfig {
            max_sigma: self.ceiling.unwrap_or(config.max_sigma),
            noise_stated: self.noise_stated || config.noise_stated,
            ..*config
        }
    }
}

/// Run the core's field pipeline on `observations` with working storage from the heap: one
/// station row per station the observations name, with its prior and unmodelled error from
/// `priors`, and the stated device classes' noise ceiling ([`Priors::config`]).
///
/// Where a station's direction-dependent error is stated nowhere and the fix's residuals show
/// one ([`direction::unstated`]), the fix is done again with it modelled (the same seed), and
/// the run says so ([`PipelineRun::found`]).
pub fn pipeline(
    observations: &[Observation],
    config: &LocateConfig,
    priors: &Priors,
    seed: u64,
) -> Result<PipelineRun, Error> {
    let first = pipeline_once(observations, config, priors, seed)?;
    let found = direction::unstated(observations, &first, priors, config.channel_width_mhz);
    if found.is_empty() {
        return Ok(first);
    }
    let modelled = direction::modelled(priors, &found);
    match pipeline_once(observations, config, &modelled, seed) {
        Ok(again) => Ok(PipelineRun { found, ..again }),
        // The first fix stands where the second found nothing to give.
        Err(_) => Ok(first),
    }
}

/// [`pipeline`] with the stations' priors as given.
fn pipeline_once(
    observations: &[Observation],
    config: &LocateConfig,
    priors: &Priors,
    seed: u64,
) -> Result<PipelineRun, Error> {
    let n = observations.len();
    let stations = observations
        .iter()
        .map(|o| usize::from(o.station) + 1)
        .max()
        .unwrap_or(0)
        .max(priors.stations.len());
    let mut items = vec![Item::EMPTY; n];
    let mut scratch = vec![Item::EMPTY; n];
    let mut order = vec![0u32; n];
    let mut tags = vec![0u8; n];
    let mut table: Vec<StationSlot> = (0..stations).map(|s| priors.row(s)).collect();
    // Room for every channel's emitter to list every station.
    let mut offsets = vec![StationOffset::EMPTY; stations * 16];
    let work = Buffers::new(
        &mut items,
        &mut scratch,
        &mut order,
        &mut tags,
        &mut table,
        &mut offsets,
    );
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let report = locate::<16, 16, _>(observations, &priors.config(config), work, &mut rng)?;
    Ok(PipelineRun {
        report,
        offsets,
        found: Vec::new(),
    })
}

/// The 95 % ellipse scale of a Gaussian fix in two dimensions, chi-square(2).
pub const CHI2_2_95: f32 = 5.991_465;

/// The noise of a set of residuals: the bearing noise a fix found and the degrees of freedom
/// behind it (what scales its ellipse).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// The bearing noise, radians.
    pub sigma: f32,
    /// Its degrees of freedom: residuals used less the position's two unknowns.
    pub dof: f32,
}

/// A static-emitter fix: position, covariance, its ellipse, and what it cost.
#[derive(Debug, Clone)]
pub struct BearingFix {
    /// Position, local metres.
    pub position: [f32; 2],
    /// Covariance, m^2.
    pub covariance: [[f32; 2]; 2],
    /// The 95 % ellipse is x^T C^-1 x <= this (chi-square, or 2 F(2, dof) when the noise was
    /// estimated).
    pub ellipse_scale: f32,
    /// Degrees of freedom of the estimated noise (`None`: the bearings' stated sigmas).
    pub dof: Option<f32>,
    /// Circular error probable, metres.
    pub cep50: f32,
    /// Likelihood evaluations (0 for batch fixes).
    pub evaluations: u64,
    /// Bearings a robust loss treated as outliers (batch fixes).
    pub outliers: u32,
    /// The particles (particle filters, when asked for).
    pub cloud: Vec<[f32; 2]>,
}

/// `method` on `bearings` with `particles` particles (a compiled count), the sequential ones
/// started from the bearing-pair cloud and the seeds' ones jittered by `jitter_var`.
pub fn locate_bearings(
    method: Method,
    particles: usize,
    jitter_var: f32,
    bearings: &[Bearing],
    keep_cloud: bool,
    rng: &mut XorShiftRng,
) -> Result<BearingFix, Error> {
    if method == Method::Unit {
        // The unit's own noise model.
        let times = window::one_a_second(bearings.len());
        return window::unit_fix(bearings, &times, None).map(|u| u.fix);
    }
    if method == Method::MlRobust {
        let obs: Vec<Observation> = bearings
            .iter()
            .enumerate()
            .map(|(k, b)| Observation::new(*b, k as f32))
            .collect();
        let r = pipeline(
            &obs,
            &LocateConfig::default(),
            &Priors::default(),
            u64::from(rng.next_u32()),
        )?;
        let e = r.emitters().first().ok_or(Error::TooFewMeasurements)?;
        return Ok(BearingFix {
            position: e.position,
            covariance: e.covariance,
            ellipse_scale: e.ellipse_scale,
            dof: e.sigma_estimated.then_some(e.dof),
            cep50: e.cep50,
            evaluations: 0,
            outliers: r.rejected.outliers,
            cloud: Vec::new(),
        });
    }
    if !method.is_sequential() {
        let f = batch_fix(method, bearings)?;
        return Ok(BearingFix {
            position: f.position,
            covariance: f.covariance,
            ellipse_scale: CHI2_2_95,
            dof: None,
            cep50: cep50(&f.covariance).unwrap_or(f32::NAN),
            evaluations: 0,
            outliers: f.outliers,
            cloud: Vec::new(),
        });
    }
    let run = with_particles!(particles, N => {
        let mut cloud = Box::new(ParticleSet::<N, 2>::new());
        initial_particles(bearings, MIN_CROSSING, &mut cloud, rng)?;
        let steps = Steps {
            cloud: &cloud.states,
            measurements: bearings,
            rng,
            each: |_, _: &Estimate<2>| {},
            keep_cloud,
        };
        with_bearing_filter::<N, _>(method, jitter_var, steps)?
    })?;
    Ok(BearingFix {
        position: run.estimate.mean,
        covariance: run.estimate.covariance,
        ellipse_scale: CHI2_2_95,
        dof: None,
        cep50: cep50(&run.estimate.covariance).unwrap_or(f32::NAN),
        evaluations: run.evaluations,
        outliers: 0,
        cloud: run.cloud,
    })
}
/// Stack of every thread that estimates ([`pool`]'s workers, a live track's, the live map's
/// input): filters are sized at compile time and built on the stack.
pub const STACK_BYTES: usize = 64 << 20;

/// The thread pool of every estimation on the host (fixes and Monte Carlo runs): one worker per
/// core, with [`STACK_BYTES`] stacks. Filters are sized at
/// compile time and built on the stack (a 100 000-particle filter is megabytes); a rayon
/// worker that waits on a join can also run a stolen run on top of its own, so the default
/// 2 MiB stacks overflow. The reservation is virtual: only touched pages cost memory.
pub fn pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .stack_size(STACK_BYTES)
            .thread_name(|i| format!("foxhunt-mc-{i}"))
            .build()
            .unwrap_or_else(|_| {
                // Without threads the runs still go, one at a time on a big stack.
                rayon::ThreadPoolBuilder::new()
                    .num_threads(1)
                    .stack_size(STACK_BYTES)
                    .build()
                    .unwrap_or_else(|e| panic!("no thread for the Monte Carlo runs: {e}"))
            })
    })
}
