//! The moving-emitter tracker on the MCU (docs/src/firmware.md, "Tracking a moving emitter on
//! the microcontroller"): the default tracker of the host (the tuned SIR with the Gaussian +
//! uniform likelihood on [`Mover`], four stations' offsets Rao-Blackwellised: 13 components)
//! at `N` particles, four fixed stations at the corners of an 8 km square each reporting a
//! bearing ten times a second (2 degree noise, each unit off by an offset drawn from N(0, 2
//! degrees), the tracker's prior), a drone crossing it east at 12 m/s from (1200, 2000) m.
//!
//! Parts, each run as its own image invocation so that QEMU's instruction count of one part
//! is a difference of two (`serial-bridge/qemu/track-steps.sh`): `epochs` builds each step's
//! epoch and nothing else; `predict` adds the motion ([`Model::propagate_all`]); `weigh` adds
//! the four bearings' weighting and Kalman steps ([`Model::update_all`]), the normalisation
//! and the weighted moments; `resample` adds a systematic resampling and the shrinkage kernel
//! on every step; `step` is the filter itself ([`Sir::step`]: resampling only when the
//! effective sample size falls below N / 2). Every part prints the final position error, the
//! filter's bytes and the painted stack's high-water mark.

use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::likelihood::GaussianUniform;
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::roughen::KERNEL_PERIOD_S;
use foxhunt_core::track::init::{Prior, Start, initial_cloud};
use foxhunt_core::track::{Epoch, Forgetting, Layout, Motion, Mover};
use foxhunt_core::{Error, Filter, Model, ParticleSet, Sir, SirConfig, random};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Stations (each one DF source with its own offset).
const STATIONS: usize = 4;
/// State components: position, velocity, mode, and a mean and variance per offset.
pub const D: usize = 5 + 2 * STATIONS;
/// Seconds between updates (10 Hz).
const DT: f32 = 0.1;
/// Bearing noise and offset sd, radians (2 degrees).
const SIGMA: f32 = 2.0 * core::f32::consts::PI / 180.0;
/// The drone's start and velocity.
const START: [f32; 2] = [1200.0, 2000.0];
const VELOCITY: [f32; 2] = [12.0, 0.0];
/// The stations: the square's corners.
const AT: [[f32; 2]; STATIONS] = [[0.0, 0.0], [8000.0, 0.0], [8000.0, 8000.0], [0.0, 8000.0]];
/// Seconds left out of the rmse (the tracker finding the emitter), as on the host.
pub const WARMUP_S: f32 = 30.0;
/// The host's: the parameters forget in two minutes (docs/src/tracking.md).
const MEMORY_S: f32 = 120.0;

/// Which parts of a step run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Part {
    /// Build the epoch only.
    Epochs,
    /// And predict.
    Predict,
    /// And weigh.
    Weigh,
    /// And resample every step.
    Resample,
    /// The filter's own step.
    Step,
}

impl Part {
    /// The part of a name.
    pub fn named(name: &str) -> Option<Part> {
        Some(match name {
            "epochs" => Part::Epochs,
            "predict" => Part::Predict,
            "weigh" => Part::Weigh,
            "resample" => Part::Resample,
            "step" => Part::Step,
            _ => return None,
        })
    }
}

fn mover() -> Mover<STATIONS> {
    Mover {
        forgetting: Forgetting {
            memory_s: MEMORY_S,
            offset_var: SIGMA * SIGMA,
            power_var: 0.0,
            exponent_var: 0.0,
        },
        ..Mover::new(
            Motion::OUTDOOR,
            Layout {
                sources: STATIONS as u8,
                rssi: false,
            },
        )
    }
}

/// The emitter at step `k`.
fn truth(k: usize) -> [f32; 2] {
    let t = k as f32 * DT;
    [START[0] + VELOCITY[0] * t, START[1] + VELOCITY[1] * t]
}

/// Step `k`'s epoch: a bearing from every station, off by its offset and noise.
fn epoch(k: usize, offsets: &[f32; STATIONS], rng: &mut XorShiftRng) -> Epoch<STATIONS> {
    let p = truth(k);
    let mut e = Epoch::new(if k == 0 { 0.0 } else { DT });
    for (s, at) in AT.iter().enumerate() {
        let theta = wrap(predicted(&p, at) + offsets[s] + SIGMA * random::normal(rng));
        let mut o = Observation::new(
            Bearing {
                vehicle: *at,
                theta,
                sigma: SIGMA,
            },
            k as f32 * DT,
        );
        o.station = s as u16;
        // STATIONS fit the epoch.
        let _ = e.push_bearing(o);
    }
    e
}

/// What one run gives: the final position error (metres), the state's bytes (the filter, or
/// the particle set the staged parts work on).
pub struct Ran {
    /// Distance from the truth after the last step, metres.
    pub error: f32,
    /// Root mean square of the distance over the steps after [`WARMUP_S`], metres (NaN
    /// when the run is shorter).
    pub rmse: f32,
    /// Bytes of the tracker's state.
    pub bytes: usize,
}

/// The run's setting: the true offsets, the model, the first cloud's prior.
struct Setting {
    offsets: [f32; STATIONS],
    model: Mover<STATIONS>,
    priors: [BiasPrior; STATIONS],
}

impl Setting {
    fn new(rng: &mut XorShiftRng) -> Self {
        Setting {
            offsets: core::array::from_fn(|_| SIGMA * random::normal(rng)),
            model: mover(),
            priors: [BiasPrior {
                mean: 0.0,
                sd: SIGMA,
            }; STATIONS],
        }
    }

    /// The first cloud, from the first epoch's crossings.
    fn first<const N: usize>(
        &self,
        set: &mut ParticleSet<N, D>,
        rng: &mut XorShiftRng,
    ) -> Result<(), Error> {
        let prior = Prior {
            moving: 0.5,
            speed_sd: self.model.motion.start_speed_sd,
            offsets: &self.priors,
            power_sd: 0.0,
            exponent_sd: 0.0,
        };
        let first = epoch(0, &self.offsets, rng);
        initial_cloud(
            Start::Bearings(first.bearings()),
            &self.model.layout,
            &prior,
            set,
            rng,
        )?;
        Ok(())
    }
}

/// The host's robust likelihood (`sir-robust`: 5 % wild bearings).
const LIKELIHOOD: GaussianUniform = GaussianUniform { eps: 0.05 };

/// Run `part` for `steps` steps at `N` particles, the noise and offsets drawn from `seed`. `settled` is called once the first cloud is
/// made, before the first step (the image repaints its stack there: the start's one-off
/// frame is not what a running tracker needs).
#[inline(never)]
pub fn run<const N: usize>(
    part: Part,
    steps: usize,
    seed: u64,
    settled: fn(),
) -> Result<Ran, Error> {
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let setting = Setting::new(&mut rng);
    if part == Part::Step {
        filtered::<N>(&setting, steps, settled, &mut rng)
    } else {
        by_hand::<N>(part, &setting, steps, settled, &mut rng)
    }
}

/// The filter's own steps.
#[inline(never)]
fn filtered<const N: usize>(
    setting: &Setting,
    steps: usize,
    settled: fn(),
    rng: &mut XorShiftRng,
) -> Result<Ran, Error> {
    let mut filter = Sir::<_, _, N, D>::new(setting.model, LIKELIHOOD, SirConfig::TUNED);
    start(setting, &mut filter, rng)?;
    settled();
    let mut position = truth(0);
    let mut errors = Errors::default();
    for k in 1..=steps {
        let z = epoch(k, &setting.offsets, rng);
        if let Ok(e) = filter.step(&z, rng) {
            position = [e.mean[0], e.mean[1]];
        }
        errors.add(k, position);
    }
    Ok(errors.ran(position, steps, core::mem::size_of_val(&filter)))
}

/// The parts up to `part`, by hand.
#[inline(never)]
fn by_hand<const N: usize>(
    part: Part,
    setting: &Setting,
    steps: usize,
    settled: fn(),
    rng: &mut XorShiftRng,
) -> Result<Ran, Error> {
    let mut set = ParticleSet::<N, D>::new();
    setting.first(&mut set, rng)?;
    settled();
    let mut position = truth(0);
    let mut errors = Errors::default();
    for k in 1..=steps {
        let z = epoch(k, &setting.offsets, rng);
        position = match part {
            Part::Epochs => [position[0] + z.bearings()[0].bearing.theta, position[1]],
            _ => staged(part, &setting.model, &mut set, &z, rng),
        };
        errors.add(k, position);
    }
    Ok(errors.ran(position, steps, core::mem::size_of_val(&set)))
}

/// The squared errors after the warm-up.
#[derive(Default)]
struct Errors {
    sum: f32,
    count: u32,
}

impl Errors {
    fn add(&mut self, k: usize, position: [f32; 2]) {
        if k as f32 * DT >= WARMUP_S {
            let p = truth(k);
            let (dx, dy) = (position[0] - p[0], position[1] - p[1]);
            self.sum += dx * dx + dy * dy;
            self.count += 1;
        }
    }

    fn ran(&self, position: [f32; 2], steps: usize, bytes: usize) -> Ran {
        let p = truth(steps);
        Ran {
            error: libm::hypotf(position[0] - p[0], position[1] - p[1]),
            rmse: libm::sqrtf(self.sum / self.count as f32),
            bytes,
        }
    }
}

/// Start `filter` from the first cloud, made in this frame (gone once it returns).
#[inline(never)]
fn start<const N: usize>(
    setting: &Setting,
    filter: &mut Sir<Mover<STATIONS>, GaussianUniform, N, D>,
    rng: &mut XorShiftRng,
) -> Result<(), Error> {
    let mut set = ParticleSet::<N, D>::new();
    setting.first(&mut set, rng)?;
    filter.initialise(&set.states, rng)
}

/// The parts of a step up to `part` on `set`, by hand (what [`Sir::step`] does, without its
/// checks and with resampling on every step); the weighted mean's position.
#[inline(never)]
fn staged<const N: usize>(
    part: Part,
    model: &Mover<STATIONS>,
    set: &mut ParticleSet<N, D>,
    z: &Epoch<STATIONS>,
    rng: &mut XorShiftRng,
) -> [f32; 2] {
    model.propagate_all(&mut set.states, z, rng);
    if part < Part::Weigh {
        return [set.states[0][0], set.states[0][1]];
    }
    model.update_all(&mut set.states, z, &LIKELIHOOD, &mut set.log_weights);
    if set.normalise().is_err() {
        set.set_uniform_weights();
    }
    let mean = set.mean();
    let covariance = set.covariance(&mean);
    if part >= Part::Resample {
        let config = SirConfig::TUNED;
        set.resample(config.resampling, rng);
        let kernel = <Mover<STATIONS> as Model<D>>::regularised(model, &covariance);
        config.roughening.apply_to(
            set,
            &mean,
            &covariance,
            &kernel,
            z.dt / KERNEL_PERIOD_S,
            rng,
        );
    }
    [mean[0], mean[1]]
}
