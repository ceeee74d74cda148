//! Posterior Cramér-Rao bound for tracking (Tichavsky, Muravchik and Nehorai 1998).
//!
//! With linear Gaussian dynamics x_{k+1} = F x_k + w, w ~ N(0, Q), the recursion
//! J_{k+1} = D22 - D21 (J_k + D11)^-1 D12 (D11 = F^T Q^-1 F, D12 = -F^T Q^-1,
//! D22 = Q^-1 + E[H^T R^-1 H]) reduces by the matrix inversion lemma to
//! J_{k+1} = (Q + F J_k^-1 F^T)^-1 + E[H^T R^-1 H], which is what is computed here. The
//! expectation over true trajectories is the caller's (average the information of simulated
//! trajectories at each step). The inverses are taken scaled to unit diagonal: position,
//! velocity and sensor parameters differ in size by many orders, more than f32 keeps otherwise.

use crate::error::Error;
use crate::linalg::inverse_scaled;

/// One step of the recursion: from J_k and the expected measurement information at k + 1.
pub fn pcrb_step<const D: usize>(
    j: &[[f32; D]; D],
    f: &[[f32; D]; D],
    q: &[[f32; D]; D],
    information: &[[f32; D]; D],
) -> Result<[[f32; D]; D], Error> {
    let p = inverse_scaled(j).ok_or(Error::DegenerateGeometry)?;
    // Q + F P F^T
    let mut m = *q;
    for r in 0..D {
        for c in 0..D {
            let mut s = 0.0;
            for a in 0..D {
                for b in 0..D {
                    s += f[r][a] * p[a][b] * f[c][b];
                }
            }
            m[r][c] += s;
        }
    }
    let mut next = inverse_scaled(&m).ok_or(Error::DegenerateGeometry)?;
    for r in 0..D {
        for c in 0..D {
            next[r][c] += information[r][c];
        }
    }
    if next.iter().flatten().all(|v| v.is_finite()) {
        Ok(next)
    } else {
        Err(Error::NonFinite)
    }
}
