//! The bearing noise a fix's residuals give, for every method that estimates it (all but the
//! field pipeline, which does its own), with honest degrees of freedom.
//!
//! With the noise estimated from n residuals of a fit with p = 2 position unknowns, the
//! unbiased variance is RSS / (n - p), and the confidence region is 2 F(2, n - p) wide, not
//! chi-square(2): with 5 bearings the 95 % ellipse is 1.9 times wider in each axis (docs/src/
//! field.md, "Honest intervals"). A method whose likelihood down-weights wild bearings
//! ([`Method::robust_loss`]) estimates it from the inliers (a MAD cut), with the inliers'
//! degrees of freedom; a plain one from every residual, as its fit used them.

use super::{BearingFix, Noise, locate_bearings};
use foxhunt_core::estimator::batch_fix;
use foxhunt_core::fix::consistency::ellipse_scale;
use foxhunt_core::fix::crlb::information;
use foxhunt_core::fix::ellipse::{Ellipse, cep50_of};
use foxhunt_core::fix::noise::chance_cut;
use foxhunt_core::linalg::eigen2;
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{Bearing, Error, Method};
use rand_xorshift::XorShiftRng;

/// Unknowns of a fix's position.
const POSITION_UNKNOWNS: usize = 2;

/// The share of a Gaussian's variance inside +-c standard deviations: the inliers' RMS is
/// corrected by it (0.9733 at 3, 0.998 at 3.7).
fn kept_variance(c: f64) -> f64 {
    let inside = libm::erf(c / core::f64::consts::SQRT_2);
    let density = (-0.5 * c * c).exp() / (2.0 * core::f64::consts::PI).sqrt();
    (1.0 - 2.0 * c * density / inside).clamp(0.5, 1.0)
}

/// Rounds of the robust cut at most (it settles in a few).
const MAX_ROUNDS: usize = 20;

/// Smallest noise a fix states, radians: residuals of a few hundredths of a degree are a
/// simulation's, not a DF unit's.
const FLOOR_DEG: f32 = 0.05;

/// Bearing noise from the residuals at `p`, as `method`'s fit weighed them: every residual for a
/// plain method (RSS / (n - 2)); for a robust one the inliers' RMS over n_in - 2, corrected for
/// the cut, the inliers those within what chance allows the largest of n residuals at that
/// noise (started from a cut at 3 MADs). `None` when fewer than
/// three residuals remain: two bearings leave no degree of freedom to judge their noise by.
pub fn estimate_noise(bearings: &[Bearing], p: &[f32; 2], robust: bool) -> Option<Noise> {
    let floor = FLOOR_DEG.to_radians();
    let mut r: Vec<f32> = bearings
        .iter()
        .map(|b| wrap(b.theta - predicted(p, &b.vehicle)).abs())
        .filter(|r| r.is_finite())
        .collect();
    if r.len() <= POSITION_UNKNOWNS {
        return None;
    }
    let (used, correction) = if robust {
        let n = r.len();
        let mid = n / 2;
        let (_, median, _) = r.select_nth_unstable_by(mid, f32::total_cmp);
        // Gross outliers out first (a MAD is not moved by them), then the cut set by the
        // inliers' own noise: a residual is wild when it lies beyond what chance allows the
        // largest of n Gaussian residuals (Student-t at the inliers' degrees of freedom,
        // Bonferroni over n), repeated until the inliers settle. A cut at a fixed 3 MADs drops
        // good bearings of a small sample (its MAD is often small) and understates the noise.
        let mut cut = 3.0 * (1.4826 * *median).max(floor);
        let mut kept = usize::MAX;
        let mut keep_share = 1.0f64;
        for _ in 0..MAX_ROUNDS {
            let inliers: Vec<f32> = r.iter().copied().filter(|x| *x <= cut).collect();
            if inliers.len() == kept || inliers.len() <= POSITION_UNKNOWNS {
                break;
            }
            kept = inliers.len();
            let dof = (kept - POSITION_UNKNOWNS) as f32;
            let ss: f64 = inliers.iter().map(|x| f64::from(x * x)).sum();
            let scale = ((ss / f64::from(dof) / keep_share).sqrt() as f32).max(floor);
            let c = chance_cut(n, dof).unwrap_or(3.0);
            keep_share = kept_variance(f64::from(c));
            cut = c * scale;
        }
        r.retain(|x| *x <= cut);
        (r, keep_share)
    } else {
        (r, 1.0)
    };
    if used.len() <= POSITION_UNKNOWNS {
        return None;
    }
    let dof = used.len() - POSITION_UNKNOWNS;
    let ss: f64 = used.iter().map(|x| f64::from(x * x)).sum();
    let sigma = ((ss / dof as f64 / correction).sqrt() as f32).max(floor);
    Some(Noise {
        sigma,
        dof: dof as f32,
    })
}

/// `method` on `bearings` as `foxhunt locate` runs it when the DF unit's noise is unknown: a
/// Huber ML with a nominal 1 degree first, the noise estimated from its residuals, then the
/// method with that noise on every bearing, its claim ([`claim`]) at the noise of its own
/// residuals, F-scaled for their degrees of freedom. The fix and the noise used.
pub fn with_estimated_noise(
    method: Method,
    particles: usize,
    jitter_var: f32,
    bearings: &[Bearing],
    keep_cloud: bool,
    rng: &mut XorShiftRng,
) -> Result<(BearingFix, Noise), Error> {
    if method == Method::Unit {
        // The unit estimates its noise itself, from its window's inliers.
        let times = super::window::one_a_second(bearings.len());
        return super::window::unit_fix(bearings, &times, None).map(|u| (u.fix, u.noise));
    }
    let with =
        |sigma: f32| -> Vec<Bearing> { bearings.iter().map(|b| Bearing { sigma, ..*b }).collect() };
    let nominal = with(1.0f32.to_radians());
    let first = batch_fix(Method::MlHuber, &nominal)?;
    let robust = method.robust_loss();
    let noise =
        estimate_noise(&nominal, &first.position, robust).ok_or(Error::TooFewMeasurements)?;
    let mut fix = locate_bearings(
        method,
        particles,
        jitter_var,
        &with(noise.sigma),
        keep_cloud,
        rng,
    )?;
    // The method's own residuals set the noise its ellipse is scaled by: a method that fits
    // differently from the Huber start (a particle filter's mean) has residuals of its own.
    let own = estimate_noise(&with(noise.sigma), &fix.position, robust).unwrap_or(noise);
    let scale = own.sigma / noise.sigma;
    for row in fix.covariance.iter_mut() {
        for c in row.iter_mut() {
            *c *= scale * scale;
        }
    }
    fix.dof = Some(own.dof);
    claim(method, &mut fix, &with(own.sigma))?;
    Ok((fix, own))
}

/// What a fix of `method` may claim from `bearings` (their sigmas the noise it used): nothing
/// when its estimate lies outside the bearings' own region (`within_the_bearings`); else its
/// covariance at least the bound at its estimate ([`at_least_the_bound`]), its 95 % ellipse
/// scale and CEP50 for its noise's degrees of freedom (chi-square when the sigmas were given).
pub fn claim(method: Method, fix: &mut BearingFix, bearings: &[Bearing]) -> Result<(), Error> {
    within_the_bearings(method, fix, bearings)?;
    fix.covariance = at_least_the_bound(&fix.covariance, &fix.position, bearings);
    fix.ellipse_scale = ellipse_scale(0.95, fix.dof)?;
    let half = Ellipse::with_scale(&fix.covariance, ellipse_scale(0.5, fix.dof)?, 0.5)?;
    fix.cep50 = cep50_of(&half);
    Ok(())
}

/// [`Error::NotConverged`] when `fix` lies outside the bearings' own 95 % likelihood region
/// (the ML fix's: (RSS(p) - RSS_ml) / s^2 beyond 2 F(2, dof), or chi-square(2) with the sigmas
/// given). A filter that linearises can stop there: the EKF, started from a spread cloud, on
/// 10 bearings stopped hundreds of metres to kilometres from the ML fix in a third of the
/// runs, its residuals then set a noise that hid part of it, and its ellipse missed the truth
/// in 12 % of the runs (docs/src/field.md, "Every method, every sample size"). Methods with a
/// robust loss are not judged by a Gaussian likelihood; the ML fix is the region's centre.
fn within_the_bearings(
    method: Method,
    fix: &BearingFix,
    bearings: &[Bearing],
) -> Result<(), Error> {
    if method.robust_loss() || method == Method::Ml {
        return Ok(());
    }
    let Ok(ml) = batch_fix(Method::Ml, bearings) else {
        return Ok(());
    };
    let deviance = |p: &[f32; 2]| -> f64 {
        bearings
            .iter()
            .map(|b| f64::from(wrap(b.theta - predicted(p, &b.vehicle)) / b.sigma).powi(2))
            .sum()
    };
    let best = deviance(&ml.position);
    // With an estimated noise the deviance is in units of the ML fit's own residual variance.
    let unit = fix.dof.map_or(1.0, |dof| best / f64::from(dof.max(1.0)));
    let gap = (deviance(&fix.position) - best) / unit.max(f64::MIN_POSITIVE);
    let limit = ellipse_scale(0.95, fix.dof)?;
    if gap > f64::from(limit) {
        return Err(Error::NotConverged);
    }
    Ok(())
}

/// `f` applied to the eigenvalues of a symmetric 2x2 matrix.
fn on_eigenvalues(m: &[[f32; 2]; 2], f: impl Fn(f32) -> f32) -> Option<[[f32; 2]; 2]> {
    let (l1, l2, a) = eigen2(m)?;
    let (c, s) = (a.cos(), a.sin());
    let (g1, g2) = (f(l1), f(l2));
    Some([
        [g1 * c * c + g2 * s * s, (g1 - g2) * c * s],
        [(g1 - g2) * c * s, g1 * s * s + g2 * c * c],
    ])
}

fn product(a: &[[f32; 2]; 2], b: &[[f32; 2]; 2]) -> [[f32; 2]; 2] {
    let mut p = [[0.0f32; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            p[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    p
}

/// The covariance a fix may claim: its own, widened in every direction where it is tighter
/// than the Cramér-Rao bound at its own estimate (no unbiased estimator does better; an EKF's
/// covariance collapses along the range, a particle cloud can collapse to a few points). In
/// the bound's whitened coordinates the covariance's eigenvalues are raised to at least 1.
/// Left as it is when the bound cannot be computed there.
pub fn at_least_the_bound(
    cov: &[[f32; 2]; 2],
    position: &[f32; 2],
    bearings: &[Bearing],
) -> [[f32; 2]; 2] {
    let widened = || -> Option<[[f32; 2]; 2]> {
        let j = information(position, bearings)?;
        let half = on_eigenvalues(&j, |l| l.max(0.0).sqrt())?;
        let inv_half = on_eigenvalues(&j, |l| if l > 0.0 { 1.0 / l.sqrt() } else { 0.0 })?;
        let whitened = product(&product(&half, cov), &half);
        let raised = on_eigenvalues(&whitened, |l| l.max(1.0))?;
        let c = product(&product(&inv_half, &raised), &inv_half);
        c.iter().flatten().all(|v| v.is_finite()).then_some(c)
    };
    widened().unwrap_or(*cov)
}
