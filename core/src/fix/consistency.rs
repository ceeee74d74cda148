//! Is the answer as good as it claims? Residuals against the noise model, the effective number
//! of independent bearings, honest ellipse scales, and particle clouds against the bound.
//!
//! - **Correlated bearings.** A DF unit that reports 5 times a second from a running average
//!   sends bearings whose errors persist over many reports; counted as independent they shrink
//!   the ellipse by up to sqrt(N / N_eff). [`effective_count`] estimates N_eff from the
//!   autocorrelation of the ordered, normalised residuals (Geyer's initial positive sequence)
//!   and callers widen the covariance by N / N_eff.
//! - **Consistency.** The normalised residuals' chi-square with n - p degrees of freedom says
//!   whether the noise model holds; [`chi2_p_value`] is its tail probability.
//! - **Honest scales.** With the noise estimated from the residuals, the 95 % region of a 2-D
//!   position is 2 F(2, n - p; 0.95) times its covariance, not chi-square's 5.991
//!   ([`ellipse_scale`]).
//! - **Particle clouds.** A filter's covariance below the CRLB at its own estimate, or a cloud
//!   of a handful of distinct points, claims more than the bearings hold ([`check_cloud`]).

use crate::error::{Error, check_finite};
use crate::model::bearing::Bearing;
use crate::particles::ParticleSet;
use crate::stats;

/// Lags of the autocorrelation at most (a correlation time of ~60 reports is the most the
/// estimate resolves; the work is O(n x lags)).
pub const MAX_LAG: usize = 128;

/// Effective number of independent values in `values` (in time order; `n` of them): n / tau
/// with tau = 1 + 2 sum rho_k, summed by Geyer's initial positive (and monotone) sequence of
/// paired autocorrelations. White noise gives n: a lag-1 autocorrelation below 2 / sqrt(n) (not
/// significant at about 2.5 %) is taken for white, so independent bearings are not widened by
/// the estimator's own noise. Never more than n, never less than 1. O(n x lags), lags capped at
/// [`MAX_LAG`] and n / 4.
pub fn effective_count<I: Iterator<Item = f32> + Clone>(values: I, n: u32) -> f32 {
    let tau = correlation_time(values, n);
    (n as f32 / tau).clamp(1.0f32.min(n as f32), n as f32)
}

/// tau = n / N_eff (>= 1) of `values`: the factor by which correlation inflates the variance of
/// a mean.
pub fn correlation_time<I: Iterator<Item = f32> + Clone>(values: I, n: u32) -> f32 {
    if n < 8 {
        return 1.0;
    }
    let nf = n as f32;
    let mean = values.clone().take(n as usize).sum::<f32>() / nf;
    let lag = |l: usize| -> f32 {
        values
            .clone()
            .take(n as usize)
            .zip(values.clone().take(n as usize).skip(l))
            .map(|(a, b)| (a - mean) * (b - mean))
            .sum::<f32>()
            / nf
    };
    let g0 = lag(0);
    if !(g0 > 0.0) || !g0.is_finite() {
        return 1.0;
    }
    let rho = |l: usize| lag(l) / g0;
    let r1 = rho(1);
    if !(r1 >= 2.0 / libm::sqrtf(nf)) {
        return 1.0;
    }
    let max_lag = MAX_LAG.min(n as usize / 4);
    // Gamma_m = rho_{2m} + rho_{2m+1}, rho_0 = 1; tau = -1 + 2 sum Gamma_m while positive,
    // each Gamma kept no larger than the one before (the initial monotone sequence).
    let mut tau = -1.0f32;
    let mut previous = f32::INFINITY;
    let mut m = 0;
    while 2 * m < max_lag {
        let g = if m == 0 {
            1.0 + r1
        } else {
            rho(2 * m) + rho(2 * m + 1)
        };
        if !(g > 0.0) {
            break;
        }
        let g = g.min(previous);
        tau += 2.0 * g;
        previous = g;
        m += 1;
    }
    if tau.is_finite() { tau.max(1.0) } else { 1.0 }
}

/// Thin high-rate bearings in place: keep an item only if at least `interval` (seconds) has
/// passed since the last kept item of the same source (`key(item)` gives its time and source);
/// returns how many are kept, compacted to the front in order. The simple alternative to
/// widening by N / N_eff: with `interval` about one correlation time (tau reports), the kept
/// bearings are nearly independent. Sources index a table of 256; items with a non-finite time
/// are dropped. O(n).
pub fn thin<T: Copy>(items: &mut [T], interval: f32, key: impl Fn(&T) -> (f32, u8)) -> usize {
    let mut last = [f32::NEG_INFINITY; 256];
    let mut kept = 0;
    for i in 0..items.len() {
        let it = items[i];
        let (t, source) = key(&it);
        let Some(l) = last.get_mut(source as usize) else {
            continue;
        };
        if t.is_finite() && (*l == f32::NEG_INFINITY || t - *l >= interval) {
            *l = t;
            items[kept] = it;
            kept += 1;
        }
    }
    kept
}

/// P(chi-square(dof) > chi2): small when the residuals are too large for the noise model.
pub fn chi2_p_value(chi2: f32, dof: f32) -> Result<f32, Error> {
    check_finite(&[chi2, dof])?;
    if !(dof > 0.0) {
        return Err(Error::TooFewMeasurements);
    }
    stats::chi2_sf(chi2, dof)
}

/// The factor k with which the `confidence` ellipse of a 2-D position is x^T C^-1 x <= k:
/// chi-square(2) when the noise is known (`dof` = `None`), 2 F(2, dof) when it was estimated
/// from residuals with `dof` degrees of freedom (Student-t in two dimensions).
pub fn ellipse_scale(confidence: f32, dof: Option<f32>) -> Result<f32, Error> {
    match dof {
        None => stats::chi2_2_quantile(confidence),
        Some(d) => Ok(2.0 * stats::f_quantile(confidence, 2.0, d)?),
    }
}

/// A particle cloud held against the bound of its own estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CloudCheck {
    /// Distinct positions among the particles with weight.
    pub distinct: u32,
    /// Smallest eigenvalue of P J (P the cloud's position covariance, J the Fisher information
    /// at its mean): 1 at the bound, below 1 where the cloud claims more than any unbiased
    /// estimator could. The covariance along that direction is this share of the bound's.
    pub information_ratio: f32,
    /// The cloud is not to be believed: fewer than [`CloudCheck::MIN_DISTINCT`] (or N / 20)
    /// distinct points, or a covariance under a quarter of the bound in some direction.
    pub collapsed: bool,
}

impl CloudCheck {
    /// Distinct points below which a cloud is collapsed whatever its size.
    pub const MIN_DISTINCT: u32 = 5;
    /// Information ratio below which a cloud is collapsed (its sd under half the bound's).
    pub const MIN_RATIO: f32 = 0.25;
}

/// Check a particle filter's cloud (positions in the first two state components) against the
/// CRLB of `bearings` at the cloud's own weighted mean. Costs one O(N log N) sort of the
/// particles' keys and one pass over the bearings.
pub fn check_cloud<const N: usize, const D: usize>(
    set: &ParticleSet<N, D>,
    bearings: &[Bearing],
) -> Result<CloudCheck, Error> {
    if D < 2 {
        return Err(Error::OutOfRange);
    }
    let mean = set.mean();
    let cov = set.covariance(&mean);
    let p = [mean[0], mean[1]];
    let c = [[cov[0][0], cov[0][1]], [cov[1][0], cov[1][1]]];
    check_finite(&[p[0], p[1], c[0][0], c[0][1], c[1][1]])?;
    let j = super::crlb::information(&p, bearings).ok_or(Error::DegenerateGeometry)?;
    // Eigenvalues of P J are real and >= 0 (both symmetric PSD): the roots of
    // l^2 - tr(PJ) l + det(P) det(J).
    let pj = [
        [
            c[0][0] * j[0][0] + c[0][1] * j[1][0],
            c[0][0] * j[0][1] + c[0][1] * j[1][1],
        ],
        [
            c[1][0] * j[0][0] + c[1][1] * j[1][0],
            c[1][0] * j[0][1] + c[1][1] * j[1][1],
        ],
    ];
    let tr = pj[0][0] + pj[1][1];
    let det = pj[0][0] * pj[1][1] - pj[0][1] * pj[1][0];
    let disc = libm::sqrtf((0.25 * tr * tr - det).max(0.0));
    let ratio = (0.5 * tr - disc).max(0.0);
    // Distinct positions: sort the weighted particles' bit patterns.
    let mut keys = [(0u32, 0u32); N];
    let mut k = 0;
    for (x, w) in set.states.iter().zip(set.weights.iter()) {
        if *w > 0.0
            && let Some(slot) = keys.get_mut(k)
        {
            *slot = (x[0].to_bits(), x[1].to_bits());
            k += 1;
        }
    }
    super::order::heapsort_by(&mut keys[..k], |a, b| a < b);
    let distinct = if k == 0 {
        0
    } else {
        1 + keys[..k].windows(2).filter(|w| w[0] != w[1]).count() as u32
    };
    check_finite(&[ratio])?;
    let collapsed =
        distinct < CloudCheck::MIN_DISTINCT.max(N as u32 / 20) || ratio < CloudCheck::MIN_RATIO;
    Ok(CloudCheck {
        distinct,
        information_ratio: ratio,
        collapsed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::predicted;
    use crate::random;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn white_noise_counts_fully_and_a_running_average_does_not() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let white: [f32; 2000] = core::array::from_fn(|_| random::normal(&mut rng));
        let n = effective_count(white.iter().copied(), 2000);
        // The estimator's own noise: when the gate lets white noise through (a few percent of
        // sequences), Geyer's sum adds about 0.1 to tau.
        assert!(n > 1700.0, "white: {n}");
        // A running mean of 10 raw values: tau = 10 (the moving average's sum of
        // autocorrelations 1 + 2 sum (10 - k)/10).
        let raw: [f32; 2010] = core::array::from_fn(|_| random::normal(&mut rng));
        let smooth: [f32; 2000] =
            core::array::from_fn(|k| raw[k..k + 10].iter().sum::<f32>() / 10.0);
        let tau = correlation_time(smooth.iter().copied(), 2000);
        assert!((7.5..12.5).contains(&tau), "running mean of 10: tau {tau}");
        // Few values: nothing to estimate from.
        assert_eq!(correlation_time(white.iter().copied(), 5), 1.0);
    }

    #[test]
    fn thinning_to_the_correlation_time_decorrelates() {
        let mut rng = XorShiftRng::seed_from_u64(4);
        let raw: [f32; 4010] = core::array::from_fn(|_| random::normal(&mut rng));
        // 5 reports a second, each the mean of the last 10 raw values: (time, value).
        let mut reports: [(f32, f32); 4000] =
            core::array::from_fn(|k| (0.2 * k as f32, raw[k..k + 10].iter().sum::<f32>() / 10.0));
        let tau = correlation_time(reports.iter().map(|r| r.1), 4000);
        // One report per 10 (2 s) keeps 400 nearly independent ones.
        let kept = thin(&mut reports, 0.2 * tau.round(), |r| (r.0, 0));
        let after = correlation_time(reports[..kept].iter().map(|r| r.1), kept as u32);
        assert!((350..=450).contains(&kept), "{kept} kept at tau {tau}");
        assert!(after < 1.5, "tau after thinning {after}");
        assert!(
            reports[..kept]
                .windows(2)
                .all(|w| w[1].0 - w[0].0 >= 0.2 * tau.round() - 1e-3)
        );
    }

    #[test]
    fn white_noise_is_rarely_widened() {
        // Over 200 short white sequences, the gate leaves most at tau = 1 and the mean
        // widening small: the ellipses of independent bearings stay honest, not padded.
        let mut rng = XorShiftRng::seed_from_u64(2);
        let mut widened = 0;
        let mut sum = 0.0;
        for _ in 0..200 {
            let v: [f32; 60] = core::array::from_fn(|_| random::normal(&mut rng));
            let tau = correlation_time(v.iter().copied(), 60);
            widened += (tau > 1.0) as u32;
            sum += tau;
        }
        assert!(widened < 20, "{widened} of 200 widened");
        assert!(sum / 200.0 < 1.05, "mean tau {}", sum / 200.0);
    }

    #[test]
    fn honest_scales() {
        assert!((ellipse_scale(0.95, None).unwrap() - 5.991).abs() < 1e-3);
        // n = 5, p = 2: 2 F(2, 3) = 19.10.
        assert!((ellipse_scale(0.95, Some(3.0)).unwrap() - 19.104).abs() < 0.01);
        // Many residuals: the F scale tends to chi-square's.
        let big = ellipse_scale(0.95, Some(10_000.0)).unwrap();
        assert!((big - 5.991).abs() < 0.01, "{big}");
        assert!(chi2_p_value(10.0, 0.0).is_err());
        let p = chi2_p_value(58.0, 58.0).unwrap();
        assert!((0.4..0.55).contains(&p), "{p}");
    }

    fn loop_bearings(e: [f32; 2]) -> [Bearing; 60] {
        core::array::from_fn(|k| {
            let a = k as f32 * 0.1047;
            let v = [e[0] + 300.0 * libm::cosf(a), e[1] + 300.0 * libm::sinf(a)];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 0.0195,
            }
        })
    }

    #[test]
    fn a_collapsed_cloud_is_flagged_and_an_honest_one_is_not() {
        let e = [1200.0, 800.0];
        let bs = loop_bearings(e);
        let bound = super::super::crlb::crlb(&e, &bs).unwrap().covariance;
        let mut rng = XorShiftRng::seed_from_u64(3);
        let mut set = ParticleSet::<500, 2>::new();
        // Drawn from the bound itself: at the bound, many distinct points.
        set.draw_gaussian(&e, &bound, &mut rng).unwrap();
        let honest = check_cloud(&set, &bs).unwrap();
        assert!(!honest.collapsed, "{honest:?}");
        assert!((0.7..1.3).contains(&honest.information_ratio), "{honest:?}");
        // Five points copied a hundred times each (the standard FA-PF's end state).
        for i in 0..500 {
            set.states[i] = set.states[i % 5];
        }
        let few = check_cloud(&set, &bs).unwrap();
        assert!(few.collapsed && few.distinct == 5, "{few:?}");
        // Many distinct points, but a hundred times tighter than the bound.
        let tight = [
            [bound[0][0] * 1e-4, bound[0][1] * 1e-4],
            [bound[1][0] * 1e-4, bound[1][1] * 1e-4],
        ];
        set.draw_gaussian(&e, &tight, &mut rng).unwrap();
        let small = check_cloud(&set, &bs).unwrap();
        assert!(
            small.collapsed && small.information_ratio < 0.01,
            "{small:?}"
        );
    }
}
