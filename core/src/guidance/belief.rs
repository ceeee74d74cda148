//! What the bearings so far say about the emitter and the unit's offset, at one hypothesised
//! emitter position, and what a bearing from a candidate position would add.
//!
//! The unknowns are [x, y, b] (docs/src/field.md, "Mounting offset"): a bearing from vehicle s adds
//! g g^T / sigma^2 to the Fisher information, g = [-dy/d^2, dx/d^2, 1] (d = emitter - s); the
//! offset's prior adds 1 / sd^2 to the last diagonal entry. The belief keeps the inverse C of
//! that 3 x 3 information, so a candidate bearing is a Sherman-Morrison update,
//! C' = C - w (C g)(C g)^T / (1 + w g^T C g), O(9) work with no inversion, and the position
//! marginal (the top-left 2 x 2 of C) is the bias-aware bound: the offset integrated out. For a
//! calibrated unit the offset column is dropped and the same formulas reduce to docs/src/guidance.md's
//! closed forms (D gain log(1 + u^T P u / (sigma^2 r^2)), A gain
//! u^T P^2 u / (sigma^2 r^2 + u^T P u)).

use crate::error::{Error, check_finite};
use crate::fix::bias::BiasPrior;
use crate::fix::ellipse::CEP50_PER_SD_SUM;
use crate::linalg::{self, inverse_scaled};
use crate::model::bearing::Bearing;

/// Hypothesised emitter positions a score is averaged over at most.
pub const MAX_POINTS: usize = 5;

/// The bias-aware covariance bound of [x, y, b] for an emitter at one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Belief {
    /// The emitter position the information is evaluated at, metres.
    pub emitter: [f32; 2],
    cov: [[f32; 3]; 3],
    bias_free: bool,
}

impl Belief {
    /// The belief of the usable `bearings` about an emitter at `emitter`, with the unit's
    /// offset `prior` and an isotropic prior of sd `position_sd` metres on the position
    /// (infinite for none; a finite one keeps the belief proper before the bearings cross,
    /// e.g. while every bearing so far came from one place).
    pub fn from_bearings(
        emitter: [f32; 2],
        bearings: &[Bearing],
        prior: BiasPrior,
        position_sd: f32,
    ) -> Result<Self, Error> {
        check_finite(&emitter)?;
        prior.check()?;
        if !(position_sd > 0.0) {
            return Err(Error::OutOfRange);
        }
        let bias_free = prior.is_free();
        let mut j = [[0.0f32; 3]; 3];
        for b in bearings.iter().filter(|b| b.check().is_ok()) {
            let Some(g) = jacobian(&emitter, &b.vehicle, bias_free) else {
                continue;
            };
            let w = 1.0 / (b.sigma * b.sigma);
            for r in 0..3 {
                for c in 0..3 {
                    j[r][c] += w * g[r] * g[c];
                }
            }
        }
        let p = if position_sd.is_finite() {
            1.0 / (position_sd * position_sd)
        } else {
            0.0
        };
        j[0][0] += p;
        j[1][1] += p;
        if bias_free {
            if prior.sd.is_finite() {
                j[2][2] += 1.0 / (prior.sd * prior.sd);
            }
        } else {
            // A calibrated unit: the offset is known; a unit entry keeps the matrix invertible
            // and its column is never touched (g has no offset component).
            j[2][2] = 1.0;
        }
        check_finite(&[j[0][0], j[0][1], j[1][1], j[0][2], j[1][2], j[2][2]])?;
        let mut cov = inverse_scaled(&j).ok_or(Error::DegenerateGeometry)?;
        if !bias_free {
            cov[2] = [0.0; 3];
            cov[0][2] = 0.0;
            cov[1][2] = 0.0;
        }
        let belief = Self {
            emitter,
            cov,
            bias_free,
        };
        belief.check()?;
        Ok(belief)
    }

    /// `Ok` when the position marginal is a proper covariance.
    fn check(&self) -> Result<(), Error> {
        check_finite(&self.cov[0])?;
        check_finite(&self.cov[1])?;
        check_finite(&self.cov[2])?;
        let p = self.position_covariance();
        let det = p[0][0] * p[1][1] - p[0][1] * p[1][0];
        if p[0][0] > 0.0 && p[1][1] > 0.0 && det > 0.0 {
            Ok(())
        } else {
            Err(Error::DegenerateGeometry)
        }
    }

    /// Add `count` bearings of noise `sigma` (radians) from vehicle position `vehicle`. A
    /// position on the emitter (or bad numbers) adds nothing and returns false.
    pub fn observe(&mut self, vehicle: [f32; 2], sigma: f32, count: f32) -> bool {
        if !(sigma > 0.0) || !(count > 0.0) || !count.is_finite() {
            return false;
        }
        let Some(g) = jacobian(&self.emitter, &vehicle, self.bias_free) else {
            return false;
        };
        let w = count / (sigma * sigma);
        let cg: [f32; 3] = core::array::from_fn(|r| {
            self.cov[r][0] * g[0] + self.cov[r][1] * g[1] + self.cov[r][2] * g[2]
        });
        let q = g[0] * cg[0] + g[1] * cg[1] + g[2] * cg[2];
        let s = 1.0 + w * q;
        if !(s >= 1.0) || !s.is_finite() {
            return false;
        }
        let f = w / s;
        let mut next = self.cov;
        for r in 0..3 {
            for c in 0..3 {
                next[r][c] -= f * cg[r] * cg[c];
            }
        }
        let before = *self;
        self.cov = next;
        if self.check().is_err() {
            // Round-off ate the update (information far beyond f32's digits): keep the old
            // covariance, a bound that is still valid.
            *self = before;
            return false;
        }
        true
    }

    /// The position covariance bound with the offset integrated out, m^2.
    pub fn position_covariance(&self) -> [[f32; 2]; 2] {
        [
            [self.cov[0][0], self.cov[0][1]],
            [self.cov[1][0], self.cov[1][1]],
        ]
    }

    /// The offset's sd bound, radians (0 for a calibrated unit).
    pub fn bias_sd(&self) -> f32 {
        libm::sqrtf(self.cov[2][2].max(0.0))
    }

    /// Whether the offset is an unknown of this belief.
    pub fn bias_free(&self) -> bool {
        self.bias_free
    }

    /// ln det of the position covariance (D-optimality: smaller is better).
    pub fn log_det(&self) -> f32 {
        let p = self.position_covariance();
        libm::logf((p[0][0] * p[1][1] - p[0][1] * p[1][0]).max(f32::MIN_POSITIVE))
    }

    /// Trace of the position covariance, m^2 (A-optimality).
    pub fn trace(&self) -> f32 {
        self.cov[0][0] + self.cov[1][1]
    }

    /// Standard deviations along the major and minor axes of the position covariance, metres.
    pub fn axes(&self) -> (f32, f32) {
        match linalg::eigen2(&self.position_covariance()) {
            Some((l1, l2, _)) => (libm::sqrtf(l1.max(0.0)), libm::sqrtf(l2.max(0.0))),
            None => (f32::MAX, f32::MAX),
        }
    }

    /// The predicted CEP50, metres: 0.59 (s_major + s_minor), as
    /// [`crate::fix::ellipse::cep50`] computes it.
    pub fn cep50(&self) -> f32 {
        let (a, b) = self.axes();
        CEP50_PER_SD_SUM * (a + b)
    }
}

/// d theta / d [x, y, b] of a bearing from `vehicle` to an emitter at `emitter`; `None` on the
/// emitter itself.
fn jacobian(emitter: &[f32; 2], vehicle: &[f32; 2], bias_free: bool) -> Option<[f32; 3]> {
    let dx = emitter[0] - vehicle[0];
    let dy = emitter[1] - vehicle[1];
    let d2 = dx * dx + dy * dy;
    if !(d2 > 1.0) || !d2.is_finite() {
        return None;
    }
    Some([-dy / d2, dx / d2, if bias_free { 1.0 } else { 0.0 }])
}

/// Where the emitter may be: the points a score is averaged over.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hypotheses {
    points: [[f32; 2]; MAX_POINTS],
    len: usize,
}

impl Hypotheses {
    /// One point: the fix, where the ellipse is small against the range.
    pub fn at(p: [f32; 2]) -> Self {
        let mut points = [[0.0; 2]; MAX_POINTS];
        points[0] = p;
        Self { points, len: 1 }
    }

    /// The points.
    pub fn points(&self) -> &[[f32; 2]] {
        self.points.get(..self.len).unwrap_or(&[])
    }

    /// The fix and, where its 1-sigma ellipse reaches beyond `wide` (a share, e.g. 0.15) of the
    /// range from `vehicle`, the points one sigma out along each wide axis (kept at least
    /// 10 % of the range in front of the vehicle): the posterior's spread, which a
    /// single-point score would ignore exactly when the answer is most uncertain.
    pub fn spread(
        position: [f32; 2],
        covariance: &[[f32; 2]; 2],
        vehicle: [f32; 2],
        wide: f32,
    ) -> Result<Self, Error> {
        check_finite(&position)?;
        check_finite(&vehicle)?;
        let (l1, l2, angle) = linalg::eigen2(covariance).ok_or(Error::NonFinite)?;
        let range = libm::hypotf(position[0] - vehicle[0], position[1] - vehicle[1]);
        let mut h = Self::at(position);
        let (c, s) = (libm::cosf(angle), libm::sinf(angle));
        for (sd, dir) in [
            (libm::sqrtf(l1.max(0.0)), [c, s]),
            (libm::sqrtf(l2.max(0.0)), [-s, c]),
        ] {
            if !(sd > wide * range) {
                continue;
            }
            for sign in [-1.0f32, 1.0] {
                let mut p = [
                    position[0] + sign * sd * dir[0],
                    position[1] + sign * sd * dir[1],
                ];
                let (dx, dy) = (p[0] - vehicle[0], p[1] - vehicle[1]);
                let r = libm::hypotf(dx, dy);
                if r < 0.1 * range && r > 0.0 {
                    let k = 0.1 * range / r;
                    p = [vehicle[0] + dx * k, vehicle[1] + dy * k];
                }
                if let Some(slot) = h.points.get_mut(h.len)
                    && p.iter().all(|v| v.is_finite())
                {
                    *slot = p;
                    h.len += 1;
                }
            }
        }
        Ok(h)
    }

    /// Before the bearings cross: points along the line of bearing `theta` from `vehicle` at
    /// the given ranges (at most [`MAX_POINTS`]; docs/src/field.md's initialisation spreads them
    /// evenly
    /// in log range).
    pub fn along(vehicle: [f32; 2], theta: f32, ranges: &[f32]) -> Result<Self, Error> {
        check_finite(&vehicle)?;
        check_finite(&[theta])?;
        let mut h = Self {
            points: [[0.0; 2]; MAX_POINTS],
            len: 0,
        };
        for r in ranges.iter().take(MAX_POINTS) {
            if !(*r > 0.0) || !r.is_finite() {
                return Err(Error::OutOfRange);
            }
            h.points[h.len] = [
                vehicle[0] + r * libm::cosf(theta),
                vehicle[1] + r * libm::sinf(theta),
            ];
            h.len += 1;
        }
        if h.len == 0 {
            return Err(Error::TooFewMeasurements);
        }
        Ok(h)
    }
}

/// The beliefs at every hypothesis, written into `out`; how many. Points where the bearings
/// give no proper belief are left out.
pub fn beliefs(
    hypotheses: &Hypotheses,
    bearings: &[Bearing],
    prior: BiasPrior,
    position_sd: f32,
    out: &mut [Belief; MAX_POINTS],
) -> usize {
    let mut n = 0;
    for p in hypotheses.points() {
        if let Ok(b) = Belief::from_bearings(*p, bearings, prior, position_sd)
            && let Some(slot) = out.get_mut(n)
        {
            *slot = b;
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fix::bias;
    use crate::model::bearing::predicted;

    const DEG: f32 = core::f32::consts::PI / 180.0;

    fn road(e: [f32; 2], n: usize, len: f32) -> [Bearing; 40] {
        core::array::from_fn(|k| {
            let v = [-0.5 * len + len * (k % n) as f32 / n as f32, 0.0];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 3.0 * DEG,
            }
        })
    }

    #[test]
    fn the_belief_is_the_bias_aware_bound() {
        let e = [300.0, 2000.0];
        let bs = road(e, 40, 1500.0);
        let prior = BiasPrior::default();
        let b = Belief::from_bearings(e, &bs, prior, f32::INFINITY).unwrap();
        let bound = bias::crlb(&e, &bs, prior).unwrap();
        let rmse = libm::sqrtf(b.trace());
        assert!(
            (rmse - bound.rmse).abs() < 1e-3 * bound.rmse,
            "{rmse} {bound:?}"
        );
        assert!((b.bias_sd() - bound.bias_sd).abs() < 1e-3 * bound.bias_sd);
        // Calibrated: the plain CRLB.
        let cal = Belief::from_bearings(e, &bs, BiasPrior::calibrated(0.0), f32::INFINITY).unwrap();
        let plain = crate::fix::crlb::crlb(&e, &bs).unwrap().rmse;
        assert!((libm::sqrtf(cal.trace()) - plain).abs() < 1e-3 * plain);
        assert_eq!(cal.bias_sd(), 0.0);
    }

    #[test]
    fn an_observed_bearing_equals_recomputing_with_it() {
        let e = [300.0, 2000.0];
        let bs = road(e, 40, 1500.0);
        let v = [1800.0, 900.0];
        for prior in [BiasPrior::default(), BiasPrior::calibrated(0.0)] {
            let mut b = Belief::from_bearings(e, &bs[..30], prior, f32::INFINITY).unwrap();
            // Ten bearings from v at once, as one update of weight 10.
            assert!(b.observe(v, 3.0 * DEG, 10.0));
            let mut more = [bs[0]; 40];
            more[..30].copy_from_slice(&bs[..30]);
            for m in more[30..].iter_mut() {
                *m = Bearing {
                    vehicle: v,
                    theta: predicted(&e, &v),
                    sigma: 3.0 * DEG,
                };
            }
            let r = Belief::from_bearings(e, &more, prior, f32::INFINITY).unwrap();
            let (p, q) = (b.position_covariance(), r.position_covariance());
            for i in 0..2 {
                for j in 0..2 {
                    assert!(
                        (p[i][j] - q[i][j]).abs() < 2e-3 * q[0][0].max(q[1][1]),
                        "{p:?} {q:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn field_closed_forms_hold_for_a_calibrated_unit() {
        // D gain = log(1 + u^T P u / (sigma^2 r^2)) with u perpendicular to the line of sight.
        let e = [0.0, 3000.0];
        let bs = road(e, 40, 800.0);
        let b = Belief::from_bearings(e, &bs, BiasPrior::calibrated(0.0), f32::INFINITY).unwrap();
        let v = [2000.0, 500.0];
        let (dx, dy) = (e[0] - v[0], e[1] - v[1]);
        let r = libm::hypotf(dx, dy);
        let u = [-dy / r, dx / r];
        let p = b.position_covariance();
        let upu =
            u[0] * (p[0][0] * u[0] + p[0][1] * u[1]) + u[1] * (p[1][0] * u[0] + p[1][1] * u[1]);
        let s2r2 = (3.0 * DEG) * (3.0 * DEG) * r * r;
        let mut after = b;
        after.observe(v, 3.0 * DEG, 1.0);
        let d_gain = b.log_det() - after.log_det();
        let expect = libm::logf(1.0 + upu / s2r2);
        assert!((d_gain - expect).abs() < 0.01 * expect, "{d_gain} {expect}");
        let pu = [
            p[0][0] * u[0] + p[0][1] * u[1],
            p[1][0] * u[0] + p[1][1] * u[1],
        ];
        let a_expect = (pu[0] * pu[0] + pu[1] * pu[1]) / (s2r2 + upu);
        let a_gain = b.trace() - after.trace();
        assert!(
            (a_gain - a_expect).abs() < 0.01 * a_expect,
            "{a_gain} {a_expect}"
        );
    }

    #[test]
    fn hypotheses_follow_the_spread() {
        let narrow =
            Hypotheses::spread([0.0, 3000.0], &[[100.0, 0.0], [0.0, 400.0]], [0.0; 2], 0.15)
                .unwrap();
        assert_eq!(narrow.points().len(), 1);
        // 1 km sd along the line of sight at 3 km: two more points, the near one in front.
        let wide =
            Hypotheses::spread([0.0, 3000.0], &[[100.0, 0.0], [0.0, 1e6]], [0.0; 2], 0.15).unwrap();
        assert_eq!(wide.points().len(), 3);
        assert!(wide.points().iter().all(|p| p[1] >= 300.0 - 1e-3));
        let line = Hypotheses::along([0.0; 2], 0.0, &[1000.0, 2000.0, 4000.0]).unwrap();
        assert_eq!(line.points()[2], [4000.0, 0.0]);
        assert_eq!(
            Hypotheses::along([0.0; 2], 0.0, &[-1.0]),
            Err(Error::OutOfRange)
        );
        assert!(Belief::from_bearings([f32::NAN, 0.0], &[], BiasPrior::default(), 1e4).is_err());
        // No bearing, a proper prior: a belief all the same (the prior's).
        let b = Belief::from_bearings([0.0, 0.0], &[], BiasPrior::default(), 1000.0).unwrap();
        assert!((b.trace() - 2e6).abs() < 10.0);
    }
}
