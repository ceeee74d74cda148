//! The noise the bearings claim, in one number: the median of their sigmas.
//!
//! The robust search sets its agreement threshold from it, the refinement its first scale, and
//! the pipeline reports the noise it used as this median times the estimated scale.

use super::bias::Sighting;
use super::order;

/// Chance that a sample of Gaussian residuals holds one beyond [`chance_cut`] (Bonferroni over
/// the sample): a residual past it is wild, one within it is noise however small the others.
pub const WILD_ALPHA: f32 = 0.05;

/// The largest of `n` Gaussian residuals, in units of a noise estimated with `dof` degrees of
/// freedom, stays within this but in [`WILD_ALPHA`] of samples (Student-t, Bonferroni over
/// `n`). A small sample's estimate is often small by chance: a fixed cut at a few of its
/// sigmas drops good bearings, and the estimate then falls further. `None` when `dof` is not
/// positive.
pub fn chance_cut(n: usize, dof: f32) -> Option<f32> {
    let tail = 1.0 - WILD_ALPHA / (2.0 * n.max(1) as f32);
    crate::stats::t_quantile(tail, dof).ok()
}

/// Bearings the median is taken over at most: an evenly strided sample, so a long drive costs
/// no more than this and nothing is allocated.
pub const SIGMA_SAMPLE: usize = 256;

/// The median sigma (radians) of the usable bearings among an evenly strided sample of at most
/// [`SIGMA_SAMPLE`] of `items` (all of them when there are no more); 0 when none is usable. A
/// bearing the stride lands on that [`Bearing::check`](crate::model::bearing::Bearing::check)
/// refuses is skipped, not replaced; of an even count the median is the mean of the middle two.
pub fn median_sigma<T: Sighting>(items: &[T]) -> f32 {
    let mut s = [0.0f32; SIGMA_SAMPLE];
    let stride = items.len().div_ceil(SIGMA_SAMPLE).max(1);
    let mut k = 0;
    for t in items.iter().step_by(stride) {
        let b = t.bearing();
        if b.check().is_ok()
            && let Some(slot) = s.get_mut(k)
        {
            *slot = b.sigma;
            k += 1;
        }
    }
    order::median(&mut s[..k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::Bearing;

    fn with_sigma(sigma: f32) -> Bearing {
        Bearing {
            vehicle: [0.0; 2],
            theta: 0.0,
            sigma,
        }
    }

    #[test]
    fn the_median_of_the_usable_sigmas_of_a_strided_sample() {
        assert_eq!(median_sigma::<Bearing>(&[]), 0.0);
        let mixed = [0.03, -1.0, 0.01, f32::NAN, 0.02].map(with_sigma);
        assert_eq!(median_sigma(&mixed), 0.02);
        let even = [0.01, 0.03].map(with_sigma);
        assert!((median_sigma(&even) - 0.02).abs() < 1e-7);
        // 1000 bearings: every fourth is sampled.
        let many: [Bearing; 1000] =
            core::array::from_fn(|k| with_sigma(if k % 4 == 0 { 0.05 } else { 0.01 }));
        assert_eq!(median_sigma(&many), 0.05);
    }
}
