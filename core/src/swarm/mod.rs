//! Swarm optimisers that move a particle set toward higher likelihood before it is weighted
//! (seeds 001-003). Each is a [`Swarm`]; a [`Sir`](crate::Sir) or [`Gpf`](crate::Gpf) built
//! with one runs it every step between prediction and weighting.
//!
//! A swarm move changes the proposal: after it the particles are weighted by the likelihood at
//! their moved positions, as the seeds do. That is a heuristic, not an unbiased importance
//! weight (the proposal density of the move is not divided out), so the posterior it reports
//! is narrower than the true one. The bench measures whether the move pays for itself.

pub mod afsa;
pub mod firefly;
pub mod gsa;
pub mod pso;

use crate::particles::ParticleSet;
use rand_core::Rng;

/// Moves particles toward higher fitness.
pub trait Swarm<const D: usize> {
    /// False for [`NoSwarm`]: the filters then skip preparing a fitness function (a bearing's
    /// sine and cosine, a thousand soft-float instructions on the MCU) that nothing would call.
    const MOVES: bool = true;
    /// Move the states of `set` toward higher `fitness` (a log-likelihood: larger is better).
    /// Returns the number of fitness evaluations spent, the currency of equal-cost comparisons.
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        fitness: F,
        rng: &mut R,
    ) -> u32;
}

/// No swarm: the plain filter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoSwarm;

impl<const D: usize> Swarm<D> for NoSwarm {
    const MOVES: bool = false;

    #[inline]
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        _set: &mut ParticleSet<N, D>,
        _fitness: F,
        _rng: &mut R,
    ) -> u32 {
        0
    }
}

/// Log-fitness of every particle; NaN counts as the worst possible.
pub(crate) fn evaluate<const N: usize, const D: usize>(
    set: &ParticleSet<N, D>,
    fitness: &mut impl FnMut(&[f32; D]) -> f32,
) -> [f32; N] {
    core::array::from_fn(|i| sane(fitness(&set.states[i])))
}

/// NaN fitness becomes -inf so that comparisons never prefer it.
#[inline]
pub(crate) fn sane(l: f32) -> f32 {
    if l.is_nan() { f32::NEG_INFINITY } else { l }
}

/// `f(0); f(1); ..; f(D - 1)` with the first two calls written out: at the MCU image's
/// opt-level "s" the compiler keeps even a two-trip loop, and the swarms run these once per
/// particle pair or trial point.
#[inline(always)]
pub(crate) fn each_axis<const D: usize>(mut f: impl FnMut(usize)) {
    if D > 0 {
        f(0);
    }
    if D > 1 {
        f(1);
    }
    for c in 2..D {
        f(c);
    }
}

/// Squared Euclidean distance, the axes written out (see [`each_axis`]).
#[inline(always)]
pub(crate) fn distance_sq<const D: usize>(a: &[f32; D], b: &[f32; D]) -> f32 {
    let mut d2 = 0.0;
    each_axis::<D>(|c| d2 += (a[c] - b[c]) * (a[c] - b[c]));
    d2
}

/// Index and value of the largest entry.
pub(crate) fn argmax(v: &[f32]) -> (usize, f32) {
    v.iter()
        .copied()
        .enumerate()
        .fold((0, f32::NEG_INFINITY), |(bi, bv), (i, x)| {
            if x > bv { (i, x) } else { (bi, bv) }
        })
}

/// Per-axis weighted standard deviation of the set (at least `floor`): the length scale that
/// makes the firefly constants independent of the state's units.
pub(crate) fn axis_scale<const N: usize, const D: usize>(
    set: &ParticleSet<N, D>,
    floor: f32,
) -> [f32; D] {
    let mean = set.mean();
    let cov = set.covariance(&mean);
    core::array::from_fn(|j| {
        let s = libm::sqrtf(cov[j][j]);
        if s.is_finite() && s > floor { s } else { floor }
    })
}
