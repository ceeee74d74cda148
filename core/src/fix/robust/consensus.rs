//! The consensus: the point most bearings agree on, each hypothesis with its best common
//! offset, and how likely luck would have lined up as many.

use super::super::bias::{BiasPrior, Sighting, StationSlot};
use super::super::intersection::intersect;
use super::super::noise::median_sigma;
use super::{MAX_RANGE_M, SCORE_SAMPLE};
use crate::error::{Error, check_finite};
use crate::model::bearing::{predicted, wrap};
use crate::random;
use crate::stats;
use core::f32::consts::PI;
use rand_core::Rng;

/// Settings of the robust search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RansacOptions {
    /// Hypotheses scored at most.
    pub hypotheses: u32,
    /// Bearing pairs drawn at most (pairs that do not cross well are drawn and dropped).
    pub max_attempts: u32,
    /// Minimum crossing angle of a pair, radians (small: a far emitter has only shallow ones).
    pub min_crossing: f32,
    /// A bearing agrees with a hypothesis within this many of its sigmas...
    pub threshold: f32,
    /// ...or within this angle, radians, whichever is larger.
    pub floor: f32,
    /// Hypotheses farther than this from the drive's centroid are dropped, metres (default
    /// [`MAX_RANGE_M`]).
    pub max_range: f32,
}

impl Default for RansacOptions {
    fn default() -> Self {
        Self {
            hypotheses: 256,
            max_attempts: 4096,
            min_crossing: 1.0 * PI / 180.0,
            threshold: 3.0,
            floor: 0.5 * PI / 180.0,
            max_range: MAX_RANGE_M,
        }
    }
}

impl RansacOptions {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[
            self.min_crossing,
            self.threshold,
            self.floor,
            self.max_range,
        ])?;
        if self.hypotheses > 0
            && self.max_attempts > 0
            && self.min_crossing >= 0.0
            && self.threshold > 0.0
            && self.floor >= 0.0
            && self.max_range > 0.0
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// The range of common offsets a hypothesis may take: centre +- half width (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetWindow {
    /// Centre, radians.
    pub centre: f32,
    /// Half width, radians (0: the offset is known).
    pub half_width: f32,
}

impl OffsetWindow {
    /// Three prior sds either side of the widest prior the caller gave the stations of `items`
    /// (capped at 30 degrees), centred on its mean; a zero window when every one is
    /// calibrated. The caller's priors, not the ones in force: the search looks where the
    /// caller said the offsets may lie, also for a channel's later sources, whose priors the
    /// emitter's estimate narrowed.
    pub fn from_stations<T: Sighting>(items: &[T], stations: &[StationSlot]) -> Self {
        let widest = items
            .iter()
            .filter_map(|t| stations.get(t.station()).map(StationSlot::prior))
            .fold(None::<BiasPrior>, |w, p| match w {
                Some(w) if w.sd >= p.sd => Some(w),
                _ => Some(p),
            })
            .unwrap_or_default();
        Self::from_prior(widest)
    }

    /// Three sds of `prior` either side of its mean (capped at 30 degrees).
    pub fn from_prior(prior: BiasPrior) -> Self {
        Self {
            centre: prior.mean,
            half_width: (3.0 * prior.sd).min(30.0 * PI / 180.0),
        }
    }
}

/// The best-supported point of a set of bearings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Consensus {
    /// The hypothesis, metres.
    pub position: [f32; 2],
    /// Its best common offset, radians.
    pub bias: f32,
    /// Bearings of the whole set within the threshold of it (offset removed).
    pub inliers: u32,
    /// Usable bearings in the set.
    pub candidates: u32,
    /// Hypotheses scored.
    pub hypotheses: u32,
    /// The agreement angle used, radians.
    pub threshold: f32,
}

/// Count of sorted `r` inside [lo, lo + width], and the mean of those (a contiguous run of the
/// sorted residuals, found by bisection).
fn window_at(r: &[f32], lo: f32, width: f32) -> (u32, f32) {
    let a = r.partition_point(|x| *x < lo);
    let b = a + r[a..].partition_point(|x| *x <= lo + width);
    let inside = &r[a..b];
    let n = inside.len() as u32;
    (
        n,
        if n > 0 {
            inside.iter().sum::<f32>() / n as f32
        } else {
            lo + 0.5 * width
        },
    )
}

/// The densest window of width 2t among sorted residuals `r`, its centre constrained to
/// `window`: (count, offset).
fn best_offset(r: &[f32], t: f32, window: OffsetWindow) -> (u32, f32) {
    let (lo_c, hi_c) = (
        window.centre - window.half_width,
        window.centre + window.half_width,
    );
    // The windows at either end of the allowed range, then every window starting at a
    // residual whose centre is allowed (two pointers over the sorted residuals).
    let mut best = window_at(r, lo_c - t, 2.0 * t);
    let high = window_at(r, hi_c - t, 2.0 * t);
    if high.0 > best.0 {
        best = high;
    }
    // The best run's ends; its mean is summed once, at the end (the count rises run by run
    // toward the densest, and summing each better run was most of the scan's cost).
    let mut run: Option<(usize, usize)> = None;
    let mut j = 0;
    for i in 0..r.len() {
        let centre = r[i] + t;
        if centre < lo_c || centre > hi_c {
            continue;
        }
        j = j.max(i);
        while j < r.len() && r[j] <= r[i] + 2.0 * t {
            j += 1;
        }
        let n = (j - i) as u32;
        if n > best.0 {
            best.0 = n;
            run = Some((i, j));
        }
    }
    if let Some((i, j)) = run {
        best.1 = r[i..j].iter().sum::<f32>() / best.0 as f32;
    }
    best
}

/// Bins [`densest_bound`] counts residuals in.
const BOUND_BINS: usize = 64;

/// At least the count of any window of width 2t among residuals `r`, all within `near`
/// (unsorted): the most in three neighbouring bins at least t wide. A window of width 2t spans
/// no more than three such bins (1 % wider than t, so rounding cannot make it four), so a
/// hypothesis whose bound is below the best count cannot win and is neither sorted nor scanned.
fn densest_bound(r: &[f32], near: (f32, f32), t: f32) -> u32 {
    let width = 1.01 * t.max((near.1 - near.0) / BOUND_BINS as f32);
    let mut bins = [0u16; BOUND_BINS];
    for x in r {
        let i = ((x - near.0) / width) as usize;
        bins[i.min(BOUND_BINS - 1)] += 1;
    }
    bins.windows(3)
        .map(|w| u32::from(w[0]) + u32::from(w[1]) + u32::from(w[2]))
        .max()
        .unwrap_or(r.len() as u32)
}

/// RANSAC over bearing pairs: the point most bearings agree on, with its common offset.
pub fn ransac<T: Sighting, R: Rng + ?Sized>(
    items: &[T],
    options: &RansacOptions,
    window: OffsetWindow,
    rng: &mut R,
) -> Result<Consensus, Error> {
    options.check()?;
    check_finite(&[window.centre, window.half_width])?;
    let usable = |t: &T| t.bearing().check().is_ok();
    let candidates = items.iter().filter(|t| usable(t)).count() as u32;
    if candidates < 2 {
        return Err(Error::TooFewMeasurements);
    }
    let t = (options.threshold * median_sigma(items)).max(options.floor);
    // Centroid of the drive, to drop hypotheses beyond any plausible range.
    let mut centroid = [0.0f32; 2];
    for it in items.iter().filter(|t| usable(t)) {
        centroid[0] += it.bearing().vehicle[0] / candidates as f32;
        centroid[1] += it.bearing().vehicle[1] / candidates as f32;
    }
    let stride = items.len().div_ceil(SCORE_SAMPLE).max(1);
    // The scored sample's usable bearings (angle, observer), taken once for every hypothesis.
    let mut sample = [(0.0f32, [0.0f32; 2]); SCORE_SAMPLE];
    let mut m = 0;
    for it in items.iter().step_by(stride).filter(|t| usable(t)) {
        if let Some(slot) = sample.get_mut(m) {
            *slot = (it.bearing().theta, it.bearing().vehicle);
            m += 1;
        }
    }
    let sample = &sample[..m];
    let n = items.len();
    let mut best: Option<(u32, f32, [f32; 2], f32)> = None;
    let mut scored = 0u32;
    let mut residuals = [0.0f32; SCORE_SAMPLE];
    // Only residuals near the allowed offsets can count or enter the spread (those within a
    // window of width 2t centred in the allowed range, or within t of its mean): the rest are
    // left out before the sort, which is most of the scoring's cost (the sorted list, and so
    // every sum over it, is what it was, a margin of t spare).
    let near = (
        window.centre - window.half_width - 3.0 * t,
        window.centre + window.half_width + 3.0 * t,
    );
    for _ in 0..options.max_attempts {
        if scored >= options.hypotheses {
            break;
        }
        let i = ((random::uniform(rng) * n as f32) as usize).min(n - 1);
        let j = ((random::uniform(rng) * n as f32) as usize).min(n - 1);
        let (Some(a), Some(b)) = (items.get(i), items.get(j)) else {
            continue;
        };
        if i == j || !usable(a) || !usable(b) {
            continue;
        }
        // The pair's crossing with the window's offset removed from both bearings.
        let (mut ba, mut bb) = (*a.bearing(), *b.bearing());
        ba.theta -= window.centre;
        bb.theta -= window.centre;
        let Ok(p) = intersect(&ba, &bb, options.min_crossing) else {
            continue;
        };
        if libm::hypotf(p[0] - centroid[0], p[1] - centroid[1]) > options.max_range {
            continue;
        }
        scored += 1;
        let mut k = 0;
        for (theta, observer) in sample {
            if let Some(slot) = residuals.get_mut(k) {
                *slot = wrap(theta - predicted(&p, observer));
                if *slot >= near.0 && *slot <= near.1 {
                    k += 1;
                }
            }
        }
        // No more than the k near residuals can agree, nor more than the densest three bins
        // hold: a hypothesis with fewer than the best's count cannot win, and needs no sort.
        if best.is_some_and(|(c, ..)| (k as u32) < c || densest_bound(&residuals[..k], near, t) < c)
        {
            continue;
        }
        super::super::order::radix_sort(&mut residuals[..k]);
        let (count, offset) = best_offset(&residuals[..k], t, window);
        // Ties go to the tighter window (smaller spread about its offset).
        let spread = residuals[..k]
            .iter()
            .map(|r| libm::fabsf(r - offset))
            .filter(|d| *d <= t)
            .sum::<f32>();
        let better = match best {
            None => true,
            Some((c, s, _, _)) => count > c || (count == c && spread < s),
        };
        if better {
            best = Some((count, spread, p, offset));
        }
    }
    let Some((_, _, position, offset)) = best else {
        return Err(Error::ShallowCrossing);
    };
    let inliers = items
        .iter()
        .filter(|t| usable(t))
        .filter(|it| {
            let b = it.bearing();
            libm::fabsf(wrap(b.theta - predicted(&position, &b.vehicle) - offset)) <= t
        })
        .count() as u32;
    Ok(Consensus {
        position,
        bias: offset,
        inliers,
        candidates,
        hypotheses: scored,
        threshold: t,
    })
}

/// How likely `inliers` of `candidates` uniformly random bearings would agree within
/// `threshold` (radians) of the best of a search over `hypotheses` points and offsets within
/// +- `half_width`: a Bonferroni bound, min(1, H P(Binomial(n - 2, t / pi) >= k - 2)) (the two
/// bearings that made the hypothesis agree by construction), with H the hypotheses (no more
/// than the n (n - 1) / 2 pairs) times the distinct offsets (1 + half_width / threshold).
pub fn chance(
    inliers: u32,
    candidates: u32,
    threshold: f32,
    hypotheses: u32,
    half_width: f32,
) -> Result<f32, Error> {
    check_finite(&[threshold, half_width])?;
    if !(threshold > 0.0) || half_width < 0.0 {
        return Err(Error::OutOfRange);
    }
    if inliers < 2 || candidates < 2 {
        return Ok(1.0);
    }
    let q = (threshold / PI).min(1.0);
    let pairs = (candidates as f32) * (candidates as f32 - 1.0) / 2.0;
    let h = (hypotheses as f32).min(pairs).max(1.0) * (1.0 + half_width / threshold);
    let tail = stats::binomial_tail(inliers - 2, candidates - 2, q)?;
    Ok((h * tail).min(1.0))
}

#[cfg(test)]
mod window_tests {
    use super::{OffsetWindow, best_offset, densest_bound, window_at};
    use crate::random;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    /// The bisection finds the run a scan of every residual finds, and sums it in the same
    /// order (the same bits).
    #[test]
    fn a_window_by_bisection_is_the_window_by_scan() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        for n in 0..60 {
            let mut r: [f32; 60] = core::array::from_fn(|_| random::uniform(&mut rng) - 0.5);
            let r = &mut r[..n];
            r.sort_unstable_by(f32::total_cmp);
            for _ in 0..20 {
                let (lo, width) = (
                    random::uniform(&mut rng) - 0.7,
                    0.4 * random::uniform(&mut rng),
                );
                let inside = r.iter().filter(|x| **x >= lo && **x <= lo + width);
                let count = inside.clone().count() as u32;
                let mean = match count {
                    0 => lo + 0.5 * width,
                    c => inside.fold(0.0f32, |s, x| s + x) / c as f32,
                };
                assert_eq!(window_at(r, lo, width), (count, mean), "n {n} lo {lo}");
            }
        }
    }

    /// The bound is never below the densest window's count, whatever the residuals and the
    /// window (ties at bin edges among them).
    #[test]
    fn the_densest_bound_holds_the_densest_window() {
        let mut rng = XorShiftRng::seed_from_u64(7);
        for n in 0..200 {
            let t = 0.001 + 0.05 * random::uniform(&mut rng);
            let window = OffsetWindow {
                centre: 0.1 * (random::uniform(&mut rng) - 0.5),
                half_width: 0.6 * random::uniform(&mut rng) * random::uniform(&mut rng),
            };
            let near = (
                window.centre - window.half_width - 3.0 * t,
                window.centre + window.half_width + 3.0 * t,
            );
            let mut r = [0.0f32; 256];
            let len = (n * 7) % 257;
            for (i, x) in r[..len].iter_mut().enumerate() {
                let u = random::uniform(&mut rng);
                // Every fourth residual on a multiple of t from the near edge: bin edges.
                *x = if i % 4 == 0 {
                    near.0 + t * (u * 10.0) as i32 as f32
                } else {
                    near.0 + u * (near.1 - near.0)
                }
                .min(near.1);
            }
            let r = &mut r[..len];
            let bound = densest_bound(r, near, t);
            r.sort_unstable_by(f32::total_cmp);
            let (count, _) = best_offset(r, t, window);
            assert!(bound >= count, "n {n}: bound {bound} < {count}");
        }
    }

    /// The densest window as summed at each better run (the scan before its mean was summed
    /// once): the same count and the same bits of the offset.
    #[test]
    fn the_best_offset_summed_once_is_the_one_summed_at_each_better_run() {
        let mut rng = XorShiftRng::seed_from_u64(5);
        for n in 0..80 {
            let mut r: [f32; 80] =
                core::array::from_fn(|_| 0.3 * (random::uniform(&mut rng) - 0.5));
            let r = &mut r[..n];
            r.sort_unstable_by(f32::total_cmp);
            let t = 0.02 + 0.05 * random::uniform(&mut rng);
            let window = OffsetWindow {
                centre: 0.1 * (random::uniform(&mut rng) - 0.5),
                half_width: 0.1 * random::uniform(&mut rng),
            };
            let (lo_c, hi_c) = (
                window.centre - window.half_width,
                window.centre + window.half_width,
            );
            let mut expected = window_at(r, lo_c - t, 2.0 * t);
            let high = window_at(r, hi_c - t, 2.0 * t);
            if high.0 > expected.0 {
                expected = high;
            }
            for i in 0..r.len() {
                let centre = r[i] + t;
                if centre < lo_c || centre > hi_c {
                    continue;
                }
                let j = i + r[i..].iter().take_while(|x| **x <= r[i] + 2.0 * t).count();
                let count = (j - i) as u32;
                if count > expected.0 {
                    expected = (count, r[i..j].iter().sum::<f32>() / count as f32);
                }
            }
            assert_eq!(best_offset(r, t, window), expected, "n {n}");
        }
    }
}
