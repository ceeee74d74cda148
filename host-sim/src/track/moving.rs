//! The moving-emitter tracker of the core ([`foxhunt_core::track`]) driven on the host: the
//! registry's filters over a list of updates, the first cloud from the first update's
//! bearings (or a region), the fixed-lag smoother beside the filter, and every update's point.
//!
//! The core sizes its filters at compile time: the particle count is one of
//! [`TRACK_PARTICLES`] and the state one of [`STATE_SIZES`] components (the smallest that
//! holds the layout; components beyond it are carried unused).

use foxhunt_core::estimator::with_moving_filter;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::fix::init::InitialCloud;
use foxhunt_core::track::init::{Prior, Start, initial_cloud};
use foxhunt_core::track::smooth::FixedLag;
use foxhunt_core::track::{
    Epoch, Forgetting, Layout, MODE, Motion, Mover, PARAMETERS, position_covariance,
};
use foxhunt_core::{Error, Estimate, Filter, Method, ParticleSet, StepStatus, WithFilter};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Bearings and RSSI readings an update holds at most, of each.
pub const K: usize = 16;
/// The particle counts compiled for tracking.
pub const TRACK_PARTICLES: [usize; 4] = [200, 1000, 2000, 10_000];
/// The state sizes compiled for tracking: one source's offset (a vehicle), RSSI alone, four
/// sources, four sources and RSSI ([`Layout::dims`]).
pub const STATE_SIZES: [usize; 4] = [7, 10, 13, 18];
/// The most DF sources a track's state holds (the largest of [`STATE_SIZES`]), with RSSI
/// terms beside them or without.
pub const fn max_sources(rssi: bool) -> usize {
    let largest = STATE_SIZES[STATE_SIZES.len() - 1];
    let rssi_terms = Layout {
        sources: 0,
        rssi: true,
    }
    .dims()
        - PARAMETERS;
    (largest - PARAMETERS - if rssi { rssi_terms } else { 0 }) / 2
}

/// Updates the fixed-lag smoother holds: each smoothed point has seen this many - 1 later
/// updates.
pub const LAG: usize = 16;
/// The particle filters' shortest memory, seconds: their parameter statistics forget in
/// [`MEMORY_S_PER_PARTICLE`] times the particles, never in less (chosen at N = 1 000 on the
/// moving scenarios, docs/src/tracking.md).
pub const MEMORY_S: f32 = 250.0;
/// Seconds of memory a particle buys. The particles come to share their ancestors' offsets
/// after a time that grows with their number, and statistics remembered beyond it grow surer
/// than the data allow (the ellipses narrow below the truth); forgetting sooner costs accuracy.
/// Chosen on the moving scenarios (docs/src/tracking.md, "How well it follows"): at N = 1 000,
/// 250 s holds the truth 93-99 % of the time and 1 000 s 74-94 %; at N = 10 000, 1 500 s gives
/// 1.05-1.33x the bound at 93.5-99 %, 2 000 s 90-98 %, 250 s 1.14-1.52x.
pub const MEMORY_S_PER_PARTICLE: f32 = 0.15;

/// The particle filters' memory at `particles` ([`MEMORY_S_PER_PARTICLE`], at least
/// [`MEMORY_S`]).
pub fn particle_memory_s(particles: usize) -> f32 {
    (MEMORY_S_PER_PARTICLE * particles as f32).max(MEMORY_S)
}

/// Seconds in which the IMM of EKFs' parameters forget: its one Gaussian keeps the offsets'
/// covariance with the position, so it can remember far longer (chosen on the moving
/// scenarios, docs/src/tracking.md: 1.06-1.17x the bound on the fixed masts at 1 500 s,
/// 1.4-1.7x at the particle filters' 250; at 2 000 s the two vehicles' ellipses fall short).
pub const EKF_MEMORY_S: f32 = 1500.0;
/// Particles unless told otherwise: enough for the offsets to be remembered 1 500 s
/// ([`particle_memory_s`]), the default's rmse within 1.05-1.33x the bound where it is
/// 1.09-1.74x at 1 000 (docs/src/tracking.md), at 200-400x real time for four stations at 1 Hz
/// on one core.
pub const PARTICLES: usize = 10_000;
/// The default method: the tuned SIR with its shrinkage kernel (a regularised PF) and a
/// Gaussian + uniform likelihood that survives wild bearings.
pub const DEFAULT_METHOD: Method = Method::SirRobust;

/// The methods that track: every particle filter of the registry and the IMM of EKFs.
pub const TRACK_METHODS: [Method; 11] = {
    use Method::*;
    [
        SirRobust, Sir, SirWide, SirSeed, AfsaPf, FaPf, FaPfImp, Gpf, PsoGpf, GsaGpf, Ekf,
    ]
};

/// One update: its time and what was measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Update {
    /// Seconds from the track's start.
    pub t_s: f32,
    /// The measurements (their `dt` from the previous update).
    pub epoch: Epoch<K>,
}

/// How to track.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The estimator.
    pub method: Method,
    /// Particles (one of [`TRACK_PARTICLES`]).
    pub particles: usize,
    /// How the emitter moves.
    pub motion: Motion,
    /// What the state holds.
    pub layout: Layout,
    /// A room the emitter cannot leave, if known.
    pub room: Option<[f32; 2]>,
    /// Each source's offset prior (by source index).
    pub offsets: Vec<BiasPrior>,
    /// Prior sd of the RSSI power offset, dB.
    pub power_sd: f32,
    /// Prior sd of the path-loss exponent correction.
    pub exponent_sd: f32,
    /// P(moving) before the first update.
    pub moving: f32,
    /// Where to start when the first update has no bearing: centre and sd, metres.
    pub region: Option<([f32; 2], f32)>,
    /// Seconds in which the parameters' statistics forget what they learned (their variance
    /// regains the prior's: [`Forgetting`]); none: the method's own ([`particle_memory_s`],
    /// the EKF's [`EKF_MEMORY_S`]).
    pub memory_s: Option<f32>,
    /// Also smooth the track with the fixed lag ([`LAG`] updates).
    pub smooth: bool,
    /// Seed.
    pub seed: u64,
}

impl Settings {
    /// The default tracker for `layout` moving by `motion`.
    pub fn new(layout: Layout, motion: Motion) -> Self {
        Self {
            method: DEFAULT_METHOD,
            particles: PARTICLES,
            motion,
            layout,
            room: None,
            offsets: Vec::new(),
            power_sd: 0.0,
            exponent_sd: 0.0,
            moving: 0.5,
            region: None,
            memory_s: None,
            smooth: false,
            seed: 1,
        }
    }

    fn prior(&self) -> Prior<'_> {
        Prior {
            moving: self.moving,
            speed_sd: self.motion.start_speed_sd,
            offsets: &self.offsets,
            power_sd: self.power_sd,
            exponent_sd: self.exponent_sd,
        }
    }

    /// The core's model of these settings.
    pub fn mover(&self) -> Mover<K> {
        let var = |sd: f32| if sd.is_finite() { sd * sd } else { 0.0 };
        let offset_var = self
            .offsets
            .iter()
            .map(|p| var(p.sd))
            .fold(0.0f32, f32::max);
        Mover {
            motion: self.motion,
            layout: self.layout,
            room: self.room,
            forgetting: Forgetting {
                memory_s: self.memory_s.unwrap_or(if self.method == Method::Ekf {
                    EKF_MEMORY_S
                } else {
                    particle_memory_s(self.particles)
                }),
                offset_var,
                power_var: var(self.power_sd),
                exponent_var: var(self.exponent_sd),
            },
        }
    }
}

/// One point of a track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackPoint {
    /// Seconds from the track's start.
    pub t_s: f32,
    /// Position (east, north), metres.
    pub position: [f32; 2],
    /// Velocity (east, north), m/s.
    pub velocity: [f32; 2],
    /// Covariance of the position, m^2.
    pub covariance: [[f32; 2]; 2],
    /// P(moving).
    pub p_moving: f32,
    /// The filter restarted here (its measurements contradicted every hypothesis).
    pub restarted: bool,
}

impl TrackPoint {
    /// The point of estimate `e` at `t_s`.
    pub fn of<const D: usize>(t_s: f32, e: &Estimate<D>) -> Self {
        Self {
            t_s,
            position: [e.mean[0], e.mean[1]],
            velocity: [e.mean[2], e.mean[3]],
            covariance: position_covariance(&e.covariance),
            p_moving: e.mean[MODE].clamp(0.0, 1.0),
            restarted: e.status == StepStatus::Reinitialised,
        }
    }

    /// The 95 % ellipse, if the covariance gives one.
    pub fn ellipse(&self) -> Option<Ellipse> {
        Ellipse::from_covariance(&self.covariance, 0.95).ok()
    }

    /// Whether `truth` lies inside the 95 % ellipse.
    pub fn covers(&self, truth: [f32; 2]) -> bool {
        self.ellipse()
            .is_some_and(|e| e.contains(&self.position, &truth))
    }
}

/// A tracked run.
#[derive(Debug, Clone, Default)]
pub struct TrackRun {
    /// The filter's point at every update.
    pub points: Vec<TrackPoint>,
    /// The smoothed points (empty unless asked for).
    pub smoothed: Vec<TrackPoint>,
    /// Likelihood evaluations spent.
    pub evaluations: u64,
    /// How the first cloud was made (`None` from a region).
    pub start: Option<InitialCloud>,
    /// The parameters' final means and sds, in [`Layout::means`] order (offsets in radians,
    /// then the RSSI power offset in dB and the exponent correction).
    pub parameters: Vec<(f32, f32)>,
}

/// Run `$body` with `$n` bound to the tracking particle count `$count` (one of
/// [`TRACK_PARTICLES`]), else `Err(Error::Unsupported)`.
macro_rules! with_track_particles {
    ($count:expr, $n:ident => $body:expr) => {
        match $count {
            200 => {
                const $n: usize = 200;
                $body
            }
            1000 => {
                const $n: usize = 1000;
                $body
            }
            2000 => {
                const $n: usize = 2000;
                $body
            }
            10_000 => {
                const $n: usize = 10_000;
                $body
            }
            _ => Err(Error::Unsupported),
        }
    };
}

/// Run `$body` with `$d` bound to the smallest of [`STATE_SIZES`] that holds `$used`
/// components, else `Err(Error::Unsupported)`.
macro_rules! with_state_size {
    ($used:expr, $d:ident => $body:expr) => {
        match $used {
            0..=7 => {
                const $d: usize = 7;
                $body
            }
            8..=10 => {
                const $d: usize = 10;
                $body
            }
            11..=13 => {
                const $d: usize = 13;
                $body
            }
            14..=18 => {
                const $d: usize = 18;
                $body
            }
            _ => Err(Error::Unsupported),
        }
    };
}

/// Track through `updates` as `s` says: the first cloud from the first update's bearings
/// (their crossings, or along them), else from `s.region`; every later update stepped.
pub fn track(updates: &[Update], s: &Settings) -> Result<TrackRun, Error> {
    let mut points = Vec::with_capacity(updates.len());
    let mut run = crate::estimate::pool()
        .install(|| track_each(&mut updates.iter().copied(), s, &mut |p| points.push(p)))?;
    run.points = points;
    Ok(run)
}

/// Track through the updates `next` yields as they come (a live line's: it may block), handing
/// each update's point to `sink` as soon as it is made; the run's `points` stay empty, so a
/// line that never ends keeps nothing but the filter. The filters are built on the stack:
/// call it on a thread with a large stack ([`crate::estimate::pool`]'s, or one of its own).
pub fn track_each(
    next: &mut dyn Iterator<Item = Update>,
    s: &Settings,
    sink: &mut dyn FnMut(TrackPoint),
) -> Result<TrackRun, Error> {
    if !TRACK_METHODS.contains(&s.method) {
        return Err(Error::Unsupported);
    }
    let first = next.next().ok_or(Error::TooFewMeasurements)?;
    let particles = if s.method.uses_particles() {
        s.particles
    } else {
        // The EKF starts from the moments of a cloud: any compiled count makes it.
        PARTICLES
    };
    with_track_particles!(particles, N => {
        with_state_size!(s.layout.dims(), D => run::<N, D>(first, next, s, sink))
    })
}

fn run<const N: usize, const D: usize>(
    first: Update,
    rest: &mut dyn Iterator<Item = Update>,
    s: &Settings,
    sink: &mut dyn FnMut(TrackPoint),
) -> Result<TrackRun, Error> {
    let mut rng = XorShiftRng::seed_from_u64(s.seed);
    let mut cloud = Box::new(ParticleSet::<N, D>::new());
    let bearings = first.epoch.bearings();
    let (start, stepped) = if bearings.is_empty() {
        let (centre, sd) = s.region.ok_or(Error::TooFewMeasurements)?;
        (Start::Region(centre, sd), true)
    } else {
        (Start::Bearings(bearings), false)
    };
    let how = initial_cloud(start, &s.layout, &s.prior(), &mut cloud, &mut rng)?;
    let drive = Drive {
        cloud: &cloud.states,
        first,
        stepped,
        rest,
        sink,
        rng: &mut rng,
        smoother: s.smooth.then(|| FixedLag::<D, LAG>::new(s.motion)),
        layout: s.layout,
    };
    let mut run = with_moving_filter::<N, D, K, _>(s.method, s.mover(), drive)??;
    run.start = matches!(start, Start::Bearings(_)).then_some(how);
    Ok(run)
}

/// The visitor that steps a filter through the updates.
struct Drive<'a, const D: usize> {
    cloud: &'a [[f32; D]],
    first: Update,
    /// Whether the first update is stepped (it did not make the cloud).
    stepped: bool,
    rest: &'a mut dyn Iterator<Item = Update>,
    sink: &'a mut dyn FnMut(TrackPoint),
    rng: &'a mut XorShiftRng,
    smoother: Option<FixedLag<D, LAG>>,
    layout: Layout,
}

impl<const D: usize> WithFilter<D, Epoch<K>> for Drive<'_, D> {
    type Output = Result<TrackRun, Error>;

    fn visit<F: Filter<D, Measurement = Epoch<K>>>(mut self, f: &mut F) -> Self::Output {
        f.initialise(self.cloud, self.rng)?;
        let mut run = TrackRun::default();
        let mut held_times = std::collections::VecDeque::new();
        let mut previous = self.first.t_s;
        let mut step = self.stepped;
        for u in core::iter::once(self.first).chain(&mut *self.rest) {
            let e = if step {
                match f.step(&u.epoch, self.rng) {
                    Ok(e) => e,
                    Err(_) => f.estimate()?,
                }
            } else {
                f.estimate()?
            };
            step = true;
            (self.sink)(TrackPoint::of(u.t_s, &e));
            if let Some(s) = self.smoother.as_mut() {
                held_times.push_back(u.t_s);
                if let Some(sm) = s.push(e, u.t_s - previous) {
                    let t = held_times.pop_front().unwrap_or(u.t_s);
                    run.smoothed.push(TrackPoint::of(t, &sm));
                }
            }
            previous = u.t_s;
        }
        if let Some(s) = self.smoother.as_mut() {
            s.drain(|e| {
                let t = held_times.pop_front().unwrap_or(previous);
                run.smoothed.push(TrackPoint::of(t, &e));
            });
        }
        let last = f.estimate()?;
        run.evaluations = f.evaluations();
        run.parameters = parameters(&self.layout, &last);

        Ok(run)
    }
}

/// Each parameter's estimate and sd from a filter's estimate, [`Layout::means`] order: the
/// mean of the particles' means, and the sd from the mean of their variances plus the spread
/// of their means (a Kalman filter's own variance sits in the spread).
pub fn parameters<const D: usize>(layout: &Layout, e: &Estimate<D>) -> Vec<(f32, f32)> {
    let variance_of = |m: usize| -> Option<usize> {
        match layout.rssi() {
            Some(r) if m == r => Some(r + 2),
            Some(r) if m == r + 1 => Some(r + 4),
            _ => (m >= PARAMETERS).then_some(m + 1),
        }
    };
    layout
        .means()
        .filter(|m| *m < D)
        .map(|m| {
            let within = variance_of(m).filter(|v| *v < D).map_or(0.0, |v| e.mean[v]);
            let var = (within + e.covariance[m][m]).max(0.0);
            (e.mean[m], var.sqrt())
        })
        .collect()
}
