//! The trackers' baseline: per-epoch triangulation. Each update's bearings (one of every
//! station) are intersected on their own by the core's Gaussian maximum-likelihood fix
//! ([`foxhunt_core::fix::ml`], least squares on the angles from the bias-compensated PLE),
//! with no memory of earlier epochs and no offset: what a tracker must beat to be worth its
//! state.

use super::MovingRun;
use super::bench::RunFigures;
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::fix::ml::{MlOptions, ml};
use foxhunt_core::likelihood::Gaussian;
use foxhunt_core::model::bearing::Bearing;

/// One run triangulated epoch by epoch, from `warmup` seconds on: the errors and 95 %
/// coverage of the epochs that gave a fix, and how many of the counted epochs gave none.
pub fn triangulate(run: &MovingRun, warmup: f32) -> (RunFigures, usize) {
    let mut f = RunFigures::default();
    let mut missed = 0;
    let t0 = std::time::Instant::now();
    for (u, (x, _, _)) in run.updates.iter().zip(&run.truth) {
        if u.t_s < warmup {
            continue;
        }
        let bearings: Vec<Bearing> = u.epoch.bearings().iter().map(|o| o.bearing).collect();
        let Ok(fix) = ml(&bearings, None, &Gaussian, MlOptions::default()) else {
            missed += 1;
            continue;
        };
        let p = fix.position;
        f.errors.push((p[0] - x[0]).hypot(p[1] - x[1]));
        f.covered
            .push(Ellipse::from_covariance(&fix.covariance, 0.95).is_ok_and(|e| e.contains(&p, x)));
        f.evaluations += u64::from(fix.iterations);
    }
    f.seconds = t0.elapsed().as_secs_f64();
    (f, missed)
}
