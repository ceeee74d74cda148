//! Tracking scenarios: the indoor RSSI node (seed 003) and the UNGM (seed 001), their
//! simulated truth, and their posterior Cramér-Rao bound.
//!
//! The room (chosen): the RSSI node moves in the scenario's area and reflects off its walls
//! (position mirrored, that velocity component reversed), and the filters' model knows the room.
//! Under the literal model, Q = diag(1/2, 1, 1/2, 1) makes the velocity a random walk and the
//! node drifts 100-200 m from a 10 m anchor triangle within 60 steps, where no filter can reach
//! the seed's 0.3-1.3 m; the table gives an area, so the node stays in it. A filter that did not
//! know the walls loses the node at its first fast bounce (a reversal of 2v in one step, with
//! unit velocity noise): that was measured, at 6-24 m even with 2000 particles.
//!
//! The error figure is the seeds' "average RMSE" (seed 003 eq. 10): the mean over steps and runs
//! of the Euclidean position error, (1/M) sum_k (1/N_mc) sum_runs |x_hat_k - x_k|. The bound is
//! the same average of the PCRB, (1/M) sum_k sqrt(tr J_k^-1) over the position components.

use crate::runs::scenario::{Scenario, ScenarioModel};
use foxhunt_core::fix::pcrb::pcrb_step;
use foxhunt_core::{
    Model, ParticleSet, RssiMeasurement, RssiTracker, Ungm, UngmObservation, linalg, random,
};
use rand_xorshift::XorShiftRng;

/// One simulated tracking run: the true states and what was measured at each step.
pub enum Truth {
    /// RSSI: states [x, vx, y, vy] and each step's readings.
    Rssi(Vec<[f32; 4]>, Vec<RssiMeasurement<3>>),
    /// UNGM: states and observations.
    Ungm(Vec<f32>, Vec<UngmObservation>),
}

/// Simulate one run of the RSSI node.
pub fn simulate_rssi(
    tracker: &RssiTracker<3>,
    start: [f32; 4],
    steps: usize,
    rng: &mut XorShiftRng,
) -> (Vec<[f32; 4]>, Vec<RssiMeasurement<3>>) {
    let mut x = start;
    let (mut states, mut readings) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    for _ in 0..steps {
        tracker.propagate(&mut x, &RssiMeasurement::all([0.0; 3]), rng);
        let h = tracker.expected(&x);
        let dbm = std::array::from_fn(|i| h[i] + tracker.sigma[i] * random::normal(rng));
        readings.push(RssiMeasurement::all(dbm));
        states.push(x);
    }
    (states, readings)
}

/// Simulate one run of the UNGM from x0 = 0.1.
pub fn simulate_ungm(steps: usize, rng: &mut XorShiftRng) -> (Vec<f32>, Vec<UngmObservation>) {
    let ungm = Ungm::default();
    let mut x = [0.1f32];
    let (mut states, mut obs) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    for k in 1..=steps as u32 {
        ungm.propagate(&mut x, &UngmObservation { k, z: 0.0 }, rng);
        let z = Ungm::observe(x[0]) + random::normal(rng);
        obs.push(UngmObservation { k, z });
        states.push(x[0]);
    }
    (states, obs)
}

/// One run's truth for a tracking scenario (`None` for a bearing scenario).
pub fn simulate(s: &Scenario, rng: &mut XorShiftRng) -> Option<Truth> {
    match &s.model {
        ScenarioModel::Rssi {
            tracker,
            start,
            steps,
        } => {
            let (x, z) = simulate_rssi(tracker, *start, *steps, rng);
            Some(Truth::Rssi(x, z))
        }
        ScenarioModel::Ungm { steps } => {
            let (x, z) = simulate_ungm(*steps, rng);
            Some(Truth::Ungm(x, z))
        }
        ScenarioModel::Bearing(_) => None,
    }
}

/// Prior variances of the filters' initial state (chosen: the process noise for the RSSI
/// node, variance 2 for the UNGM).
pub fn prior_var(s: &Scenario) -> [f32; 4] {
    match &s.model {
        ScenarioModel::Rssi { tracker, .. } => tracker.q,
        _ => [2.0, 0.0, 0.0, 0.0],
    }
}

/// The filters' initial cloud: N draws about the true start with the prior variances.
pub fn prior_cloud<const N: usize, const D: usize>(
    start: [f32; 4],
    var: [f32; 4],
    rng: &mut XorShiftRng,
) -> Result<Box<ParticleSet<N, D>>, foxhunt_core::Error> {
    let mean: [f32; D] = std::array::from_fn(|i| start[i]);
    let cov: [[f32; D]; D] =
        std::array::from_fn(|i| std::array::from_fn(|j| if i == j { var[i] } else { 0.0 }));
    let mut set = Box::new(ParticleSet::<N, D>::new());
    set.draw_gaussian(&mean, &cov, rng)?;
    Ok(set)
}

/// The posterior CRB of a tracking scenario averaged over steps (module docs), with the
/// expectations over true trajectories taken over the runs' own simulated truths. `None` for
/// a bearing scenario or when the recursion breaks down.
pub fn pcrb(s: &Scenario) -> Option<f64> {
    let truths: Vec<Truth> = (0..s.runs)
        .filter_map(|r| simulate(s, &mut s.rng(r)))
        .collect();
    let var = prior_var(s);
    let n = truths.len() as f64;
    match &s.model {
        ScenarioModel::Rssi { tracker, steps, .. } => {
            let mut j = [[0.0f32; 4]; 4];
            for i in 0..4 {
                j[i][i] = 1.0 / var[i];
            }
            let q: [[f32; 4]; 4] = std::array::from_fn(|i| {
                std::array::from_fn(|k| if i == k { tracker.q[i] } else { 0.0 })
            });
            let f = tracker.transition();
            let mut total = 0.0f64;
            for k in 0..*steps {
                let mut info = [[0.0f32; 4]; 4];
                for tr in &truths {
                    let Truth::Rssi(x, _) = tr else { continue };
                    let ik = tracker.information(&x[k]);
                    for a in 0..4 {
                        for b in 0..4 {
                            info[a][b] += ik[a][b] / n as f32;
                        }
                    }
                }
                j = pcrb_step(&j, &f, &q, &info).ok()?;
                let p = linalg::inverse_spd(&j)?;
                total += ((p[0][0] + p[2][2]) as f64).sqrt();
            }
            Some(total / *steps as f64)
        }
        ScenarioModel::Ungm { steps } => {
            // Scalar Tichavsky recursion with the expectations over the truths:
            // D11 = E[f'(x)^2]/Q, D12 = -E[f'(x)]/Q, D22 = 1/Q + E[h'(x)^2]/R.
            let u = Ungm::default();
            let (qv, rv) = (u.process_var as f64, u.measurement_var as f64);
            let mut j = 1.0 / var[0] as f64;
            let mut total = 0.0;
            let mut prev: Vec<f64> = vec![0.1; truths.len()];
            for k in 0..*steps {
                let (mut d11, mut d12, mut hh) = (0.0, 0.0, 0.0);
                for (tr, xp) in truths.iter().zip(prev.iter_mut()) {
                    let Truth::Ungm(x, _) = tr else { continue };
                    let fp = 0.5 + 25.0 * (1.0 - *xp * *xp) / (1.0 + *xp * *xp).powi(2);
                    d11 += fp * fp / qv / n;
                    d12 -= fp / qv / n;
                    let x = x[k] as f64;
                    hh += (x / 10.0) * (x / 10.0) / rv / n;
                    *xp = x;
                }
                let d22 = 1.0 / qv + hh;
                j = d22 - d12 * d12 / (j + d11);
                total += (1.0 / j).sqrt();
            }
            Some(total / *steps as f64)
        }
        ScenarioModel::Bearing(_) => None,
    }
}
