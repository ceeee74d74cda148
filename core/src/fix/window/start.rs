//! The start without a previous fix: the pair search, and the test that no position can come of
//! the window at all.

use super::{DEG, HYPOTHESES, MAX_RANGE_M, PAIR_ATTEMPTS, WindowFix, fold, sin_cos};
use crate::fastmath::atan2;
use rand_core::Rng;

/// Vehicle positions within this of each other count as one position, metres.
const STATIONARY_M: f32 = 1.0;
/// Bearings within this of each other (radians) count as parallel.
const PARALLEL_RAD: f32 = 0.1 * DEG;
/// The sine of the shallowest crossing a pair may make.
const MIN_CROSSING_SIN: f32 = 0.017_452_4;

impl WindowFix {
    /// No position can come of the window: every vehicle position in one place, or every
    /// bearing parallel.
    pub(super) fn degenerate(&self) -> bool {
        let Some(first) = self.entry(0).copied() else {
            return true;
        };
        let mut moved = false;
        let mut turned = false;
        for e in self.entries() {
            let (dx, dy) = (
                e.vehicle[0] - first.vehicle[0],
                e.vehicle[1] - first.vehicle[1],
            );
            moved |= dx * dx + dy * dy > STATIONARY_M * STATIONARY_M;
            turned |= libm::fabsf(fold(e.theta - first.theta)) > PARALLEL_RAD;
        }
        !(moved && turned)
    }

    /// Bearings that pass within three sigmas (or half a degree) of `p`, and their summed
    /// absolute residuals.
    fn support(&self, origin: [f32; 2], p: [f32; 2], sigma: f32) -> (u32, f32) {
        let mut n = 0;
        let mut spread = 0.0;
        for e in self.entries() {
            let dx = p[0] - (e.vehicle[0] - origin[0]);
            let dy = p[1] - (e.vehicle[1] - origin[1]);
            let r = libm::fabsf(fold(e.theta - atan2(dy, dx)));
            if r <= (3.0 * sigma * e.rel).max(0.5 * DEG) {
                n += 1;
                spread += r;
            }
        }
        (n, spread)
    }

    /// Where the bearings of entries `i` and `j` cross (centred), if in front of both within
    /// range.
    fn crossing(&self, origin: [f32; 2], i: usize, j: usize) -> Option<[f32; 2]> {
        let (a, b) = (self.entry(i)?, self.entry(j)?);
        let (sa, ca) = sin_cos(a.theta);
        let (sb, cb) = sin_cos(b.theta);
        let cross = ca * sb - sa * cb;
        if libm::fabsf(cross) < MIN_CROSSING_SIN {
            return None;
        }
        let dp = [b.vehicle[0] - a.vehicle[0], b.vehicle[1] - a.vehicle[1]];
        let s = (dp[0] * sb - dp[1] * cb) / cross;
        let t = (dp[0] * sa - dp[1] * ca) / cross;
        if !(s > 0.0 && t > 0.0) {
            return None;
        }
        let p = [
            a.vehicle[0] - origin[0] + s * ca,
            a.vehicle[1] - origin[1] + s * sa,
        ];
        let far = p[0] * p[0] + p[1] * p[1] > MAX_RANGE_M * MAX_RANGE_M;
        (p[0].is_finite() && p[1].is_finite() && !far).then_some(p)
    }

    /// The pair search: the crossing most window bearings agree with.
    pub(super) fn search<R: Rng + ?Sized>(
        &mut self,
        origin: [f32; 2],
        sigma: f32,
        rng: &mut R,
    ) -> Option<[f32; 2]> {
        self.counters.searches += 1;
        let n = self.len as u32;
        let mut best: Option<(u32, f32, [f32; 2])> = None;
        let mut scored = 0;
        for _ in 0..PAIR_ATTEMPTS {
            if scored >= HYPOTHESES {
                break;
            }
            let i = (rng.next_u32() % n) as usize;
            let j = (rng.next_u32() % n) as usize;
            if i == j {
                continue;
            }
            let Some(p) = self.crossing(origin, i, j) else {
                continue;
            };
            scored += 1;
            let (count, spread) = self.support(origin, p, sigma);
            let better = match best {
                None => true,
                Some((c, s, _)) => count > c || (count == c && spread < s),
            };
            if better {
                best = Some((count, spread, p));
            }
        }
        best.filter(|b| b.0 >= 3).map(|b| b.2)
    }
}
