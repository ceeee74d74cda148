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

/// One station's bearings as the problem's set-up counted them (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Summary {
    /// Bearings counted.
    n: u32,
    /// Where they were taken, and their sd (radians), both as the first bearing's.
    place: [f32; 2],
    sigma: f32,
    /// The first bearing (theta) and the running mean, scatter and extremes of the others'
    /// wrapped difference from it.
    first: f32,
    mean: f32,
    scatter: f32,
    low: f32,
    high: f32,
    /// A bearing from another place.
    moved: bool,
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
        n: 0,
        place: [0.0; 2],
        sigma: 0.0,
        first: 0.0,
        mean: 0.0,
        scatter: 0.0,
        low: 0.0,
        high: 0.0,
        moved: false,
        mixed: false,
    };

    /// Count bearing `b` (Welford's update of the mean and scatter).
    pub(super) fn add(&mut self, b: &Bearing) {
        if self.n == 0 {
            *self = Self {
                n: 1,
                place: b.vehicle,
                sigma: b.sigma,
                first: b.theta,
                ..Self::EMPTY
            };
            return;
        }
        let d = wrap(b.theta - self.first);
        self.moved |= b.vehicle != self.place;
        self.mixed |= b.sigma != self.sigma || libm::fabsf(d) > WIDEST;
        self.n += 1;
        let before = d - self.mean;
        self.mean += before / self.n as f32;
        self.scatter += before * (d - self.mean);
        self.low = self.low.min(d);
        self.high = self.high.max(d);
    }

    /// Where the bearings were all taken, if two or more and from one place: the direction
    /// they predict is one `atan2` for all of them, whatever the loss.
    pub(super) fn one_place(&self) -> Option<[f32; 2]> {
        (self.n >= 2 && !self.moved).then_some(self.place)
    }

    /// The summary, where it stands for two or more bearings from one place with one sd.
    pub(super) fn summed(&self) -> Option<Summed> {
        (self.n >= 2 && !self.moved && !self.mixed).then(|| Summed {
            n: self.n as f32,
            place: self.place,
            sigma: self.sigma,
            mean: wrap(self.first + self.mean),
            scatter: self.scatter.max(0.0),
            spread: (self.high - self.mean).max(self.mean - self.low),
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
