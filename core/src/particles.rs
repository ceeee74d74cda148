//! The particle set: states and weights in fixed arrays sized by const generics.

use crate::error::Error;
use crate::fastmath;
use crate::linalg;
use crate::random;
use crate::resample::Resampling;
use rand_core::Rng;

/// `N` weighted particles of state dimension `D`, stored inline (no allocator).
///
/// Weights are kept twice: `log_weights` accumulate likelihoods (a burst of unlikely
/// measurements cannot underflow them), `weights` hold the normalised linear weights after
/// [`ParticleSet::normalise`].
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleSet<const N: usize, const D: usize> {
    /// Particle states.
    pub states: [[f32; D]; N],
    /// Unnormalised log-weights.
    pub log_weights: [f32; N],
    /// Normalised weights (sum 1) as of the last normalisation.
    pub weights: [f32; N],
}

impl<const N: usize, const D: usize> Default for ParticleSet<N, D> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const D: usize> ParticleSet<N, D> {
    /// All particles at the origin with equal weights.
    pub const fn new() -> Self {
        const { assert!(N > 0 && D > 0, "a particle set needs particles and a state") };
        Self {
            states: [[0.0; D]; N],
            log_weights: [0.0; N],
            weights: [1.0 / N as f32; N],
        }
    }

    /// Reset every weight to 1/N.
    pub fn set_uniform_weights(&mut self) {
        self.log_weights = [0.0; N];
        self.weights = [1.0 / N as f32; N];
    }

    /// Turn log-weights into normalised weights by shifting with the maximum first.
    ///
    /// NaN log-weights count as impossible particles. If no particle has a finite log-weight
    /// the weights are reset to uniform and [`Error::WeightCollapse`] is returned, so the
    /// caller can re-initialise; the set is never left holding NaN. On success the log-weights
    /// are rebased to the logs of the normalised weights and the effective sample size is
    /// returned.
    pub fn normalise(&mut self) -> Result<f32, Error> {
        // A comparison is false for NaN, so NaN log-weights never become the maximum. (Not
        // f32::max: on the MCU that is a call to fmaxf per particle.)
        let larger = |m: f32, x: f32| if x > m { x } else { m };
        let max = lane_fold(N, f32::NEG_INFINITY, larger, |i| self.log_weights[i]);
        if !max.is_finite() {
            self.set_uniform_weights();
            return Err(Error::WeightCollapse);
        }
        // Plain maps and separate reductions: each loop vectorises on its own.
        for (w, lw) in self.weights.iter_mut().zip(self.log_weights.iter()) {
            let e = fastmath::exp_nonpositive(lw - max);
            *w = if e.is_nan() { 0.0 } else { e };
        }
        let sum = lane_sum(N, |i| self.weights[i]);
        // The maximum contributes exp(0) = 1, so 1 <= sum <= N here.
        let inv = 1.0 / sum;
        let shift = max + libm::logf(sum);
        for (w, lw) in self.weights.iter_mut().zip(self.log_weights.iter_mut()) {
            *w *= inv;
            *lw = if *w > 0.0 {
                *lw - shift
            } else {
                f32::NEG_INFINITY
            };
        }
        let sum_sq = lane_sum(N, |i| self.weights[i] * self.weights[i]);
        Ok(if sum_sq > 0.0 { 1.0 / sum_sq } else { 0.0 })
    }

    /// Effective sample size 1 / sum w^2 of the normalised weights, in [1, N].
    pub fn ess(&self) -> f32 {
        let s = lane_sum(N, |i| self.weights[i] * self.weights[i]);
        if s > 0.0 { 1.0 / s } else { 0.0 }
    }

    /// Weighted mean of the states.
    pub fn mean(&self) -> [f32; D] {
        core::array::from_fn(|j| lane_sum(N, |i| self.weights[i] * self.states[i][j]))
    }

    /// Weighted covariance of the states about `mean`.
    pub fn covariance(&self, mean: &[f32; D]) -> [[f32; D]; D] {
        let mut c = [[0.0f32; D]; D];
        for i in 0..D {
            for j in 0..=i {
                c[i][j] = lane_sum(N, |k| {
                    let x = &self.states[k];
                    self.weights[k] * (x[i] - mean[i]) * (x[j] - mean[j])
                });
                c[j][i] = c[i][j];
            }
        }
        c
    }

    /// Range (max - min) of each state component: the scale of the roughening jitter.
    pub fn spread(&self) -> [f32; D] {
        let mut lo = [f32::INFINITY; D];
        let mut hi = [f32::NEG_INFINITY; D];
        for x in self.states.iter() {
            for j in 0..D {
                lo[j] = lo[j].min(x[j]);
                hi[j] = hi[j].max(x[j]);
            }
        }
        let mut e = [0.0f32; D];
        for j in 0..D {
            e[j] = hi[j] - lo[j];
        }
        e
    }

    /// Resample in place with `scheme` and reset the weights to 1/N.
    pub fn resample<R: Rng + ?Sized>(&mut self, scheme: Resampling, rng: &mut R) {
        let mut counts = [0u32; N];
        scheme.counts(&self.weights, rng, &mut counts);
        self.apply_counts(&counts);
        self.set_uniform_weights();
    }

    /// Replicate particle j `counts[j]` times, in place and without a branch per copy: slot k
    /// gets ancestor a_k, nondecreasing in k (each particle marks the first slot of its run and
    /// a running maximum fills the rest). Then two passes copy with no second state array:
    /// ascending where a_k >= k (that source is not yet overwritten), descending where a_k < k
    /// (nor is that one: a_{a_k} <= a_k, so its slot kept its particle). Counts summing to
    /// more than N stop at N; to fewer, the last ancestor fills the remaining slots.
    pub fn apply_counts(&mut self, counts: &[u32; N]) {
        let mut ancestor = [0u32; N];
        let mut start = 0usize;
        for (j, &c) in counts.iter().enumerate() {
            if let Some(a) = ancestor.get_mut(start) {
                *a = j as u32;
            }
            start = start.saturating_add(c as usize);
        }
        let mut run = 0;
        for a in ancestor.iter_mut() {
            run = run.max(*a);
            *a = run;
        }
        for k in 0..N {
            let a = ancestor[k] as usize;
            self.states[k] = self.states[if a >= k { a } else { k }];
        }
        for k in (0..N).rev() {
            let a = ancestor[k] as usize;
            self.states[k] = self.states[if a < k { a } else { k }];
        }
    }

    /// Fill the set by drawing every particle from N(mean, cov), with uniform weights.
    pub fn draw_gaussian<R: Rng + ?Sized>(
        &mut self,
        mean: &[f32; D],
        cov: &[[f32; D]; D],
        rng: &mut R,
    ) -> Result<(), Error> {
        let l = linalg::cholesky(cov).ok_or(Error::NonFinite)?;
        crate::error::check_finite(mean)?;
        // Normals four at a time from independent lanes (see random::Lanes).
        let mut lanes = random::Lanes::seed_from(rng);
        let (mut four, mut used) = ([0.0f32; 4], 4);
        for x in self.states.iter_mut() {
            let z = core::array::from_fn(|_| {
                if used == 4 {
                    four = lanes.normals(rng);
                    used = 0;
                }
                used += 1;
                four[used - 1]
            });
            *x = random::correlate(mean, &l, &z);
        }
        self.set_uniform_weights();
        Ok(())
    }
}

/// Accumulators of the reductions over particles. One running sum fixes the order of the
/// additions and so forbids the compiler to vectorise; eight interleaved ones give it four- or
/// eight-wide registers to fill. The order is fixed by the code, so every target gets the same
/// bits.
const LANES: usize = 8;

/// `f(0) + ... + f(n - 1)` in [`LANES`] interleaved partial sums.
#[inline(always)]
fn lane_sum(n: usize, f: impl FnMut(usize) -> f32) -> f32 {
    lane_fold(n, 0.0, |a, b| a + b, f)
}

/// Fold `f(0), ..., f(n - 1)` with `op` (associative and commutative up to rounding) in
/// [`LANES`] interleaved accumulators, combined pairwise at the end.
#[inline(always)]
fn lane_fold(
    n: usize,
    init: f32,
    op: impl Fn(f32, f32) -> f32,
    mut f: impl FnMut(usize) -> f32,
) -> f32 {
    // Written out, not a loop over the lanes: at the MCU's opt-level "s" a loop would stay a
    // loop, with the accumulators in memory.
    let [
        mut a0,
        mut a1,
        mut a2,
        mut a3,
        mut a4,
        mut a5,
        mut a6,
        mut a7,
    ] = [init; LANES];
    let full = n - n % LANES;
    let mut i = 0;
    while i < full {
        a0 = op(a0, f(i));
        a1 = op(a1, f(i + 1));
        a2 = op(a2, f(i + 2));
        a3 = op(a3, f(i + 3));
        a4 = op(a4, f(i + 4));
        a5 = op(a5, f(i + 5));
        a6 = op(a6, f(i + 6));
        a7 = op(a7, f(i + 7));
        i += LANES;
    }
    let mut acc = [a0, a1, a2, a3, a4, a5, a6, a7];
    for (a, i) in acc.iter_mut().zip(full..n) {
        *a = op(*a, f(i));
    }
    let [a0, a1, a2, a3, a4, a5, a6, a7] = acc;
    op(op(op(a0, a4), op(a2, a6)), op(op(a1, a5), op(a3, a7)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalise_survives_underflow() {
        let mut p = ParticleSet::<4, 1>::new();
        p.log_weights = [-1.0e4, -1.0e4 - 1.0, -2.0e4, f32::NAN];
        let ess = p.normalise().unwrap();
        let e = libm::expf(-1.0);
        assert!((p.weights[0] - 1.0 / (1.0 + e)).abs() < 1e-6);
        assert_eq!(p.weights[2], 0.0);
        assert_eq!(p.weights[3], 0.0);
        assert!(ess > 1.0 && ess < 2.0);
    }

    #[test]
    fn collapse_is_typed_not_nan() {
        let mut p = ParticleSet::<3, 2>::new();
        p.log_weights = [f32::NEG_INFINITY, f32::NAN, f32::NEG_INFINITY];
        assert_eq!(p.normalise(), Err(Error::WeightCollapse));
        assert!(p.weights.iter().all(|w| (*w - 1.0 / 3.0).abs() < 1e-7));
    }

    #[test]
    fn mean_and_covariance() {
        let mut p = ParticleSet::<4, 2>::new();
        p.states = [[1.0, 0.0], [-1.0, 0.0], [0.0, 2.0], [0.0, -2.0]];
        let m = p.mean();
        let c = p.covariance(&m);
        assert_eq!(m, [0.0, 0.0]);
        assert!((c[0][0] - 0.5).abs() < 1e-6 && (c[1][1] - 2.0).abs() < 1e-6);
        assert_eq!(c[0][1], 0.0);
    }

    #[test]
    fn apply_counts_in_place() {
        let mut p = ParticleSet::<5, 1>::new();
        p.states = [[0.0], [1.0], [2.0], [3.0], [4.0]];
        p.apply_counts(&[0, 3, 0, 2, 0]);
        assert_eq!(p.states, [[1.0], [1.0], [1.0], [3.0], [3.0]]);
        // Survivors moving both ways, and counts that overrun N.
        p.states = [[0.0], [1.0], [2.0], [3.0], [4.0]];
        p.apply_counts(&[2, 0, 0, 0, 3]);
        assert_eq!(p.states, [[0.0], [0.0], [4.0], [4.0], [4.0]]);
        p.states = [[0.0], [1.0], [2.0], [3.0], [4.0]];
        p.apply_counts(&[0, 0, 1, 9, 9]);
        assert_eq!(p.states, [[2.0], [3.0], [3.0], [3.0], [3.0]]);
    }

    /// Every count vector of a 6-particle set against the obvious out-of-place copy.
    #[test]
    fn apply_counts_matches_a_plain_copy() {
        let mut counts = [0u32; 6];
        loop {
            if counts.iter().sum::<u32>() == 6 {
                let mut p = ParticleSet::<6, 1>::new();
                p.states = core::array::from_fn(|i| [i as f32]);
                let mut expected = [[0.0f32]; 6];
                let mut k = 0;
                for (j, &c) in counts.iter().enumerate() {
                    for _ in 0..c {
                        expected[k] = [j as f32];
                        k += 1;
                    }
                }
                p.apply_counts(&counts);
                assert_eq!(p.states, expected, "{counts:?}");
            }
            // Next vector in base 7.
            let Some(i) = counts.iter().position(|&c| c < 6) else {
                break;
            };
            counts[i] += 1;
            counts[..i].fill(0);
        }
    }
}
