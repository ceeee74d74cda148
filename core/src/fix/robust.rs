//! A fix that survives multipath: a global start that needs no prior, then a redescending
//! refinement on the bearings that agree with it.
//!
//! Scattered wild bearings are handled by any bounded-influence loss started from the PLE; a
//! consistent ghost (a stretch of the drive that sees a reflection) is not: the PLE lands
//! between the emitter and the ghost, and a loss that must pull it back has to tell, from that
//! start, which bearings are the wild ones (FIELD.md: Huber or Cauchy from the PLE, 100-114 m
//! median; RANSAC then ML on the inliers, 34-35 m). So:
//!
//! 1. [`ransac`]: intersections of random bearing pairs are hypotheses; each is scored by how
//!    many bearings of an evenly strided sample pass within the threshold of it, with the best
//!    common offset for that hypothesis (the densest window of its residuals, within the
//!    offset prior's range), so a mounting offset does not hide the emitter. Bounded work:
//!    `hypotheses` scored, `max_attempts` pairs drawn, a sample of at most [`SCORE_SAMPLE`].
//!    Deterministic given the generator.
//! 2. [`refine`]: Tukey's biweight from the best hypothesis, then trimmed ML: keep the bearings
//!    Tukey gave weight to, fit position and offsets by Gaussian ML on them alone, re-estimate
//!    the scale from their residuals (truncation-corrected), cut at [`trim_cut`] scale sigmas
//!    (3, or the Student-t quantile at 1 - 0.01 / n when that is wider: few bearings are not
//!    trimmed on a noisy scale estimate), repeat until the set settles (at most
//!    [`MAX_TRIM_ROUNDS`]). On clean data nothing is trimmed and the answer is the ML fix.
//!
//! [`chance`] says how likely so many bearings would line up on some point by luck (uniform
//! bearings, a search over the hypotheses and offsets tried): pure noise is not an emitter.

use super::bias::{self, BiasPrior, BiasedFix, BiasedOptions, MAX_SOURCES, Sighting, Start};
use super::intersection::intersect;
use super::noise::median_sigma;
use crate::error::{Error, check_finite};
use crate::likelihood::{Gaussian, Tukey};
use crate::model::bearing::{predicted, wrap};
use crate::random;
use crate::stats;
use core::f32::consts::PI;
use rand_core::Rng;

/// Bearings a hypothesis is scored on at most (an evenly strided sample).
pub const SCORE_SAMPLE: usize = 256;
/// Rounds of trimming at most.
pub const MAX_TRIM_ROUNDS: u32 = 12;
/// Trimmed ML keeps bearings within this many (scaled) sigmas at least...
pub const TRIM_CUT: f32 = 3.0;
/// ...or within the two-sided Student-t quantile at 1 - TRIM_ALPHA / n (n bearings, the
/// residual degrees of freedom): on few bearings a 3-sigma cut would drop good ones (a 2-sigma
/// residual of 9 bearings is not an outlier), on many it stays near 3.5 sigmas.
pub const TRIM_ALPHA: f32 = 0.01;

/// The cut in scaled sigmas for `n` bearings with `dof` residual degrees of freedom.
pub fn trim_cut(n: u32, dof: f32) -> f32 {
    if !(dof > 0.0) || n == 0 {
        return f32::INFINITY;
    }
    let p = 1.0 - TRIM_ALPHA / n as f32;
    stats::t_quantile(p, dof)
        .map(|t| t.max(TRIM_CUT))
        .unwrap_or(TRIM_CUT)
}

/// Share of a Gaussian's variance inside +-c: 1 - 2 c phi(c) / (2 Phi(c) - 1). Corrects the
/// scale estimated from bearings trimmed at c.
fn kept_variance(c: f32) -> f32 {
    if !c.is_finite() {
        return 1.0;
    }
    let inside = libm::erff(c / core::f32::consts::SQRT_2);
    let density = libm::expf(-0.5 * c * c) / libm::sqrtf(2.0 * PI);
    if inside > 0.0 {
        (1.0 - 2.0 * c * density / inside).clamp(0.05, 1.0)
    } else {
        1.0
    }
}

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
    /// Hypotheses farther than this from the drive's centroid are dropped, metres.
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
            max_range: 100_000.0,
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
    /// Three prior sds either side of the widest free prior among `priors` (capped at 30
    /// degrees), centred on its mean; a zero window when every unit is calibrated.
    pub fn from_priors(priors: &[BiasPrior; MAX_SOURCES]) -> Self {
        let widest = priors
            .iter()
            .copied()
            .fold(None::<BiasPrior>, |w, p| match w {
                Some(w) if w.sd >= p.sd => Some(w),
                _ => Some(p),
            })
            .unwrap_or_default();
        Self {
            centre: widest.mean,
            half_width: (3.0 * widest.sd).min(30.0 * PI / 180.0),
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

/// Count of sorted `r` inside [lo, lo + width], and the mean of those.
fn window_at(r: &[f32], lo: f32, width: f32) -> (u32, f32) {
    let mut n = 0u32;
    let mut sum = 0.0f32;
    for &x in r {
        if x >= lo && x <= lo + width {
            n += 1;
            sum += x;
        }
    }
    (
        n,
        if n > 0 {
            sum / n as f32
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
            let mean = r[i..j].iter().sum::<f32>() / n as f32;
            best = (n, mean);
        }
    }
    best
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
    let usable = |t: &T| t.source() < MAX_SOURCES && t.bearing().check().is_ok();
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
    let n = items.len();
    let mut best: Option<(u32, f32, [f32; 2], f32)> = None;
    let mut scored = 0u32;
    let mut residuals = [0.0f32; SCORE_SAMPLE];
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
        for it in items.iter().step_by(stride).filter(|t| usable(t)) {
            if let Some(slot) = residuals.get_mut(k) {
                let bg = it.bearing();
                *slot = wrap(bg.theta - predicted(&p, &bg.vehicle));
                k += 1;
            }
        }
        super::order::heapsort(&mut residuals[..k]);
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

/// A refined robust fix and the bearings it rests on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustFix {
    /// Gaussian ML on the kept bearings, covariance at `scale`.
    pub fix: BiasedFix,
    /// The noise scale: every bearing's sigma times this is the residuals' sd (1 when the
    /// scale was not estimated).
    pub scale: f32,
    /// Bearings kept (the first `kept` of the scratch buffer, in input order).
    pub kept: u32,
    /// Trimming rounds run.
    pub rounds: u32,
}

/// Settings of the refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Estimate the noise scale from the residuals (otherwise the bearings' sigmas hold).
    pub estimate_scale: bool,
    /// Solver settings of each ML fit.
    pub solver: BiasedOptions,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            estimate_scale: true,
            solver: BiasedOptions::default(),
        }
    }
}

/// The residual of a sighting at a fix, its source's offset removed.
fn residual_at<T: Sighting>(t: &T, fix: &BiasedFix) -> Option<f32> {
    let b = t.bearing();
    let bias = *fix.bias.get(t.source())?;
    b.check().ok()?;
    Some(wrap(b.theta - predicted(&fix.position, &b.vehicle) - bias))
}

/// Refine a consensus on `items`: Tukey from the hypothesis, then trimmed Gaussian ML. The kept
/// bearings are copied, in order, to the front of `scratch` (at least `items.len()` long).
pub fn refine<T: Sighting + Copy>(
    items: &[T],
    scratch: &mut [T],
    priors: &[BiasPrior; MAX_SOURCES],
    consensus: &Consensus,
    options: RefineOptions,
) -> Result<RobustFix, Error> {
    if scratch.len() < items.len() {
        return Err(Error::OutOfRange);
    }
    let median = median_sigma(items);
    if !(median > 0.0) {
        return Err(Error::TooFewMeasurements);
    }
    // The hypothesis' threshold in sigmas sets the first scale: a floor-dominated threshold
    // (precise bearings) starts Tukey wider than the sigmas say.
    let mut scale = if options.estimate_scale {
        (consensus.threshold / (TRIM_CUT * median)).max(1.0)
    } else {
        1.0
    };
    let start = Start {
        position: consensus.position,
        bias: core::array::from_fn(|s| {
            if priors[s].is_free() {
                consensus.bias
            } else {
                priors[s].mean
            }
        }),
    };
    let tukey = bias::ml_sources(
        items,
        priors,
        start,
        &Tukey::default(),
        BiasedOptions {
            scale,
            ..options.solver
        },
    )?;
    let mut fix = tukey;
    let mut kept_before = u32::MAX;
    let mut rounds = 0;
    // The first round keeps what Tukey gave weight to (|u| < c); later ones cut at the
    // Student-t quantile of the last round's degrees of freedom.
    let mut cut = Tukey::default().c;
    while rounds < MAX_TRIM_ROUNDS {
        rounds += 1;
        let mut kept = 0usize;
        for t in items {
            if let Some(r) = residual_at(t, &fix)
                && libm::fabsf(r) <= cut * scale * t.bearing().sigma
                && let Some(slot) = scratch.get_mut(kept)
            {
                *slot = *t;
                kept += 1;
            }
        }
        if kept < 3 {
            return Err(Error::TooFewMeasurements);
        }
        let set = scratch.get(..kept).ok_or(Error::OutOfRange)?;
        let next = bias::ml_sources(
            set,
            priors,
            Start {
                position: fix.position,
                bias: fix.bias,
            },
            &Gaussian,
            BiasedOptions {
                scale,
                ..options.solver
            },
        )?;
        let mut settled = kept as u32 == kept_before;
        let dof = kept as f32 - next.parameters;
        if options.estimate_scale && dof > 0.0 {
            // chi2 is at the current scale: sum (r / sigma)^2 = chi2 scale^2, from bearings
            // cut at `cut` scale sigmas.
            let s2 = next.chi2 * scale * scale / dof / kept_variance(cut);
            let s = libm::sqrtf(s2);
            if s.is_finite() && s > 0.0 {
                settled &= libm::fabsf(s / scale - 1.0) < 0.01;
                scale = s;
            }
        }
        cut = trim_cut(kept as u32, dof);
        fix = next;
        kept_before = kept as u32;
        if settled {
            break;
        }
    }
    // The covariance and chi-square at the final scale.
    let set = scratch
        .get(..kept_before as usize)
        .ok_or(Error::OutOfRange)?;
    let fix = bias::ml_sources(
        set,
        priors,
        Start {
            position: fix.position,
            bias: fix.bias,
        },
        &Gaussian,
        BiasedOptions {
            scale,
            ..options.solver
        },
    )?;
    check_finite(&[scale])?;
    Ok(RobustFix {
        fix,
        scale,
        kept: kept_before,
        rounds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::Bearing;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    const DEG: f32 = PI / 180.0;

    /// 240 bearings on a U around (0, 1500): east along y = 0, north, back west along
    /// y = 3000; a quarter of them (60..120) see a ghost at `ghost`, a share `wild` are
    /// uniform.
    fn u_drive(
        ghost: Option<[f32; 2]>,
        wild: f32,
        bias: f32,
        rng: &mut XorShiftRng,
    ) -> [Bearing; 240] {
        let e = [0.0, 1500.0];
        core::array::from_fn(|k| {
            let s = 8000.0 * k as f32 / 240.0;
            let v = if s < 3000.0 {
                [-1500.0 + s, 0.0]
            } else if s < 5000.0 {
                [1500.0, 0.0 + (s - 3000.0) * 1.5]
            } else {
                [1500.0 - (s - 5000.0), 3000.0]
            };
            let target = match ghost {
                Some(g) if (60..120).contains(&k) => g,
                _ => e,
            };
            let theta = if random::uniform(rng) < wild {
                random::uniform_in(rng, -PI, PI)
            } else {
                predicted(&target, &v) + bias + 2.0 * DEG * random::normal(rng)
            };
            Bearing {
                vehicle: v,
                theta: wrap(theta),
                sigma: 2.0 * DEG,
            }
        })
    }

    #[test]
    fn consensus_finds_the_emitter_past_a_ghost_and_an_offset() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let bs = u_drive(Some([900.0, 1800.0]), 0.1, 4.0 * DEG, &mut rng);
        let priors = bias::same_priors(BiasPrior::default());
        let c = ransac(
            &bs,
            &RansacOptions::default(),
            OffsetWindow::from_priors(&priors),
            &mut rng,
        )
        .unwrap();
        let e = [0.0, 1500.0];
        assert!(
            libm::hypotf(c.position[0] - e[0], c.position[1] - e[1]) < 150.0,
            "{c:?}"
        );
        assert!(c.inliers > 120, "{c:?}");
        let mut scratch = bs;
        let f = refine(&bs, &mut scratch, &priors, &c, RefineOptions::default()).unwrap();
        let err = libm::hypotf(f.fix.position[0] - e[0], f.fix.position[1] - e[1]);
        assert!(err < 40.0, "{err} m: {f:?}");
        assert!(
            (f.fix.bias[0] - 4.0 * DEG).abs() < 1.0 * DEG,
            "{}",
            f.fix.bias[0] / DEG
        );
        // The ghost's 60 and most wild bearings are out; the emitter's are in.
        assert!((140..=170).contains(&f.kept), "{}", f.kept);
        assert!((0.85..1.2).contains(&f.scale), "{}", f.scale);
        assert!(chance(f.kept, 240, c.threshold, c.hypotheses, 18.0 * DEG).unwrap() < 1e-20);
    }

    #[test]
    fn pure_noise_is_not_significant() {
        let mut rng = XorShiftRng::seed_from_u64(2);
        let bs = u_drive(None, 1.0, 0.0, &mut rng);
        let priors = bias::same_priors(BiasPrior::default());
        let c = ransac(
            &bs,
            &RansacOptions::default(),
            OffsetWindow::from_priors(&priors),
            &mut rng,
        )
        .unwrap();
        let p = chance(
            c.inliers,
            c.candidates,
            c.threshold,
            c.hypotheses,
            18.0 * DEG,
        )
        .unwrap();
        assert!(p > 0.01, "{p}: {c:?}");
    }

    #[test]
    fn clean_data_keep_every_bearing() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        let bs = u_drive(None, 0.0, 0.0, &mut rng);
        let priors = bias::same_priors(BiasPrior::calibrated(0.0));
        let c = ransac(
            &bs,
            &RansacOptions::default(),
            OffsetWindow::from_priors(&priors),
            &mut rng,
        )
        .unwrap();
        let mut scratch = bs;
        let f = refine(&bs, &mut scratch, &priors, &c, RefineOptions::default()).unwrap();
        // At most the 0.27 % a 3-sigma cut takes from a Gaussian (plus one).
        assert!(f.kept >= 237, "{}", f.kept);
        let plain = super::super::ml::ml(&bs, None, &Gaussian, Default::default()).unwrap();
        let d = libm::hypotf(
            f.fix.position[0] - plain.position[0],
            f.fix.position[1] - plain.position[1],
        );
        assert!(d < 2.0, "{d} m from the plain ML");
    }

    #[test]
    fn bad_settings_and_sets_are_refused() {
        let mut rng = XorShiftRng::seed_from_u64(4);
        let bs = u_drive(None, 0.0, 0.0, &mut rng);
        let w = OffsetWindow {
            centre: 0.0,
            half_width: 0.0,
        };
        let bad = RansacOptions {
            hypotheses: 0,
            ..Default::default()
        };
        assert_eq!(ransac(&bs, &bad, w, &mut rng), Err(Error::OutOfRange));
        assert_eq!(
            ransac(&bs[..1], &RansacOptions::default(), w, &mut rng),
            Err(Error::TooFewMeasurements)
        );
        assert_eq!(chance(5, 10, 0.0, 10, 0.0), Err(Error::OutOfRange));
        assert_eq!(chance(1, 10, 0.1, 10, 0.0), Ok(1.0));
    }
}
