//! Roughening (regularisation) after resampling. A static emitter has no process noise, so
//! without it resampling only ever copies particles and the cloud collapses onto a few points.

use crate::linalg;
use crate::particles::ParticleSet;
use crate::random;
use rand_core::Rng;

/// How to jitter the particles after resampling.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Roughening {
    /// No jitter (for models whose process noise already diversifies the cloud).
    #[default]
    None,
    /// Gordon's roughening: Gaussian jitter sigma_j = k E_j N^(-1/D), E_j the range of component
    /// j (k = 0.2 chosen). Cheap, but it inflates the cloud by a fixed fraction of its range on
    /// every resampling, which a static target pays for in accuracy.
    Gordon {
        /// Scale factor k.
        k: f32,
    },
    /// Regularised-PF kernel with shrinkage (Liu and West): x <- a x + (1 - a) mean + h L z with
    /// h = A N^(-1/(D+4)) (the optimal Gaussian-kernel bandwidth times `scale`), a =
    /// sqrt(1 - h^2), L the Cholesky factor of the weighted covariance. The shrinkage toward the
    /// mean exactly offsets the kernel's variance, so the cloud's mean and covariance are kept:
    /// the filter diversifies without forgetting what it learned (chosen for static states).
    Shrinkage {
        /// Multiplier on the optimal bandwidth (1.0 by default; < 1 jitters less).
        scale: f32,
    },
}

impl Roughening {
    /// Jitter the (just resampled, equally weighted) set. `mean` and `cov` are the cloud's
    /// weighted moments from before resampling.
    pub fn apply<R: Rng + ?Sized, const N: usize, const D: usize>(
        self,
        set: &mut ParticleSet<N, D>,
        mean: &[f32; D],
        cov: &[[f32; D]; D],
        rng: &mut R,
    ) {
        match self {
            Roughening::None => {}
            Roughening::Gordon { k } => {
                let e = set.spread();
                let f = k * libm::powf(N as f32, -1.0 / D as f32);
                for x in set.states.iter_mut() {
                    for j in 0..D {
                        x[j] += f * e[j] * random::normal(rng);
                    }
                }
            }
            Roughening::Shrinkage { scale } => {
                let Some(l) = linalg::cholesky(cov) else {
                    return;
                };
                let d = D as f32;
                let a_opt = libm::powf(4.0 / (d + 2.0), 1.0 / (d + 4.0));
                let h = (scale * a_opt * libm::powf(N as f32, -1.0 / (d + 4.0))).clamp(0.0, 1.0);
                let a = libm::sqrtf(1.0 - h * h);
                let zero = [0.0f32; D];
                for x in set.states.iter_mut() {
                    let jitter = random::gaussian(rng, &zero, &l);
                    for j in 0..D {
                        x[j] = a * x[j] + (1.0 - a) * mean[j] + h * jitter[j];
                    }
                }
            }
        }
    }
}
