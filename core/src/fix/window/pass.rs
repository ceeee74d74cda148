//! One refinement pass over the window: the IRLS sums of Tukey's biweight and the inliers'
//! Gaussian information.

use super::{TUKEY, WindowFix, fold, sin_cos};
use crate::fastmath::atan2;
use crate::likelihood::Likelihood;

/// Sums of one pass over the window at a position.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pass {
    /// IRLS normal matrix and right-hand side.
    pub(super) h: [[f32; 2]; 2],
    pub(super) g: [f32; 2],
    /// Tukey cost.
    pub(super) cost: f32,
    /// Gaussian information of the inliers.
    pub(super) info: [[f32; 2]; 2],
    /// Inliers (|u| < c), their sum of squared normalised residuals, their sum of cos(r).
    pub(super) inliers: u32,
    pub(super) chi2: f32,
    pub(super) front: f32,
    /// The smallest |u| beyond the cut (infinite when every bearing is an inlier).
    pub(super) nearest_out: f32,
    /// The largest |u| within it (0 without inliers).
    pub(super) farthest_in: f32,
}

/// `m + k n` for 2 x 2 matrices.
fn add(m: [[f32; 2]; 2], n: [[f32; 2]; 2], k: f32) -> [[f32; 2]; 2] {
    [
        [m[0][0] + k * n[0][0], m[0][1] + k * n[0][1]],
        [m[1][0] + k * n[1][0], m[1][1] + k * n[1][1]],
    ]
}

impl WindowFix {
    /// One pass over the window at `p` (centred coordinates) with noise scale `sigma`.
    pub(super) fn pass(&self, origin: [f32; 2], p: [f32; 2], sigma: f32) -> Pass {
        let mut s = Pass {
            h: [[0.0; 2]; 2],
            g: [0.0; 2],
            cost: 0.0,
            info: [[0.0; 2]; 2],
            inliers: 0,
            chi2: 0.0,
            front: 0.0,
            nearest_out: f32::INFINITY,
            farthest_in: 0.0,
        };
        for e in self.entries() {
            let dx = p[0] - (e.vehicle[0] - origin[0]);
            let dy = p[1] - (e.vehicle[1] - origin[1]);
            let d2 = dx * dx + dy * dy;
            // A branch, not `max`: the Cortex-M4F build calls `fmaxf` for that.
            let d2 = if d2 < 1e-6 { 1e-6 } else { d2 };
            let r = fold(e.theta - atan2(dy, dx));
            let sd = sigma * e.rel;
            let u = r / sd;
            s.cost -= TUKEY.ln(r, sd);
            let inv_var = 1.0 / (sd * sd);
            let w = inv_var * TUKEY.irls_weight(r, sd);
            let inlier = u * u < TUKEY.c * TUKEY.c;
            let (jx, jy) = (-dy / d2, dx / d2);
            let outer = [[jx * jx, jx * jy], [jx * jy, jy * jy]];
            s.h = add(s.h, outer, w);
            if inlier {
                s.info = add(s.info, outer, inv_var);
            }
            s.g[0] += w * jx * r;
            s.g[1] += w * jy * r;
            let a = libm::fabsf(u);
            // Branches, not `min`/`max`: see above.
            if inlier {
                s.inliers += 1;
                s.chi2 += u * u;
                s.front += sin_cos(r).1;
                if a > s.farthest_in {
                    s.farthest_in = a;
                }
            } else if a < s.nearest_out {
                s.nearest_out = a;
            }
        }
        s
    }
}
