//! Artificial fish swarm (seed 002; ALGORITHMS.md "AFSA-PF"). Each particle is a fish whose
//! food concentration is the likelihood Y = L(z | x). Per iteration each fish either swarms
//! toward the centre of its neighbours within the visual range (when the centre is better and
//! not too crowded: Y_c / n_f > delta Y_i) or preys: it tries up to `tries` random points within
//! the visual range and steps toward the first better one, or makes a random move if none is.
//!
//! Neighbour search: the fish are sorted by their first coordinate once per iteration and each
//! fish scans only the window [x - v, x + v] (binary search for its start). Cost per iteration
//! is O(N log N) for the sort plus O(N k) for the scans, k the fish per window: linear in N
//! while the visual range is small against the cloud, O(N^2) only when every fish sees every
//! other. The likelihood calls (up to `tries` per preying fish) dominate in practice.

use super::{Swarm, argmax, evaluate, sane};
use crate::particles::ParticleSet;
use crate::random;
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
        let mut ln_y = evaluate(set, &mut fitness);
        let mut evals = N as u32;
        let (_, mut best) = argmax(&ln_y);
        for _ in 0..self.iterations {
            // Fitness relative to the best: Y in (0, 1], no overflow in exp.
            let reference = best;
            let snapshot = set.states;
            let mut order: [u16; N] = core::array::from_fn(|i| i as u16);
            order.sort_unstable_by(|a, b| {
                snapshot[*a as usize][0].total_cmp(&snapshot[*b as usize][0])
            });
            for i in 0..N {
                let xi = snapshot[i];
                let yi = libm::expf(ln_y[i] - reference);
                // Swarm: centre of the neighbours within the visual range.
                let start = order.partition_point(|&j| snapshot[j as usize][0] < xi[0] - v);
                let mut centre = [0.0f32; D];
                let mut n_f = 0u32;
                for &j in order[start..].iter() {
                    let xj = snapshot[j as usize];
                    if xj[0] > xi[0] + v {
                        break;
                    }
                    // Squared distances: no square root per pair (a software routine on the
                    // Cortex-M4F, whose FPU square root stable Rust cannot reach in no_std).
                    let d2 = distance_sq(&xi, &xj);
                    if d2 > 0.0 && d2 < v * v {
                        n_f += 1;
                        for k in 0..D {
                            centre[k] += xj[k];
                        }
                    }
                }
                if n_f > 0 {
                    for c in centre.iter_mut() {
                        *c /= n_f as f32;
                    }
                    let yc = libm::expf(sane(fitness(&centre)) - reference);
                    evals += 1;
                    if yc / n_f as f32 > self.crowd * yi {
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
                    for c in xj.iter_mut() {
                        *c += v * random::uniform_in(rng, -1.0, 1.0);
                    }
                    let lj = sane(fitness(&xj));
                    evals += 1;
                    if lj > ln_y[i] {
                        step_toward(&mut set.states[i], &xj, self.step, rng);
                        moved = true;
                        break;
                    }
                }
                if !moved {
                    for c in set.states[i].iter_mut() {
                        *c += v * random::uniform_in(rng, -1.0, 1.0);
                    }
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

fn distance_sq<const D: usize>(a: &[f32; D], b: &[f32; D]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// x += r s (target - x) / |target - x|, r ~ U(0, 1).
fn step_toward<R: Rng + ?Sized, const D: usize>(
    x: &mut [f32; D],
    target: &[f32; D],
    s: f32,
    rng: &mut R,
) {
    let d = libm::sqrtf(distance_sq(x, target));
    if d > 0.0 && d.is_finite() {
        let r = random::uniform(rng);
        for k in 0..D {
            x[k] += r * s * (target[k] - x[k]) / d;
        }
    }
}
