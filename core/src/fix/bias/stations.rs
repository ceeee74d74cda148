//! The station table: one row per DF station, its offset's prior in, its estimate out, and the
//! blocks of the normal equations the solver eliminates it with.
//!
//! Each bearing depends on the position and on its own station's offset only, so the normal
//! matrix over [x, y, b_0 .. b_{S-1}] is an arrow: a 2 x 2 position block, a 2 x 1 column and a
//! 1 x 1 diagonal entry per station, nothing between stations. Each offset is eliminated on its
//! own (the Schur complement of its diagonal entry), leaving a 2 x 2 system for the position:
//! O(N + S) work and O(S) memory for any number of stations, where the dense (2 + S)-square
//! matrix cost O(S^3). Per station the bearings are summed as a weighted mean and scatter of
//! their Jacobians (Welford's update, so a fixed station whose bearings all share one Jacobian
//! leaves an exact zero scatter instead of the difference of two large sums):
//!
//! - the position block of station s is C_s + W_s m_s m_s^T (C_s the scatter, m_s the mean
//!   Jacobian, W_s the summed weight), its column W_s m_s, its diagonal W_s + I_s (I_s the
//!   prior's information);
//! - eliminating b_s leaves C_s + a_s m_s m_s^T with a_s = W_s I_s / (W_s + I_s): a station
//!   that measures its offset well (W_s >> I_s) keeps only the spread of its geometry, one that
//!   relies on its prior (a fixed station: C_s = 0) keeps I_s, and the position covariance
//!   shows the prior's share.

use super::BiasPrior;
use crate::error::{Error, check_finite};

/// One station's row of the table a fix works in (see the module doc). The caller gives each
/// row its prior ([`StationSlot::new`]) and reads the fit's offset back
/// ([`StationSlot::offset`]); the rest is the solver's room.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationSlot {
    /// The prior the caller gave.
    given: BiasPrior,
    /// The prior in force (a channel's later sources see the emitter's estimate).
    pub(super) in_force: BiasPrior,
    /// Sd of the station's unmodelled systematic error, radians (0: none; already in the
    /// priors' sds).
    unmodelled: f32,
    /// The last fit's offset, radians.
    pub(super) bias: f32,
    /// Its standard deviation, radians.
    pub(super) sd: f32,
    /// Bearings of this station in the last fit.
    pub(super) used: u32,
    /// Share of the offset's information the last fit's bearings gave (0: the prior alone).
    pub(super) measured: f32,
    /// Whether the offset is an unknown of the current problem (seen, prior sd > 0).
    pub(super) free: bool,
    /// Bearings of this station in the current problem.
    pub(super) n: u32,
    /// The solver's offset, its trial step's, and one kept aside (a profile's start).
    pub(super) x: f32,
    pub(super) trial: f32,
    pub(super) saved: f32,
    /// The last fit as it was before a profile round the circle ([`super::offset_circle`]):
    /// offset, sd, share measured, and the bearings it used.
    held: ([f32; 3], u32),
    /// Summed weight, mean Jacobian and mean residual of the current accumulation.
    w: f32,
    mean_j: [f32; 2],
    mean_r: f32,
    /// Weighted scatter of the Jacobians (xx, xy, yy) and their cross-scatter with the
    /// residuals.
    scatter: [f32; 3],
    cross: [f32; 2],
}

impl Default for StationSlot {
    fn default() -> Self {
        Self::new(BiasPrior::default())
    }
}

impl StationSlot {
    /// A row for a station whose offset has `prior`.
    pub const fn new(prior: BiasPrior) -> Self {
        Self {
            given: prior,
            in_force: prior,
            unmodelled: 0.0,
            bias: prior.mean,
            sd: prior.sd,
            used: 0,
            measured: 0.0,
            free: false,
            n: 0,
            x: prior.mean,
            trial: prior.mean,
            saved: prior.mean,
            held: ([prior.mean, prior.sd, 0.0], 0),
            w: 0.0,
            mean_j: [0.0; 2],
            mean_r: 0.0,
            scatter: [0.0; 3],
            cross: [0.0; 2],
        }
    }

    /// The same row with an unmodelled systematic error of sd `sd` (radians) on its bearings:
    /// an error common to the station's bearings (geodesy, mounting, a calibration's residue)
    /// that no number of them averages away. Its variance is added to the offset prior's (the
    /// prior given and in force): indistinguishable from the offset, it is the offset's
    /// uncertainty, so the position covariance carries its share as it carries the prior's
    /// (exactly, for a station whose bearings cannot show its offset: a fixed station, a
    /// calibrated unit on a straight road; a vehicle whose drive measures its offset takes a
    /// common error up there, where it costs the position nothing). A calibrated prior
    /// becomes a free offset with this sd; no prior stays no prior.
    pub fn with_unmodelled(self, sd: f32) -> Self {
        let widen = |p: BiasPrior| BiasPrior {
            mean: p.mean,
            sd: libm::hypotf(p.sd, sd),
        };
        let mut row = Self::new(widen(self.given));
        row.in_force = widen(self.in_force);
        row.unmodelled = sd;
        row
    }

    /// Sd of the station's unmodelled systematic error, radians.
    pub fn unmodelled(&self) -> f32 {
        self.unmodelled
    }

    /// `Ok` when the prior is usable ([`BiasPrior::check`]) and the unmodelled error's sd is
    /// finite and >= 0.
    pub fn check(&self) -> Result<(), Error> {
        self.given.check()?;
        check_finite(&[self.unmodelled])?;
        if self.unmodelled >= 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// The prior the caller gave (its unmodelled error's variance added,
    /// [`StationSlot::with_unmodelled`]).
    pub fn prior(&self) -> BiasPrior {
        self.given
    }

    /// The prior in force for the next fit.
    pub fn prior_in_force(&self) -> BiasPrior {
        self.in_force
    }

    /// Narrow the prior in force to `prior` (the caller's stays as given).
    pub fn set_prior_in_force(&mut self, prior: BiasPrior) {
        self.in_force = prior;
    }

    /// Back to the caller's prior, the last fit forgotten.
    pub fn reset(&mut self) {
        let unmodelled = self.unmodelled;
        *self = Self::new(self.given);
        self.unmodelled = unmodelled;
    }

    /// The last fit's offset and its sd, radians (the prior's where the station took no part).
    pub fn offset(&self) -> (f32, f32) {
        (self.bias, self.sd)
    }

    /// Bearings of this station the last fit used.
    pub fn used(&self) -> u32 {
        self.used
    }

    /// Share of the offset's information that came from the last fit's bearings: near 0 when
    /// the prior governs (a fixed station), near 1 when the bearings measured it.
    pub fn measured(&self) -> f32 {
        self.measured
    }

    /// Keep the solver's current offset aside ([`super::StartOffsets::Saved`] starts from it).
    pub(crate) fn keep_current(&mut self) {
        self.saved = self.x;
    }

    /// Hold the last fit aside, exactly, while other fits use the row.
    pub(super) fn hold(&mut self) {
        self.held = ([self.bias, self.sd, self.measured], self.used);
    }

    /// The fit held aside back, exactly.
    pub(super) fn unhold(&mut self) {
        let ([bias, sd, measured], used) = self.held;
        (self.bias, self.sd, self.measured, self.used) = (bias, sd, measured, used);
        self.x = bias;
    }

    /// Forget the last accumulation.
    pub(super) fn clear_blocks(&mut self) {
        self.w = 0.0;
        self.mean_j = [0.0; 2];
        self.mean_r = 0.0;
        self.scatter = [0.0; 3];
        self.cross = [0.0; 2];
    }

    /// Add one bearing: Jacobian `j` of its prediction with respect to the position, weight
    /// `w` (information), residual `r` (weighted Welford update).
    pub(super) fn add(&mut self, j: [f32; 2], w: f32, r: f32) {
        if !(w > 0.0) {
            return;
        }
        let total = self.w + w;
        let f = w / total;
        let dj = [j[0] - self.mean_j[0], j[1] - self.mean_j[1]];
        let dr = r - self.mean_r;
        self.mean_j[0] += f * dj[0];
        self.mean_j[1] += f * dj[1];
        self.mean_r += f * dr;
        let after = [j[0] - self.mean_j[0], j[1] - self.mean_j[1]];
        self.scatter[0] += w * dj[0] * after[0];
        self.scatter[1] += w * dj[0] * after[1];
        self.scatter[2] += w * dj[1] * after[1];
        self.cross[0] += w * dj[0] * (r - self.mean_r);
        self.cross[1] += w * dj[1] * (r - self.mean_r);
        self.w = total;
    }

    /// The offset's diagonal entry damped by `lambda`, (W + I)(1 + lambda).
    fn diagonal(&self, lambda: f32) -> f32 {
        (self.w + self.in_force.information()) * (1.0 + lambda)
    }
}

/// The position's normal equations with every offset eliminated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Reduced {
    /// The reduced 2 x 2 matrix (the inverse of the position's marginal covariance when
    /// undamped).
    pub(super) matrix: [[f32; 2]; 2],
    /// The reduced gradient.
    pub(super) gradient: [f32; 2],
    /// The full matrix's position diagonal (what the damping scales).
    pub(super) diagonal: [f32; 2],
}

/// Eliminate every free offset from the accumulated blocks (damping the full matrix's diagonal
/// by 1 + `lambda`). A free station whose damped diagonal is not positive leaves the offsets
/// undetermined: `None`.
pub(super) fn reduce(stations: &[StationSlot], lambda: f32) -> Option<Reduced> {
    let mut m = [[0.0f32; 2]; 2];
    let mut g = [0.0f32; 2];
    let mut diagonal = [0.0f32; 2];
    for s in stations.iter().filter(|s| s.n > 0) {
        let [jx, jy] = s.mean_j;
        let full = [
            s.scatter[0] + s.w * jx * jx,
            s.scatter[1] + s.w * jx * jy,
            s.scatter[2] + s.w * jy * jy,
        ];
        diagonal[0] += full[0];
        diagonal[1] += full[2];
        let (a, rhs) = if s.free {
            let h = s.diagonal(lambda);
            if !(h > 0.0) {
                return None;
            }
            let info = s.in_force.information();
            // h - W = I + lambda (W + I): what is left of the mean Jacobian's weight once the
            // offset has taken its share.
            let left = info + lambda * (s.w + info);
            let a = s.w * left / h;
            let rhs = s.w * (s.mean_r * left - info * (s.in_force.mean - s.x)) / h;
            (a, rhs)
        } else {
            (s.w, s.w * s.mean_r)
        };
        m[0][0] += s.scatter[0] + a * jx * jx;
        m[0][1] += s.scatter[1] + a * jx * jy;
        m[1][1] += s.scatter[2] + a * jy * jy;
        g[0] += s.cross[0] + rhs * jx;
        g[1] += s.cross[1] + rhs * jy;
    }
    m[1][0] = m[0][1];
    m[0][0] += lambda * diagonal[0];
    m[1][1] += lambda * diagonal[1];
    Some(Reduced {
        matrix: m,
        gradient: g,
        diagonal,
    })
}

/// Each free offset's step given the position's step `dp` (back-substitution), written to the
/// rows' `trial` from their `x`; the largest magnitude of the steps.
pub(super) fn back_substitute(stations: &mut [StationSlot], lambda: f32, dp: [f32; 2]) -> f32 {
    let mut largest = 0.0f32;
    for s in stations.iter_mut() {
        s.trial = s.x;
        if s.n == 0 || !s.free {
            continue;
        }
        let h = s.diagonal(lambda);
        let info = s.in_force.information();
        let g = s.w * s.mean_r + info * (s.in_force.mean - s.x);
        let along = s.w * (s.mean_j[0] * dp[0] + s.mean_j[1] * dp[1]);
        let d = (g - along) / h;
        s.trial = s.x + d;
        largest = largest.max(libm::fabsf(d));
    }
    largest
}

/// Each free offset's variance given the position's marginal covariance `c` (the block
/// inverse: 1 / h + W^2 m^T C m / h^2) and the share of its information the bearings gave,
/// written to the rows when `write`; the sum of those shares (the offsets' effective number of
/// unknowns).
pub(super) fn offset_variances(
    stations: &mut [StationSlot],
    c: &[[f32; 2]; 2],
    write: bool,
) -> Option<f32> {
    let mut shares = 0.0f32;
    for s in stations.iter_mut() {
        if s.n == 0 || !s.free {
            continue;
        }
        let h = s.diagonal(0.0);
        if !(h > 0.0) {
            return None;
        }
        let [jx, jy] = s.mean_j;
        let quad = jx * (c[0][0] * jx + c[0][1] * jy) + jy * (c[1][0] * jx + c[1][1] * jy);
        let var = 1.0 / h + s.w * s.w * quad / (h * h);
        let share = (1.0 - var * s.in_force.information()).clamp(0.0, 1.0);
        if write {
            s.sd = libm::sqrtf(var.max(0.0));
            s.measured = share;
        }
        shares += share;
    }
    Some(shares)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::inverse_scaled;

    /// The arrow's elimination against the dense (2 + S)-square inverse it replaces.
    #[test]
    fn the_reduced_system_is_the_dense_one_with_the_offsets_eliminated() {
        // Three stations: one with a prior, one without, one calibrated; a handful of
        // bearings each with varied Jacobians, weights and residuals.
        let priors = [
            BiasPrior {
                mean: 0.01,
                sd: 0.05,
            },
            BiasPrior {
                mean: 0.0,
                sd: f32::INFINITY,
            },
            BiasPrior::calibrated(0.02),
        ];
        let mut stations = priors.map(StationSlot::new);
        let rows: [(usize, [f32; 2], f32, f32); 9] = [
            (0, [1e-3, 2e-4], 400.0, 0.01),
            (0, [8e-4, 3e-4], 300.0, -0.02),
            (0, [9e-4, -1e-4], 500.0, 0.005),
            (1, [-2e-4, 7e-4], 200.0, 0.03),
            (1, [-3e-4, 6e-4], 250.0, -0.01),
            (1, [-1e-4, 9e-4], 150.0, 0.0),
            (2, [5e-4, 5e-4], 100.0, 0.02),
            (2, [4e-4, 6e-4], 120.0, -0.03),
            (2, [6e-4, 4e-4], 80.0, 0.01),
        ];
        let x = [0.012f32, -0.004, 0.02];
        for (s, slot) in stations.iter_mut().enumerate() {
            slot.x = x[s];
            slot.free = slot.in_force.is_free();
            slot.n = 3;
        }
        for &(s, j, w, r) in &rows {
            stations[s].add(j, w, r);
        }
        // The dense matrix over [x, y, b0, b1] (b2 is calibrated: not an unknown).
        let mut h = [[0.0f64; 4]; 4];
        let mut g = [0.0f64; 4];
        for &(s, j, w, r) in &rows {
            let mut jac = [j[0] as f64, j[1] as f64, 0.0, 0.0];
            if s < 2 {
                jac[2 + s] = 1.0;
            }
            for a in 0..4 {
                for b in 0..4 {
                    h[a][b] += w as f64 * jac[a] * jac[b];
                }
                g[a] += w as f64 * jac[a] * r as f64;
            }
        }
        let info = 1.0 / (0.05f64 * 0.05);
        h[2][2] += info;
        g[2] += info * (0.01 - 0.012);
        let lambda = 0.3f32;
        for i in 0..4 {
            h[i][i] *= 1.0 + lambda as f64;
        }
        let h32: [[f32; 4]; 4] = core::array::from_fn(|a| core::array::from_fn(|b| h[a][b] as f32));
        let inv = inverse_scaled(&h32).expect("dense inverse");
        let step: [f64; 4] =
            core::array::from_fn(|a| (0..4).map(|b| inv[a][b] as f64 * g[b]).sum());
        let r = reduce(&stations, lambda).expect("reduced");
        let c = inverse_scaled(&r.matrix).expect("2 x 2 inverse");
        let dp = [
            c[0][0] * r.gradient[0] + c[0][1] * r.gradient[1],
            c[1][0] * r.gradient[0] + c[1][1] * r.gradient[1],
        ];
        back_substitute(&mut stations, lambda, dp);
        let near = |a: f64, b: f64| (a - b).abs() <= 2e-3 * b.abs().max(1e-6);
        assert!(
            near(dp[0] as f64, step[0]) && near(dp[1] as f64, step[1]),
            "{dp:?} {step:?}"
        );
        for s in 0..2 {
            let d = (stations[s].trial - stations[s].x) as f64;
            assert!(near(d, step[2 + s]), "{s}: {d} {}", step[2 + s]);
        }
        assert_eq!(stations[2].trial, stations[2].x);
    }
}
