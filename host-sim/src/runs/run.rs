//! One seeded run of one method on a scenario: what the bench averages and the criterion
//! benches time.

use crate::estimate::{BearingFix, Steps, locate_bearings};
use crate::runs::scenario::{Drive, Scenario, ScenarioModel};
use crate::runs::tracking::{Truth, prior_cloud, prior_var};
use foxhunt_core::estimator::with_particle_filter;
use foxhunt_core::{Error, Estimate, Method, Model, Ungm, with_particles};
use rand_xorshift::XorShiftRng;

/// One bearing-scenario run: the drive's noisy bearings are drawn from `rng` first, then the
/// method runs on them (only that part is timed by callers, see [`bearing_run_timed`]).
pub fn bearing_run(
    d: &Drive,
    method: Method,
    particles: usize,
    rng: &mut XorShiftRng,
) -> Result<BearingFix, Error> {
    bearing_run_timed(d, method, particles, rng).0
}

/// [`bearing_run`] and the seconds its estimation took.
pub fn bearing_run_timed(
    d: &Drive,
    method: Method,
    particles: usize,
    rng: &mut XorShiftRng,
) -> (Result<BearingFix, Error>, f64) {
    let bearings = d.simulate(rng);
    let t = std::time::Instant::now();
    let r = locate_bearings(method, particles, d.process_var, &bearings, false, rng);
    (r, t.elapsed().as_secs_f64())
}

/// One tracking run: the sum over steps of the position error (Euclidean for the RSSI node,
/// absolute for the UNGM), the likelihood evaluations, and the seconds the filter took.
pub fn tracking_run(
    s: &Scenario,
    method: Method,
    particles: usize,
    run: usize,
) -> (Result<(f64, u64), Error>, f64) {
    let mut rng = s.rng(run);
    let Some(truth) = crate::runs::tracking::simulate(s, &mut rng) else {
        return (Err(Error::Unsupported), 0.0);
    };
    let var = prior_var(s);
    let t = std::time::Instant::now();
    let r = (|| {
        with_particles!(particles, N => match (&s.model, &truth) {
            (ScenarioModel::Rssi { tracker, start, .. }, Truth::Rssi(x, z)) => {
                let cloud = prior_cloud::<N, 4>(*start, var, &mut rng)?;
                let err = |k: usize, e: &Estimate<4>| {
                    ((e.mean[0] - x[k][0]) as f64).hypot((e.mean[2] - x[k][2]) as f64)
                };
                track::<N, 4, _>(method, *tracker, &cloud.states, z, err, &mut rng)
            }
            (ScenarioModel::Ungm { .. }, Truth::Ungm(x, z)) => {
                let cloud = prior_cloud::<N, 1>([0.1, 0.0, 0.0, 0.0], var, &mut rng)?;
                let err = |k: usize, e: &Estimate<1>| ((e.mean[0] - x[k]) as f64).abs();
                track::<N, 1, _>(method, Ungm::default(), &cloud.states, z, err, &mut rng)
            }
            _ => Err(Error::Unsupported),
        })
    })();
    (r, t.elapsed().as_secs_f64())
}

/// Step particle method `method` on `model` through `z`, summing `error` over the steps.
fn track<const N: usize, const D: usize, M: Model<D> + Copy>(
    method: Method,
    model: M,
    cloud: &[[f32; D]],
    z: &[M::Measurement],
    mut error: impl FnMut(usize, &Estimate<D>) -> f64,
    rng: &mut XorShiftRng,
) -> Result<(f64, u64), Error> {
    let mut sum = 0.0f64;
    let steps = Steps {
        cloud,
        measurements: z,
        rng,
        each: |k, e: &Estimate<D>| sum += error(k, e),
        keep_cloud: false,
    };
    let run = with_particle_filter::<N, D, M, _>(method, model, steps)??;
    if sum.is_finite() {
        Ok((sum, run.evaluations))
    } else {
        Err(Error::NonFinite)
    }
}
