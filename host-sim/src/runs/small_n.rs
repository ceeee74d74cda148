//! Honest at every sample size: the coverage of every noise-estimating method's 95 % ellipse
//! with a handful of bearings (`foxhunt bench --scenario small-n`).
//!
//! A run: n bearings spread evenly along the field conditions' 9 km U around an emitter at
//! (0, 1500) m, true noise 3 degrees where the unit states 2 (only an estimated noise can be
//! honest), no offset. Each method estimates the noise from its residuals (the plain methods
//! RSS / (n - 2); the robust ones from their inliers; the field pipeline its own way) and
//! scales its ellipse by 2 F(2, dof). The row counts the runs whose ellipse held the truth among
//! those that gave a fix, and how many gave one: a method that refuses a sample too small to
//! judge is honest, one that answers with a chi-square ellipse is not.

use crate::estimate::noise::with_estimated_noise;
use crate::outputs::tables::Row;
use crate::runs::field::{FieldDrive, THREE_SIGMA_TAIL, Truth, judge, run_locate, u_route};
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::consistency::ellipse_scale;
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::{LocateConfig, Observation};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::{Method, random};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;

/// The sample sizes of the table.
pub const SIZES: [usize; 6] = [4, 5, 7, 10, 20, 50];

/// The methods that estimate the noise, as `foxhunt locate` runs them.
pub const METHODS: [Method; 7] = [
    Method::Ml,
    Method::MlHuber,
    Method::Sir,
    Method::SirRobust,
    Method::Gpf,
    Method::Ekf,
    Method::MlRobust,
];

/// Particles of the particle methods (what `locate` uses).
const PARTICLES: usize = 1000;

/// Where the emitter is, local metres.
const EMITTER: [f32; 2] = [0.0, 1500.0];

/// The true bearing noise and the one the unit states, degrees.
const TRUE_SIGMA_DEG: f32 = 3.0;
const STATED_SIGMA_DEG: f32 = 2.0;

/// The bearings of run `run` at sample size `n`.
pub fn drive(n: usize, run: usize) -> FieldDrive {
    let mut rng = XorShiftRng::seed_from_u64(
        (n as u64 + 1)
            .wrapping_mul(0xD1B5_4A32_D192_ED03)
            .wrapping_add(run as u64),
    );
    // n points spread over the U's whole length (its ends included).
    let full = u_route(240);
    let sigma = TRUE_SIGMA_DEG.to_radians();
    let observations = (0..n)
        .map(|k| {
            let v = full[(k * 239) / (n - 1).max(1)];
            let b = Bearing {
                vehicle: v,
                theta: wrap(predicted(&EMITTER, &v) + sigma * random::normal(&mut rng)),
                sigma: STATED_SIGMA_DEG.to_radians(),
            };
            Observation::new(b, k as f32)
        })
        .collect();
    FieldDrive {
        observations,
        emitters: vec![Truth {
            position: EMITTER,
            freq_mhz: None,
        }],
        ghost: None,
        bias: 0.0,
        sigma,
    }
}

/// One run judged: (error m, inside the 95 % ellipse, within CEP50, beyond 3 sigma), or
/// `None` when the method gave no fix.
type Judged = Option<(f64, bool, bool, bool)>;

fn one(m: Method, n: usize, run: usize) -> Judged {
    let d = drive(n, run);
    if m == Method::MlRobust {
        let config = LocateConfig::default();
        let r = run_locate(&d, &config, run as u64).ok();
        let j = judge(&d, r.as_ref(), config.priors[0]);
        let j = j.first().filter(|j| j.found)?;
        return Some((
            f64::from(j.error),
            j.covered,
            j.within_cep50,
            j.tail < THREE_SIGMA_TAIL,
        ));
    }
    let bearings: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
    let mut rng = XorShiftRng::seed_from_u64(run as u64);
    let (f, _) = with_estimated_noise(m, PARTICLES, 0.0, &bearings, false, &mut rng).ok()?;
    let md = mahalanobis(&f.covariance, &f.position, &EMITTER).unwrap_or(f32::INFINITY);
    let error = (f.position[0] - EMITTER[0]).hypot(f.position[1] - EMITTER[1]);
    let three = ellipse_scale(1.0 - THREE_SIGMA_TAIL, f.dof).unwrap_or(f32::INFINITY);
    Some((
        f64::from(error),
        md * md <= f.ellipse_scale,
        error <= f.cep50,
        md * md > three,
    ))
}

/// The row of method `m` at sample size `n` over `runs` seeded runs.
pub fn row(m: Method, n: usize, runs: usize) -> Row {
    let t = std::time::Instant::now();
    let outcomes: Vec<Judged> = crate::estimate::pool()
        .install(|| (0..runs).into_par_iter().map(|r| one(m, n, r)).collect());
    let mut row = Row::new(format!("small-n/n={n}"), m, PARTICLES, runs);
    row.time_s = t.elapsed().as_secs_f64() / runs.max(1) as f64;
    let fixes: Vec<(f64, bool, bool, bool)> = outcomes.iter().flatten().copied().collect();
    let k = fixes.len();
    row.failures = runs - k;
    row.found = Some(k as f64 / runs.max(1) as f64);
    // The bound of the geometry at the true noise, the same for every run of a size.
    let geometry: Vec<Bearing> = drive(n, 0)
        .observations
        .iter()
        .map(|o| Bearing {
            theta: predicted(&EMITTER, &o.bearing.vehicle),
            sigma: TRUE_SIGMA_DEG.to_radians(),
            ..o.bearing
        })
        .collect();
    row.crlb = crlb(&EMITTER, &geometry)
        .ok()
        .map(|b| f64::from(b.rmse))
        .filter(|b| b.is_finite());
    if k > 0 {
        let mse = fixes.iter().map(|f| f.0 * f.0).sum::<f64>() / k as f64;
        row.rmse = Some(mse.sqrt());
        row.ratio = row.rmse.zip(row.crlb).map(|(r, b)| r / b);
        row.coverage = Some(fixes.iter().filter(|f| f.1).count() as f64 / k as f64);
        row.cep50_share = Some(fixes.iter().filter(|f| f.2).count() as f64 / k as f64);
        row.beyond_3_sigma = Some(fixes.iter().filter(|f| f.3).count());
    }
    if m == Method::MlRobust {
        row.note = Some(format!(
            "offset estimated with the default prior (sd {:.0} deg)",
            BiasPrior::default().sd.to_degrees()
        ));
    }
    row
}

/// The whole table: every method at every size, `runs` runs each.
pub fn bench(runs: usize) -> Vec<Row> {
    SIZES
        .iter()
        .flat_map(|&n| METHODS.iter().map(move |&m| row(m, n, runs)))
        .collect()
}
