//! Roughening (regularisation) after resampling. A static emitter has no process noise, so
//! without it resampling only ever copies particles and the cloud collapses onto a few points.

use crate::linalg;
use crate::particles::ParticleSet;
use crate::random;
use rand_core::Rng;

/// Seconds of time one full kernel stands for, for a model whose steps are time (a tracker's
/// epochs, [`crate::Model::elapsed_s`]): a resampling jitters by the share of a kernel owed
/// since the last one, so the regularisation is a rate per second of the track, not per
/// resampling, and a track reported ten times a second is not jittered (and shrunk toward its
/// mean) ten times as much as one reported once a second (chosen: the 1 Hz the tracker was
/// tuned at, so a 1 Hz track is jittered as before; docs/src/tracking.md).
pub const KERNEL_PERIOD_S: f32 = 1.0;

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
        self.apply_to(set, mean, cov, &[true; D], 1.0, rng);
    }

    /// [`Roughening::apply`] to the components `kernel` marks only (the model's
    /// [`Model::regularised`](crate::Model::regularised)): a component the motion model drives
    /// itself (a velocity) or keeps discrete (a motion mode) is left as it is. The kernel's
    /// bandwidth is that of the marked components' dimension; with every component marked this
    /// is [`Roughening::apply`], to the bit. `share` in [0, 1] is the share of a full kernel
    /// owed (its variance, and the shrinkage that offsets it, scaled by it: see
    /// [`KERNEL_PERIOD_S`]); 1 is a full kernel, to the bit.
    #[allow(clippy::too_many_arguments)]
    pub fn apply_to<R: Rng + ?Sized, const N: usize, const D: usize>(
        self,
        set: &mut ParticleSet<N, D>,
        mean: &[f32; D],
        cov: &[[f32; D]; D],
        kernel: &[bool; D],
        share: f32,
        rng: &mut R,
    ) {
        let part = libm::sqrtf(share.clamp(0.0, 1.0));
        let marked = kernel.iter().filter(|k| **k).count();
        if marked == 0 {
            return;
        }
        match self {
            Roughening::None => {}
            Roughening::Gordon { k } => {
                let e = set.spread();
                let f = part * k * libm::powf(N as f32, -1.0 / marked as f32);
                for x in set.states.iter_mut() {
                    for j in 0..D {
                        if kernel[j] {
                            x[j] += f * e[j] * random::normal(rng);
                        }
                    }
                }
            }
            Roughening::Shrinkage { scale } => {
                // The marked block alone, packed to the top left: only its components are
                // drawn and moved (with every component marked, the same draws and sums as
                // `random::gaussian`, so the same bits).
                let mut idx = [0usize; D];
                let mut m = 0;
                for (j, k) in kernel.iter().enumerate() {
                    if *k {
                        idx[m] = j;
                        m += 1;
                    }
                }
                let mut block = [[0.0f32; D]; D];
                for a in 0..m {
                    for b in 0..m {
                        block[a][b] = cov[idx[a]][idx[b]];
                    }
                }
                let Some(l) = linalg::cholesky(&block) else {
                    return;
                };
                let d = m as f32;
                let a_opt = libm::powf(4.0 / (d + 2.0), 1.0 / (d + 4.0));
                let h =
                    part * (scale * a_opt * libm::powf(N as f32, -1.0 / (d + 4.0))).clamp(0.0, 1.0);
                let a = libm::sqrtf(1.0 - h * h);
                let mut z = [0.0f32; D];
                for x in set.states.iter_mut() {
                    for zj in z.iter_mut().take(m) {
                        *zj = random::normal(rng);
                    }
                    for r in 0..m {
                        let mut jitter = 0.0f32;
                        for (lrc, zc) in l[r].iter().zip(z.iter()).take(r + 1) {
                            jitter += lrc * zc;
                        }
                        let j = idx[r];
                        x[j] = a * x[j] + (1.0 - a) * mean[j] + h * jitter;
                    }
                }
            }
        }
    }
}
