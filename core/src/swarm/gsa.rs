//! Gravitational search inside the Gaussian PF (GSA-GPF, seed 003). Fitness is the
//! unnormalised weight; masses m_i = (fit_i - worst) / (best - worst), M_i = m_i / sum m; the
//! gravitational constant decays, G(t) = G0 exp(-alpha t / Tc); only the K best attract, K
//! falling linearly from N to 1 (K = N + (1 - N)(t - 1)/(Tc - 1)); the acceleration is
//! a_i = G sum_{j in Kbest, j != i} rand_j M_j (x_j - x_i) / (R_ij + eps); then
//! v_i <- rand_i v_i + a_i, x_i += v_i, and every particle is reweighted.
//! All forces of an iteration are computed from the same positions. O(N K) per iteration,
//! O(N^2) over a move.

use super::{Swarm, distance_sq, each_axis, evaluate, sane};
use crate::particles::ParticleSet;
use crate::{fastmath, random};
use rand_core::Rng;

/// GSA parameters (seed 003's values by default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gsa {
    /// Initial gravitational constant G0.
    pub g0: f32,
    /// Decay alpha of G(t).
    pub alpha: f32,
    /// Iterations Tc.
    pub iterations: u32,
    /// Softening eps in the distance.
    pub softening: f32,
}

impl Default for Gsa {
    fn default() -> Self {
        Self {
            g0: 100.0,
            alpha: 20.0,
            iterations: 10,
            softening: 1e-3,
        }
    }
}

impl<const D: usize> Swarm<D> for Gsa {
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        mut fitness: F,
        rng: &mut R,
    ) -> u32 {
        if N > u16::MAX as usize || self.iterations == 0 {
            return 0;
        }
        let tc = self.iterations;
        let mut ln_fit = evaluate(set, &mut fitness);
        let mut evals = N as u32;
        let mut velocity = [[0.0f32; D]; N];
        let mut order: [u16; N] = core::array::from_fn(|i| i as u16);
        for t in 1..=tc {
            // Masses from the fitness relative to the best (exp of a log-difference: no overflow).
            let best = ln_fit.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            if !best.is_finite() {
                break;
            }
            let fit: [f32; N] =
                core::array::from_fn(|i| fastmath::exp_nonpositive(ln_fit[i] - best));
            let worst = fit.iter().copied().fold(f32::INFINITY, f32::min);
            let spread = 1.0 - worst;
            let mut mass: [f32; N] = core::array::from_fn(|i| {
                if spread > 0.0 {
                    (fit[i] - worst) / spread
                } else {
                    1.0
                }
            });
            let total: f32 = mass.iter().sum();
            if !(total > 0.0) {
                break;
            }
            for m in mass.iter_mut() {
                *m /= total;
            }
            let g = self.g0 * libm::expf(-self.alpha * t as f32 / tc as f32);
            let k = if tc > 1 {
                let n = N as f32;
                libm::roundf(n + (1.0 - n) * (t - 1) as f32 / (tc - 1) as f32).clamp(1.0, n)
                    as usize
            } else {
                N
            };
            order.sort_unstable_by(|a, b| fit[*b as usize].total_cmp(&fit[*a as usize]));
            let mut accel = [[0.0f32; D]; N];
            for i in 0..N {
                let xi = set.states[i];
                for &j in order[..k].iter() {
                    let j = j as usize;
                    if j == i {
                        continue;
                    }
                    let xj = set.states[j];
                    let r2 = distance_sq(&xi, &xj);
                    let f =
                        g * random::uniform(rng) * mass[j] / (fastmath::sqrt(r2) + self.softening);
                    let a = &mut accel[i];
                    each_axis::<D>(|d| a[d] += f * (xj[d] - xi[d]));
                }
            }
            for i in 0..N {
                let keep = random::uniform(rng);
                let (v, x) = (&mut velocity[i], &mut set.states[i]);
                each_axis::<D>(|d| {
                    v[d] = keep * v[d] + accel[i][d];
                    x[d] += v[d];
                });
                ln_fit[i] = sane(fitness(&set.states[i]));
                evals += 1;
            }
        }
        evals
    }
}
