//! Particle swarm optimisation inside the Gaussian PF (PSO-GPF; seed 003's comparison):
//! v <- w v + c1 r1 (pbest - x) + c2 r2 (gbest - x), x <- x + v, fitness = likelihood
//! (w = 0.7, c1 = c2 = 1.5, 10 iterations: chosen). O(N D) per iteration; velocities and
//! personal bests live on the stack for the duration of one move.

use super::{Swarm, argmax, each_axis, evaluate, sane};
use crate::particles::ParticleSet;
use crate::random;
use rand_core::Rng;

/// PSO parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pso {
    /// Inertia w.
    pub inertia: f32,
    /// Cognitive weight c1 (toward the particle's own best).
    pub cognitive: f32,
    /// Social weight c2 (toward the swarm's best).
    pub social: f32,
    /// Iterations.
    pub iterations: u32,
}

impl Default for Pso {
    fn default() -> Self {
        Self {
            inertia: 0.7,
            cognitive: 1.5,
            social: 1.5,
            iterations: 10,
        }
    }
}

impl<const D: usize> Swarm<D> for Pso {
    fn optimise<const N: usize, R: Rng + ?Sized, F: FnMut(&[f32; D]) -> f32>(
        &mut self,
        set: &mut ParticleSet<N, D>,
        mut fitness: F,
        rng: &mut R,
    ) -> u32 {
        let mut fit = evaluate(set, &mut fitness);
        let mut evals = N as u32;
        let mut velocity = [[0.0f32; D]; N];
        let mut pbest = set.states;
        let mut pfit = fit;
        let (g, mut gfit) = argmax(&fit);
        let mut gbest = set.states[g];
        for _ in 0..self.iterations {
            for i in 0..N {
                let x = &mut set.states[i];
                let v = &mut velocity[i];
                each_axis::<D>(|k| {
                    let r1 = random::uniform(rng);
                    let r2 = random::uniform(rng);
                    v[k] = self.inertia * v[k]
                        + self.cognitive * r1 * (pbest[i][k] - x[k])
                        + self.social * r2 * (gbest[k] - x[k]);
                    x[k] += v[k];
                });
                fit[i] = sane(fitness(x));
                evals += 1;
                if fit[i] > pfit[i] {
                    pfit[i] = fit[i];
                    pbest[i] = *x;
                }
                if fit[i] > gfit {
                    gfit = fit[i];
                    gbest = *x;
                }
            }
        }
        evals
    }
}
