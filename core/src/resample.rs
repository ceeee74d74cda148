//! Resampling schemes. Each turns normalised weights into copy counts (sum N) in O(N), without
//! a scratch array: the particle set then replicates in place.

use crate::fastmath;
use crate::random;
use rand_core::Rng;

/// Which resampling scheme to use. Systematic is the usual choice: lowest variance, one uniform.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Resampling {
    /// N independent draws from the weights (sorted uniforms by order statistics, O(N)).
    Multinomial,
    /// One uniform per stratum: u_i = (i + U_i) / N.
    Stratified,
    /// One uniform for all strata: u_i = (i + U) / N.
    #[default]
    Systematic,
    /// floor(N w_i) deterministic copies, then multinomial over the remainders
    /// N w_i - floor(N w_i) (not filterpy's issue 290 variant).
    Residual,
}

/// When a particle filter resamples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ResamplePolicy {
    /// After every update, as the seeds' filters do.
    Always,
    /// When the effective sample size falls below this fraction of N (0.5 is the textbook
    /// choice: a half-degenerate cloud is refreshed, a healthy one keeps its weights' memory).
    BelowEss(f32),
}

impl Default for ResamplePolicy {
    fn default() -> Self {
        ResamplePolicy::BelowEss(0.5)
    }
}

impl ResamplePolicy {
    /// Whether a cloud of `n` particles with effective sample size `ess` is due.
    #[inline]
    pub fn due(self, ess: f32, n: usize) -> bool {
        match self {
            ResamplePolicy::Always => true,
            ResamplePolicy::BelowEss(fraction) => ess < fraction * n as f32,
        }
    }

    /// `Ok` when the fraction is a number in [0, 1] (0 never resamples, 1 nearly always).
    pub fn check(self) -> Result<(), crate::Error> {
        match self {
            ResamplePolicy::Always => Ok(()),
            ResamplePolicy::BelowEss(f) if (0.0..=1.0).contains(&f) => Ok(()),
            ResamplePolicy::BelowEss(_) => Err(crate::Error::OutOfRange),
        }
    }
}

impl Resampling {
    /// Copy counts for each particle given normalised `weights`; `counts` sums to N.
    pub fn counts<R: Rng + ?Sized, const N: usize>(
        self,
        weights: &[f32; N],
        rng: &mut R,
        counts: &mut [u32; N],
    ) {
        if N == 0 {
            return;
        }
        let n = N as f32;
        // Systematic and residual write every count; the walks add to zeroed ones.
        match self {
            Resampling::Systematic => systematic(weights, random::uniform(rng), counts),
            Resampling::Stratified => {
                *counts = [0; N];
                walk(
                    weights,
                    1.0,
                    N,
                    |i| (i as f32 + random::uniform(rng)) / n,
                    counts,
                );
            }
            Resampling::Multinomial => {
                *counts = [0; N];
                multinomial(weights, 1.0, N, rng, counts)
            }
            Resampling::Residual => {
                let mut assigned = 0usize;
                let mut remainders = [0.0f32; N];
                let mut rsum = 0.0f32;
                for ((c, w), r) in counts.iter_mut().zip(weights).zip(remainders.iter_mut()) {
                    let nw = (n * w).clamp(0.0, n);
                    // Never more copies than slots left, even for unnormalised weights.
                    let k = libm::floorf(nw).min((N - assigned) as f32);
                    *c = k as u32;
                    assigned += k as usize;
                    *r = nw - k;
                    rsum += *r;
                }
                let left = N.saturating_sub(assigned);
                if left > 0 && rsum > 0.0 {
                    multinomial(&remainders, rsum, left, rng, counts);
                } else if left > 0 {
                    counts[0] += left as u32;
                }
            }
        }
    }
}

/// Systematic resampling without a search: the points (i + u0) / N below a cumulative weight
/// C number ceil(N C - u0) (clamped to [0, N]), so particle j gets the difference of that count
/// at its two cumulative edges. Branch-free, one pass; the last edge is N exactly, so the counts
/// always sum to N whatever the rounding in the running sum.
fn systematic<const N: usize>(weights: &[f32; N], u0: f32, counts: &mut [u32; N]) {
    let n = N as f32;
    let mut cum = 0.0f32;
    let mut below = 0u32;
    for (j, (c, w)) in counts.iter_mut().zip(weights).enumerate() {
        cum += *w;
        let upto = if j + 1 == N {
            N as u32
        } else {
            // ceil as the nearest integer plus one when below; v is in [-1, N] for
            // normalised weights (N < 2^22), and the clamp keeps rounding past 1 within N.
            let v = n * cum - u0;
            let (r, ri) = fastmath::round_to_int(v);
            (ri + i32::from(r < v)).clamp(0, N as i32) as u32
        };
        let upto = upto.max(below);
        *c = upto - below;
        below = upto;
    }
}

/// Walk the cumulative sum of `weights` with `draws` ascending points in [0, 1) (scaled by
/// `total`), adding one copy to the particle each point lands in. The last cumulative value is
/// taken as `total` exactly, so rounding in the sum never pushes a point past the end.
fn walk<const N: usize>(
    weights: &[f32; N],
    total: f32,
    draws: usize,
    mut point: impl FnMut(usize) -> f32,
    counts: &mut [u32; N],
) {
    let mut j = 0usize;
    let mut cum = weights[0];
    for i in 0..draws {
        let u = point(i) * total;
        while u >= cum && j + 1 < N {
            j += 1;
            cum += weights[j];
        }
        counts[j] += 1;
    }
}

/// `draws` independent draws, as sorted uniforms generated in order by the order-statistics
/// recursion U_(k) = U_(k+1) V^(1/k) (mirrored to run ascending), so no sort and no buffer.
fn multinomial<R: Rng + ?Sized, const N: usize>(
    weights: &[f32; N],
    total: f32,
    draws: usize,
    rng: &mut R,
    counts: &mut [u32; N],
) {
    let mut top = 1.0f32;
    walk(
        weights,
        total,
        draws,
        |i| {
            let k = (draws - i) as f32;
            top *= libm::expf(libm::logf(random::uniform_open0(rng)) / k);
            1.0 - top
        },
        counts,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    const W: [f32; 8] = [0.30, 0.01, 0.17, 0.0, 0.12, 0.05, 0.25, 0.10];

    /// Every scheme is unbiased: the mean number of copies of particle i is N w_i.
    #[test]
    fn every_scheme_is_unbiased() {
        let draws = 40_000;
        for scheme in [
            Resampling::Multinomial,
            Resampling::Stratified,
            Resampling::Systematic,
            Resampling::Residual,
        ] {
            let mut rng = XorShiftRng::seed_from_u64(7);
            let mut total = [0u64; 8];
            let mut counts = [0u32; 8];
            for _ in 0..draws {
                scheme.counts(&W, &mut rng, &mut counts);
                assert_eq!(counts.iter().sum::<u32>(), 8, "{scheme:?}");
                for (t, c) in total.iter_mut().zip(counts) {
                    *t += c as u64;
                }
            }
            for (i, (t, w)) in total.iter().zip(W).enumerate() {
                let mean = *t as f64 / draws as f64;
                let expect = 8.0 * w as f64;
                // Multinomial has the largest spread, sd of one count sqrt(N w (1 - w)) <= 1.42;
                // over 40 000 draws the standard error is <= 0.0071: 5 standard errors.
                let tol = 5.0 * (8.0 * w as f64 * (1.0 - w as f64) / draws as f64).sqrt() + 1e-9;
                assert!(
                    (mean - expect).abs() <= tol,
                    "{scheme:?} particle {i}: mean {mean} expected {expect} tol {tol}"
                );
            }
        }
    }

    #[test]
    fn systematic_is_deterministic_for_exact_weights() {
        let w = [0.25f32; 4];
        let mut rng = XorShiftRng::seed_from_u64(1);
        let mut counts = [0u32; 4];
        Resampling::Systematic.counts(&w, &mut rng, &mut counts);
        assert_eq!(counts, [1, 1, 1, 1]);
    }

    #[test]
    fn degenerate_weights_never_overflow() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        let mut counts = [0u32; 3];
        for w in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.4, 0.4, 0.4],
        ] {
            for s in [
                Resampling::Multinomial,
                Resampling::Stratified,
                Resampling::Systematic,
                Resampling::Residual,
            ] {
                s.counts(&w, &mut rng, &mut counts);
                assert_eq!(counts.iter().sum::<u32>(), 3);
            }
        }
    }
}
