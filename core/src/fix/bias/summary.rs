//! A fixed station's bearings summed up for a quadratic loss.
//!
//! Bearings taken from one place with one sd predict one direction at any position, so under
//! a Gaussian their summed cost is n R^2 + S over sigma^2 (R the residual of their mean, S
//! their scatter about it) and their normal equations one term of weight n: a mast with
//! forty bearings in a window costs the solver's passes one atan2 instead of forty. Exact
//! while no residual wraps: |R| plus the bearings' farthest deviation from their mean stays
//! below pi ([`Summary::residual`] says when it does not, and every bearing then counts
//! alone).

use core::f32::consts::FRAC_PI_2;

use crate::model::bearing::{Bearing, predicted, wrap};

/// Widest deviation from the first bearing a summary takes (a spread this wide is no
/// station's noise, and the mean of angles this far apart is ill-defined).
const WIDEST: f32 = FRAC_PI_2;

/// Largest |R| + spread the summary holds for: a little under pi, so rounding never lets a
/// residual that wraps count as one that does not.
const NO_WRAP: f32 = 3.1;

/// Values seen from one place or several, with weights: their weighted mean, their weighted
/// squared deviations from it (updated a value at a time, Welford's way, so no large sums
/// cancel) and their range, and whether they all came from one place. A station's bearings
/// ([`Summary`]) and its residuals at a fit (the no-rival bound's scatter) both count so.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct OnePlace {
    /// The first value's place, and whether a later one came from another.
    at: Option<[f32; 2]>,
    moved: bool,
    /// The weights' sum, the mean, the squared deviations and the range.
    pub(super) w: f32,
    pub(super) mean: f32,
    pub(super) scatter: f32,
    pub(super) low: f32,
    pub(super) high: f32,
}

impl OnePlace {
    /// Nothing seen.
    pub(super) const EMPTY: Self = Self {
        at: None,
        moved: false,
        w: 0.0,
        mean: 0.0,
        scatter: 0.0,
        low: f32::INFINITY,
        high: f32::NEG_INFINITY,
    };

    /// Count value `x` of weight `w` seen from `place`.
    pub(super) fn add(&mut self, place: [f32; 2], x: f32, w: f32) {
        if *self.at.get_or_insert(place) != place {
            self.moved = true;
        }
        self.w += w;
        let before = x - self.mean;
        self.mean += w * before / self.w;
        self.scatter += w * before * (x - self.mean);
        self.low = self.low.min(x);
        self.high = self.high.max(x);
    }

    /// The one place every value came from, if any came.
    pub(super) fn place(&self) -> Option<[f32; 2]> {
        self.at.filter(|_| !self.moved)
    }
}

/// One station's bearings as the problem's set-up counted them: their differences from the
/// first, of weight one each.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Summary {
    /// The first bearing (theta) and its sd (radians).
    first: f32,
    sigma: f32,
    /// The bearings' wrapped differences from the first.
    values: OnePlace,
    /// A bearing with another sd, or too far from the first.
    mixed: bool,
}

/// A summary ready to stand for its bearings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Summed {
    /// Bearings it stands for.
    pub(super) n: f32,
    /// Where they were taken, and their sd (radians).
    pub(super) place: [f32; 2],
    pub(super) sigma: f32,
    /// Their mean (theta) and their scatter about it (rad^2).
    pub(super) mean: f32,
    pub(super) scatter: f32,
    /// Farthest deviation of one of them from the mean (radians).
    spread: f32,
}

impl Summary {
    /// No bearings.
    pub(super) const EMPTY: Self = Self {
        first: 0.0,
        sigma: 0.0,
        values: OnePlace::EMPTY,
        mixed: false,
    };

    /// Count bearing `b`.
    pub(super) fn add(&mut self, b: &Bearing) {
        if self.values.w == 0.0 {
            self.first = b.theta;
            self.sigma = b.sigma;
        }
        let d = wrap(b.theta - self.first);
        self.mixed |= b.sigma != self.sigma || libm::fabsf(d) > WIDEST;
        self.values.add(b.vehicle, d, 1.0);
    }

    /// Where the bearings were all taken, if two or more and from one place: the direction
    /// they predict is one `atan2` for all of them, whatever the loss.
    pub(super) fn one_place(&self) -> Option<[f32; 2]> {
        self.values.place().filter(|_| self.values.w >= 2.0)
    }

    /// The summary, where it stands for two or more bearings from one place with one sd.
    pub(super) fn summed(&self) -> Option<Summed> {
        let v = &self.values;
        let place = self.one_place().filter(|_| !self.mixed)?;
        Some(Summed {
            n: v.w,
            place,
            sigma: self.sigma,
            mean: wrap(self.first + v.mean),
            scatter: v.scatter.max(0.0),
            spread: (v.high - v.mean).max(v.mean - v.low),
        })
    }
}

impl Summed {
    /// The mean's residual at centred position `p` (the problem's `origin` taken off the
    /// place) with correction `bias`, where no bearing's own residual wraps; `None` where one
    /// might.
    pub(super) fn residual(&self, origin: [f32; 2], p: [f32; 2], bias: f32) -> Option<f32> {
        let s = [self.place[0] - origin[0], self.place[1] - origin[1]];
        let r = wrap(self.mean - predicted(&p, &s) - bias);
        (libm::fabsf(r) + self.spread < NO_WRAP).then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    fn at(vehicle: [f32; 2], theta: f32) -> Bearing {
        Bearing {
            vehicle,
            theta,
            sigma: 0.05,
        }
    }

    #[test]
    fn bearings_either_side_of_the_wrap_have_their_mean_and_scatter() {
        let mut s = Summary::EMPTY;
        for t in [PI - 0.1, -PI + 0.1, PI - 0.05, -PI + 0.05] {
            s.add(&at([0.0, 0.0], t));
        }
        let g = s.summed().unwrap();
        assert_eq!(g.n, 4.0);
        assert!(libm::fabsf(wrap(g.mean - PI)) < 1e-5, "{}", g.mean);
        // Deviations +-0.1 and +-0.05: 2 (0.01 + 0.0025).
        assert!(libm::fabsf(g.scatter - 0.025) < 1e-5, "{}", g.scatter);
        // An emitter due west: the mean's residual is about 0 and no bearing's wraps; due
        // east, a half-turn away, they might, and the summary says so.
        let r = g.residual([0.0, 0.0], [-1000.0, 0.0], 0.0).unwrap();
        assert!(libm::fabsf(r) < 1e-5, "{r}");
        assert!(g.residual([0.0, 0.0], [1000.0, 0.0], 0.0).is_none());
        assert!(g.residual([0.0, 0.0], [1000.0, 0.0], PI - 0.2).is_some());
    }

    #[test]
    fn one_bearing_another_place_or_sd_or_a_wide_spread_is_no_summary() {
        let mut one = Summary::EMPTY;
        one.add(&at([0.0, 0.0], 0.3));
        assert!(one.summed().is_none());
        let mut moved = one;
        moved.add(&at([1.0, 0.0], 0.3));
        assert!(moved.summed().is_none());
        let mut sd = one;
        sd.add(&Bearing {
            sigma: 0.1,
            ..at([0.0, 0.0], 0.3)
        });
        assert!(sd.summed().is_none());
        let mut wide = one;
        wide.add(&at([0.0, 0.0], 0.3 + 2.0));
        assert!(wide.summed().is_none());
        let mut two = one;
        two.add(&at([0.0, 0.0], 0.4));
        assert!(two.summed().is_some());
        // One place is one direction whatever the sds and the spread.
        assert_eq!(sd.one_place(), Some([0.0, 0.0]));
        assert_eq!(wide.one_place(), Some([0.0, 0.0]));
        assert_eq!(moved.one_place(), None);
        assert_eq!(one.one_place(), None);
    }
}
