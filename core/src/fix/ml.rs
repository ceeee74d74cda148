//! Maximum-likelihood fix: Levenberg-Marquardt on sum rho(wrap(z_k - h_k(p)) / sigma_k), with
//! rho = -ln L of any [`Likelihood`]. For the Gaussian this is nonlinear least squares and
//! reaches the CRLB; for Huber, Cauchy or Student-t it is iteratively reweighted least squares
//! (IRLS weights psi(u)/u), which keeps wild bearings from dragging the fix.

use super::{Fix, geometry, usable};
use crate::error::Error;
use crate::likelihood::Likelihood;
use crate::linalg;
use crate::model::bearing::{Bearing, predicted, wrap};

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MlOptions {
    /// Outer iterations at most.
    pub max_iterations: u32,
    /// Stop when a step moves the fix less than this, metres.
    pub tolerance_m: f32,
}

impl Default for MlOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            tolerance_m: 1e-3,
        }
    }
}

/// Robust cost sum_k -ln L(r_k; sigma_k) at `p` (centred coordinates).
fn cost<L: Likelihood>(bearings: &[Bearing], origin: [f32; 2], p: [f32; 2], loss: &L) -> f32 {
    let abs = [p[0] + origin[0], p[1] + origin[1]];
    usable(bearings)
        .map(|b| -loss.ln(b.residual(&abs), b.sigma))
        .sum()
}

/// Gauss-Newton normal matrix and right-hand side at `p`, with IRLS weights.
fn normal_equations<L: Likelihood>(
    bearings: &[Bearing],
    origin: [f32; 2],
    p: [f32; 2],
    loss: &L,
) -> ([[f32; 2]; 2], [f32; 2]) {
    let mut h = [[0.0f32; 2]; 2];
    let mut g = [0.0f32; 2];
    for b in usable(bearings) {
        let s = [b.vehicle[0] - origin[0], b.vehicle[1] - origin[1]];
        let dx = p[0] - s[0];
        let dy = p[1] - s[1];
        let d2 = (dx * dx + dy * dy).max(1e-6);
        let r = wrap(b.theta - predicted(&p, &s));
        let inv_var = 1.0 / (b.sigma * b.sigma);
        let w = inv_var * loss.irls_weight(r, b.sigma);
        // d h / d p for h = atan2(dy, dx).
        let jac = [-dy / d2, dx / d2];
        for i in 0..2 {
            for j in 0..2 {
                h[i][j] += w * jac[i] * jac[j];
            }
            g[i] += w * jac[i] * r;
        }
    }
    (h, g)
}

/// ML fix started from `start` (the bias-compensated PLE when `None`).
pub fn ml<L: Likelihood>(
    bearings: &[Bearing],
    start: Option<[f32; 2]>,
    loss: &L,
    options: MlOptions,
) -> Result<Fix, Error> {
    let geo = geometry(bearings)?;
    let start = match start {
        Some(p) => {
            crate::error::check_finite(&p)?;
            p
        }
        None => super::ple::bias_compensated_ple(bearings)?.position,
    };
    let o = geo.origin;
    let mut p = [start[0] - o[0], start[1] - o[1]];
    let mut current = cost(bearings, o, p, loss);
    let mut lambda = 1e-3f32;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < options.max_iterations && !converged {
        iterations += 1;
        let (h, g) = normal_equations(bearings, o, p, loss);
        let mut accepted = false;
        for _ in 0..12 {
            let damped = [
                [h[0][0] * (1.0 + lambda), h[0][1]],
                [h[1][0], h[1][1] * (1.0 + lambda)],
            ];
            let Some(delta) = linalg::solve2(&damped, &g) else {
                lambda *= 10.0;
                continue;
            };
            let next = [p[0] + delta[0], p[1] + delta[1]];
            let c = cost(bearings, o, next, loss);
            if c.is_finite() && c <= current {
                let step = libm::hypotf(delta[0], delta[1]);
                converged = step < options.tolerance_m || current - c <= 1e-7 * current.abs();
                p = next;
                current = c;
                lambda = (lambda * 0.1).max(1e-7);
                accepted = true;
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            // No downhill step at any damping: we are at the minimum to f32 precision.
            converged = true;
        }
    }
    let position = [p[0] + o[0], p[1] + o[1]];
    crate::error::check_finite(&position)?;
    let (h, _) = normal_equations(bearings, o, p, loss);
    let covariance = linalg::inverse2(&h).ok_or(Error::DegenerateGeometry)?;
    let mut outliers = 0;
    let mut front = 0.0f32;
    for b in usable(bearings) {
        let r = b.residual(&position);
        front += libm::cosf(r);
        if libm::fabsf(r) > 3.0 * b.sigma {
            outliers += 1;
        }
    }
    if front <= 0.0 {
        // The solver settled on the mirror image, behind the vehicle: no fix, not a wrong one.
        return Err(Error::BehindVehicle);
    }
    Ok(Fix {
        position,
        covariance,
        used: geo.used,
        skipped: geo.skipped,
        outliers,
        iterations,
    })
}
