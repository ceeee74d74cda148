//! Artificial fish swarm (seed 002; docs/src/estimators.md, "AFSA-PF"). Each particle is a fish whose
//! food concentration is the likelihood Y = L(z | x). Per iteration each fish either swarms
//! toward the centre of its neighbours within the visual range (when the centre is better and
//! not too crowded: Y_c / n_f > delta Y_i) or preys: it tries up to `tries` random points within
//! the visual range and steps toward the first better one, or makes a random move if none is.
//!
//! Neighbour search: once per iteration the fish are sorted by their first coordinate and
//! each pair closer than v in it is visited once, from its left member scanning right while
//! the first coordinates stay within v. Cost per iteration is O(N log N) for the sort plus
//! O(N k), k the fish per window: linear in N while the visual range is small against the
//! cloud, O(N^2) only when every fish sees every other. The likelihood calls (up to `tries`
//! per preying fish) dominate in practice.

use super::{Swarm, argmax, distance_sq, each_axis, evaluate, sane};
use crate::particles::ParticleSet;
use crate::{fastmath, random};
use rand_core::Rng;

/// AFSA parameters (seed 002's values by default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Afsa {
    /// Visual range v (state units; metres for the emitter).
    pub visual: f32,
    /// Step s.
    pub step: f32,
    /// Crowd factor delta.
    pub crowd: f32,
    /// Prey attempts per fish per iteration.
    pub tries: u32,
    /// Iterations M at most (chosen: 10).
    pub iterations: u32,
    /// Stop early when the best fitness changes less than this, relative (chosen: 1e-6).
    pub tolerance: f32,
}

impl Default for Afsa {
    fn default() -> Self {
        Self {
            visual: 1.0,
            step: 0.3,
            crowd: 0.618,
            tries: 50,
            iterations: 10,
            tolerance: 1e-6,
        }
    }
}

impl<const D: usize> Swarm<D> for Afsa {
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        mut fitness: F,
        rng: &mut R,
    ) -> u32 {
        let usable = self.visual > 0.0 && self.step > 0.0 && self.visual.is_finite();
        if !usable || N > u16::MAX as usize {
            return 0;
        }
        let v = self.visual;
        let ln_crowd = libm::logf(self.crowd);
        let mut ln_y = evaluate(set, &mut fitness);
        let mut evals = N as u32;
        let (_, mut best) = argmax(&ln_y);
        for _ in 0..self.iterations {
            let order = by_first_coordinate(set);
            let sorted: [[f32; D]; N] = core::array::from_fn(|k| set.states[order[k] as usize]);
            let (sums, counts) = neighbour_sums(&sorted, v);
            for (k, &i) in order.iter().enumerate() {
                let (i, xi, n_f) = (i as usize, sorted[k], counts[k]);
                // Swarm: toward the centre of the neighbours within the visual range.
                if n_f > 0.0 {
                    let centre: [f32; D] = core::array::from_fn(|c| sums[k][c] / n_f);
                    let ln_yc = sane(fitness(&centre));
                    evals += 1;
                    // Y_c / n_f > delta Y_i in logs, ln Y_c - ln Y_i - ln delta > ln n_f, with
                    // n_f >= 1; no exponential can overflow.
                    let margin = ln_yc - ln_y[i] - ln_crowd;
                    if margin > 0.0 && n_f * fastmath::exp_nonpositive(-margin) < 1.0 {
                        step_toward(&mut set.states[i], &centre, self.step, rng);
                        ln_y[i] = sane(fitness(&set.states[i]));
                        evals += 1;
                        continue;
                    }
                }
                // Prey: the first better point within sight.
                let mut moved = false;
                for _ in 0..self.tries {
                    let mut xj = xi;
                    each_axis::<D>(|c| xj[c] += v * random::uniform_in(rng, -1.0, 1.0));
                    let lj = sane(fitness(&xj));
                    evals += 1;
                    if lj > ln_y[i] {
                        step_toward(&mut set.states[i], &xj, self.step, rng);
                        moved = true;
                        break;
                    }
                }
                if !moved {
                    let x = &mut set.states[i];
                    each_axis::<D>(|c| x[c] += v * random::uniform_in(rng, -1.0, 1.0));
                }
                ln_y[i] = sane(fitness(&set.states[i]));
                evals += 1;
            }
            let (_, new_best) = argmax(&ln_y);
            let change = libm::fabsf(libm::expf(new_best - best) - 1.0);
            best = best.max(new_best);
            if change < self.tolerance {
                break;
            }
        }
        evals
    }
}

/// Particle indices in increasing order of the first coordinate (NaN last, -NaN first). Each
/// key packs the coordinate's total-order bits above the index, so the sort compares plain
/// integers and ties keep index order.
fn by_first_coordinate<const N: usize, const D: usize>(set: &ParticleSet<N, D>) -> [u16; N] {
    let mut keys: [u64; N] = core::array::from_fn(|i| {
        let bits = set.states[i][0].to_bits();
        let ordered = if bits >> 31 == 1 {
            !bits
        } else {
            bits | 1 << 31
        };
        (ordered as u64) << 32 | i as u64
    });
    keys.sort_unstable();
    core::array::from_fn(|k| keys[k] as u16)
}

/// For fish sorted by their first coordinate: the sum of the positions of each one's
/// neighbours (other fish closer than `v`, coincident ones excepted) and their number. Each
/// pair is visited once, from its left member, scanning right only while the first coordinates
/// are within `v`; squared distances keep that loop short (most pairs it meets are outside
/// the range: it then costs a dozen instructions on the Cortex-M4F).
fn neighbour_sums<const N: usize, const D: usize>(
    sorted: &[[f32; D]; N],
    v: f32,
) -> ([[f32; D]; N], [f32; N]) {
    let mut sums = [[0.0f32; D]; N];
    let mut counts = [0.0f32; N];
    // Each fish a copy: the scan then keeps its coordinates in registers across the stores
    // into the neighbours' sums.
    for (k, &xk) in sorted.iter().enumerate() {
        let (left, right) = sums.split_at_mut(k + 1);
        let (n_left, n_right) = counts.split_at_mut(k + 1);
        let (mut sum, mut n) = ([0.0f32; D], 0.0f32);
        for ((xj, sum_j), n_j) in sorted[k + 1..].iter().zip(right).zip(n_right) {
            if !(xj[0] <= xk[0] + v) {
                break;
            }
            let d2 = distance_sq(&xk, xj);
            if d2 > 0.0 && d2 < v * v {
                n += 1.0;
                *n_j += 1.0;
                each_axis::<D>(|c| {
                    sum[c] += xj[c];
                    sum_j[c] += xk[c];
                });
            }
        }
        n_left[k] += n;
        each_axis::<D>(|c| left[k][c] += sum[c]);
    }
    (sums, counts)
}

/// x += r s (target - x) / |target - x|, r ~ U(0, 1).
fn step_toward<R: Rng + ?Sized, const D: usize>(
    x: &mut [f32; D],
    target: &[f32; D],
    s: f32,
    rng: &mut R,
) {
    let d = fastmath::sqrt(distance_sq(x, target));
    if d > 0.0 && d.is_finite() {
        let f = random::uniform(rng) * s / d;
        for (x, t) in x.iter_mut().zip(target) {
            *x += f * (t - *x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn neighbour_sums_match_every_pair() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        let mut set = ParticleSet::<64, 2>::new();
        for x in set.states.iter_mut() {
            *x = [
                random::uniform_in(&mut rng, 0.0, 4.0),
                random::uniform_in(&mut rng, 0.0, 4.0),
            ];
        }
        // Coincident fish are not each other's neighbours.
        set.states[5] = set.states[4];
        let order = by_first_coordinate(&set);
        assert!(
            order
                .windows(2)
                .all(|w| { set.states[w[0] as usize][0] <= set.states[w[1] as usize][0] })
        );
        let sorted: [[f32; 2]; 64] = core::array::from_fn(|k| set.states[order[k] as usize]);
        let (sums, counts) = neighbour_sums(&sorted, 1.0);
        // Each fish a copy: the scan then keeps its coordinates in registers across the stores
        // into the neighbours' sums.
        for (k, &xk) in sorted.iter().enumerate() {
            let near = |xj: &&[f32; 2]| {
                let d2 = distance_sq(&xk, xj);
                d2 > 0.0 && d2 < 1.0
            };
            assert_eq!(
                counts[k],
                sorted.iter().filter(near).count() as f32,
                "fish {k}"
            );
            for c in 0..2 {
                let sum: f32 = sorted.iter().filter(near).map(|xj| xj[c]).sum();
                assert!((sums[k][c] - sum).abs() < 1e-4, "fish {k} axis {c}");
            }
        }
    }

    #[test]
    fn nan_positions_sort_to_the_ends() {
        let mut set = ParticleSet::<4, 2>::new();
        set.states = [[1.0, 0.0], [f32::NAN, 0.0], [-1.0, 0.0], [-f32::NAN, 0.0]];
        assert_eq!(by_first_coordinate(&set), [3, 2, 0, 1]);
    }
}
