//! Firefly algorithms (Yang; seed 001). Brightness is the likelihood at a firefly.
//!
//! Scale (chosen): the seeds give beta0 = 1, gamma = 1 and a random step alpha without units.
//! Here distances and the random step are measured in units of the cloud's per-axis standard
//! deviation at the start of the move, so the same constants work for an emitter kilometres
//! away and for the UNGM's unitless state.

use super::{Swarm, argmax, axis_scale, each_axis, evaluate, sane};
use crate::particles::ParticleSet;
use crate::{fastmath, random};
use rand_core::Rng;

/// The constants both firefly variants share (seed 001 gives beta0 = 1, gamma = 1; alpha, its
/// decay and the iteration count are chosen).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FireflyParams {
    /// Attraction at zero distance.
    pub beta0: f32,
    /// Light absorption, >= 0 (a negative or NaN one disables the move: the swarm returns 0).
    pub gamma: f32,
    /// Random step (in cloud standard deviations).
    pub alpha: f32,
    /// Factor on alpha per iteration.
    pub alpha_decay: f32,
    /// Iterations (chosen: 10).
    pub iterations: u32,
}

impl Default for FireflyParams {
    fn default() -> Self {
        Self {
            beta0: 1.0,
            gamma: 1.0,
            alpha: 0.2,
            alpha_decay: 0.97,
            iterations: 10,
        }
    }
}

impl FireflyParams {
    /// The shared prologue: the cloud's length scale and every firefly's brightness, or `None`
    /// when the absorption is unusable (a negative one would pull harder the farther apart).
    fn start<const N: usize, const D: usize>(
        &self,
        set: &ParticleSet<N, D>,
        fitness: &mut impl FnMut(&[f32; D]) -> f32,
    ) -> Option<([f32; D], [f32; N])> {
        (self.gamma >= 0.0).then(|| (axis_scale(set, 1e-6), evaluate(set, fitness)))
    }
}

/// Standard firefly: every firefly moves toward every brighter one,
/// x_i += beta0 exp(-gamma r_ij^2) (x_j - x_i) + alpha (U(0,1) - 1/2). O(N^2) per iteration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Firefly {
    /// The shared constants.
    pub params: FireflyParams,
}

/// Improved firefly of seed 001 (its formulas (4)-(5) are lost; the reconstruction of
/// docs/src/estimators.md, "FA-PF (improved)", chosen): every firefly moves toward the
/// current best G only, beta_i = beta0 (I_best / (I_best + I_i)) exp(-gamma r_i^2) eps(t),
/// eps(t) = eps_min + (1 - eps_min) exp(-t / t_c). O(N) per iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImprovedFirefly {
    /// The shared constants.
    pub params: FireflyParams,
    /// Floor of the attraction schedule eps(t) (chosen: 0.1).
    pub eps_min: f32,
    /// Time constant of eps(t), iterations (chosen: 5).
    pub t_c: f32,
}

impl Default for ImprovedFirefly {
    fn default() -> Self {
        Self {
            params: FireflyParams::default(),
            eps_min: 0.1,
            t_c: 5.0,
        }
    }
}

/// Squared distance in units of `scale`.
fn scaled_r2<const D: usize>(a: &[f32; D], b: &[f32; D], scale: &[f32; D]) -> f32 {
    let mut r2 = 0.0;
    each_axis::<D>(|k| {
        let d = (a[k] - b[k]) / scale[k];
        r2 += d * d;
    });
    r2
}

impl<const D: usize> Swarm<D> for Firefly {
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        mut fitness: F,
        rng: &mut R,
    ) -> u32 {
        let p = self.params;
        let Some((scale, mut light)) = p.start(set, &mut fitness) else {
            return 0;
        };
        let mut evals = N as u32;
        let mut alpha = p.alpha;
        for _ in 0..p.iterations {
            for i in 0..N {
                let mut moved = false;
                for j in 0..N {
                    if light[j] > light[i] {
                        let xj = set.states[j];
                        let xi = &mut set.states[i];
                        let beta = p.beta0
                            * fastmath::exp_nonpositive(-p.gamma * scaled_r2(xi, &xj, &scale));
                        each_axis::<D>(|k| {
                            xi[k] += beta * (xj[k] - xi[k])
                                + alpha * scale[k] * (random::uniform(rng) - 0.5);
                        });
                        moved = true;
                    }
                }
                if moved {
                    light[i] = sane(fitness(&set.states[i]));
                    evals += 1;
                }
            }
            alpha *= p.alpha_decay;
        }
        evals
    }
}

impl<const D: usize> Swarm<D> for ImprovedFirefly {
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        mut fitness: F,
        rng: &mut R,
    ) -> u32 {
        let p = self.params;
        let Some((scale, mut light)) = p.start(set, &mut fitness) else {
            return 0;
        };
        let mut evals = N as u32;
        let mut alpha = p.alpha;
        for t in 1..=p.iterations {
            let (b, l_best) = argmax(&light);
            if !l_best.is_finite() {
                break;
            }
            let g = set.states[b];
            let eps = self.eps_min + (1.0 - self.eps_min) * libm::expf(-(t as f32) / self.t_c);
            for i in 0..N {
                if i == b {
                    continue;
                }
                // Relative brightness I_i / I_best in [0, 1]: dimmer fireflies are pulled harder.
                let rel = fastmath::exp_nonpositive(light[i] - l_best);
                let xi = &mut set.states[i];
                let beta = p.beta0 / (1.0 + rel)
                    * fastmath::exp_nonpositive(-p.gamma * scaled_r2(xi, &g, &scale))
                    * eps;
                each_axis::<D>(|k| {
                    xi[k] +=
                        beta * (g[k] - xi[k]) + alpha * scale[k] * (random::uniform(rng) - 0.5);
                });
                light[i] = sane(fitness(xi));
                evals += 1;
            }
            alpha *= p.alpha_decay;
        }
        evals
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    /// A negative absorption would pull harder the farther apart: no move, no evaluations.
    #[test]
    fn negative_gamma_leaves_the_swarm_alone() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let mut set = ParticleSet::<8, 2>::new();
        set.states = core::array::from_fn(|i| [i as f32, 0.0]);
        let before = set.states;
        let fitness = |x: &[f32; 2]| -x[0] * x[0];
        let bad = |gamma| FireflyParams {
            gamma,
            ..FireflyParams::default()
        };
        let mut standard = Firefly { params: bad(-1.0) };
        assert_eq!(standard.optimise(&mut set, fitness, &mut rng), 0);
        let mut improved = ImprovedFirefly {
            params: bad(f32::NAN),
            ..ImprovedFirefly::default()
        };
        assert_eq!(improved.optimise(&mut set, fitness, &mut rng), 0);
        assert_eq!(set.states, before);
        // And a valid one does move them.
        assert!(Firefly::default().optimise(&mut set, fitness, &mut rng) > 0);
        assert_ne!(set.states, before);
    }
}
