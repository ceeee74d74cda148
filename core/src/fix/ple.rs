//! Closed-form fixes: pseudo-linear estimator (PLE), its bias-compensated form, and the weighted
//! instrumental variable estimator (Dogancay 2005).
//!
//! The PLE writes each bearing as a line a_k . p = b_k with a_k = [sin z, -cos z] and solves by
//! least squares. It is biased toward the vehicle because the noisy angle sits in both a_k and
//! b_k; the compensation subtracts the expected bias E[sin^2 n] (A^T A)^-1 sum (p - s_k), and the
//! instrumental variable replaces a_k by its noise-free value at the current fix, which removes
//! the correlation and makes the estimator asymptotically efficient.

use super::{Fix, Geometry, geometry, usable};
use crate::error::Error;
use crate::linalg;
use crate::model::bearing::{Bearing, predicted};

/// Normal equations of the (weighted) pseudo-linear system with instruments `g`.
fn solve(
    bearings: &[Bearing],
    geo: &Geometry,
    mut instrument: impl FnMut(&Bearing, [f32; 2]) -> ([f32; 2], f32),
) -> Result<([f32; 2], [[f32; 2]; 2]), Error> {
    let mut m = [[0.0f32; 2]; 2];
    let mut r = [0.0f32; 2];
    for bk in usable(bearings) {
        let s = [bk.vehicle[0] - geo.origin[0], bk.vehicle[1] - geo.origin[1]];
        let a = [libm::sinf(bk.theta), -libm::cosf(bk.theta)];
        let b = a[0] * s[0] + a[1] * s[1];
        let (g, w) = instrument(bk, s);
        for i in 0..2 {
            for j in 0..2 {
                m[i][j] += w * g[i] * a[j];
            }
            r[i] += w * g[i] * b;
        }
    }
    let p = linalg::solve2(&m, &r).ok_or(Error::DegenerateGeometry)?;
    Ok((p, m))
}

fn fix_at(geo: &Geometry, p: [f32; 2], bearings: &[Bearing], iterations: u32) -> Fix {
    let position = [p[0] + geo.origin[0], p[1] + geo.origin[1]];
    let covariance = super::crlb::information(&position, bearings)
        .and_then(|j| linalg::inverse2(&j))
        .unwrap_or([[f32::INFINITY, 0.0], [0.0, f32::INFINITY]]);
    Fix {
        position,
        covariance,
        used: geo.used,
        skipped: geo.skipped,
        outliers: 0,
        iterations,
    }
}

fn plain(bearings: &[Bearing], geo: &Geometry) -> Result<([f32; 2], [[f32; 2]; 2]), Error> {
    solve(bearings, geo, |b, _| {
        let w = 1.0 / (b.sigma * b.sigma);
        ([libm::sinf(b.theta), -libm::cosf(b.theta)], w)
    })
}

/// The pseudo-linear estimator (weights 1/sigma^2).
pub fn ple(bearings: &[Bearing]) -> Result<Fix, Error> {
    let geo = geometry(bearings)?;
    let (p, _) = plain(bearings, &geo)?;
    Ok(fix_at(&geo, p, bearings, 0))
}

/// The bias-compensated PLE.
pub fn bias_compensated_ple(bearings: &[Bearing]) -> Result<Fix, Error> {
    let geo = geometry(bearings)?;
    let (p, m) = plain(bearings, &geo)?;
    let mut bias = [0.0f32; 2];
    for b in usable(bearings) {
        let w = 1.0 / (b.sigma * b.sigma);
        let e_sin2 = 0.5 * (1.0 - libm::expf(-2.0 * b.sigma * b.sigma));
        let s = [b.vehicle[0] - geo.origin[0], b.vehicle[1] - geo.origin[1]];
        bias[0] += w * e_sin2 * (p[0] - s[0]);
        bias[1] += w * e_sin2 * (p[1] - s[1]);
    }
    let delta = linalg::solve2(&m, &bias).ok_or(Error::DegenerateGeometry)?;
    Ok(fix_at(
        &geo,
        [p[0] + delta[0], p[1] + delta[1]],
        bearings,
        0,
    ))
}

/// The weighted instrumental variable estimator, started from the bias-compensated PLE and
/// iterated `iterations` times (2-3 suffice).
pub fn wiv(bearings: &[Bearing], iterations: u32) -> Result<Fix, Error> {
    let geo = geometry(bearings)?;
    let start = bias_compensated_ple(bearings)?;
    let mut p = [
        start.position[0] - geo.origin[0],
        start.position[1] - geo.origin[1],
    ];
    for _ in 0..iterations {
        let current = p;
        let (next, _) = solve(bearings, &geo, |b, s| {
            let h = predicted(&current, &s);
            let (dx, dy) = (current[0] - s[0], current[1] - s[1]);
            let d2 = dx * dx + dy * dy;
            let w = 1.0 / (b.sigma * b.sigma * d2.max(1e-6));
            ([libm::sinf(h), -libm::cosf(h)], w)
        })?;
        p = next;
    }
    Ok(fix_at(&geo, p, bearings, iterations))
}
