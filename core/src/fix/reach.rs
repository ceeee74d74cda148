//! How far the likelihood reaches along a fix's weak axis, and the ellipse widened to hold it.
//!
//! The covariance of an ML fix is the inverse Fisher information at the fix: the likelihood's
//! curvature there. When the range is barely observed (a vehicle driving straight at the
//! emitter, bearings nearly parallel), the likelihood is a long flat ridge along the line of
//! bearing, and a fix that settled on the ridge next to the vehicle has an enormous curvature
//! (each bearing's information grows as 1 / r^2): a 50 m ellipse on a ridge that reaches the
//! emitter kilometres away, "confident and wrong". The likelihood-ratio region {p : -2 ln
//! L(p) / L(fix) <= k} does not depend on where the curvature is taken, so it is walked here:
//! slices across the ellipse's major axis at distances growing geometrically, each slice's best
//! fit (the offsets free: [`super::bias::profile`]), until the deviance leaves the region. The
//! covariance then grows (rank-one terms, never shrinking) until its k-ellipse holds every
//! point of the region found, each slice's own width included. A fit whose region runs out to
//! the search's range limit has no range: [`Reach::bounded`] is false.

use super::bias::{BiasedFix, BiasedOptions, Sighting, Start, StartOffsets, StationSlot, profile};
use crate::error::{Error, check_finite};
use crate::likelihood::Gaussian;
use crate::linalg;

/// Slices walked per direction at most.
pub const MAX_SLICES: u32 = 40;
/// Each slice this much farther out than the last.
pub const GROWTH: f32 = core::f32::consts::SQRT_2;
/// A direction's walk stops once the deviance exceeds this many times the region's threshold
/// (a well-observed fix: at twice the ellipse's reach the quadratic gives 4).
pub const STOP: f32 = 16.0;
/// A direction's walk stops sooner, at its first slice outside the region, when that slice and
/// the one before it each rise to at least this share of the deviance the ellipse's quadratic
/// gives there: the likelihood falls as its curvature at the fix says, and nothing farther is
/// looked for (a ridge that comes back inside flattens first).
pub const BOWL: f32 = 0.8;

/// The vehicle's position error the region allows for, metres (a GPS fix's few metres): with
/// exact positions every vehicle position is a spike of the likelihood (a point a metre away
/// fits its bearing whatever the bearing's error), and a fix that settled on the spike next to
/// the vehicle would measure the region from a height the data do not support. 2.5 m: with 1
/// m 15 % of the guidance benchmark's homing drives still made a confident wrong claim, with
/// 5 m the 100-150 m ranges of aoa-afsa's loop held the truth in 100 % of runs (over-wide).
pub const POSITION_SD_M: f32 = 2.5;

/// The region's extent and the covariance that holds it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// The covariance, widened where the region reaches beyond its ellipse.
    pub covariance: [[f32; 2]; 2],
    /// The widened ellipse's major axis over the given one's (1: the Fisher ellipse held).
    pub stretch: f32,
    /// Whether the region ends within `max_range` of the fix on both sides.
    pub bounded: bool,
    /// The walk's axis (a unit vector, east and north): the covariance's major axis.
    pub axis: [f32; 2],
    /// Along `+axis` then `-axis`: where the region ends, `None` where it ran out to
    /// `max_range` along the axis ([`End::sideways`] where it ran off sideways). Where the range is
    /// open these say how near the region comes.
    pub ends: [Option<End>; 2],
    /// -2 ln L at the fix's slice: the deviance the region's threshold is counted from.
    pub deviance: f32,
    /// Along `+axis` then `-axis`: the farthest slice's best fit inside the region, relative
    /// to the fix (zero when none was): where the line of bearing heads.
    pub farthest: [[f32; 2]; 2],
}

/// Where the walk left the region on one side: the last slice inside and the first outside
/// (best fits relative to the fix, metres); the region's edge lies between them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct End {
    /// The last slice's best fit inside (the fix itself when the first slice was outside).
    pub inside: [f32; 2],
    /// The first slice's best fit outside (where a slice failed or ran off sideways: where it
    /// started).
    pub outside: [f32; 2],
    /// The region ran off sideways past `max_range` at `outside`: open, though not along the
    /// axis.
    pub sideways: bool,
}

/// Bisections [`nearest`] makes once it has a bracket: its length over 256.
pub const EDGE_BISECTIONS: u32 = 8;

/// The nearest range along a ray that the likelihood-ratio region at threshold `k` reaches:
/// the ray from `apex` along the unit vector `u`, searched inward from `from` metres (a range
/// inside the region: the fix's) in steps shrinking by [`GROWTH`] down to `floor` metres (the
/// drive's own extent, within which no ray describes the region), then bisected. Each probe is
/// the best fit on the slice across the ray, warm-started from the last probe inside (with its
/// offsets), its deviance counted from `held`'s fix. 0 when the region reaches `floor` (or a
/// probe fails: the region is then not known to end farther out).
#[allow(clippy::too_many_arguments)]
pub fn nearest<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    fit: Fit<'_>,
    held: &Reach,
    apex: [f32; 2],
    u: [f32; 2],
    from: f32,
    floor: f32,
    k: f32,
) -> f32 {
    let n = [-u[1], u[0]];
    let options = BiasedOptions {
        scale: fit.scale,
        position_sd_m: POSITION_SD_M,
        ..BiasedOptions::default()
    };
    for row in stations.iter_mut() {
        row.keep_current();
    }
    let point = |r: f32| [apex[0] + r * u[0], apex[1] + r * u[1]];
    // The last probe inside: its range and best fit.
    let mut inside = (from, point(from));
    let probe = |stations: &mut [StationSlot], r: f32, inside: &mut (f32, [f32; 2])| {
        let step = r - inside.0;
        let start = Start {
            position: [inside.1[0] + step * u[0], inside.1[1] + step * u[1]],
            offsets: StartOffsets::Saved,
        };
        let p = profile(items, stations, start, n, &Gaussian, options)?;
        let held_in = (p.deviance - held.deviance) / fit.inflation <= k;
        if held_in {
            for row in stations.iter_mut() {
                row.keep_current();
            }
            *inside = (r, p.position);
        }
        Ok::<bool, Error>(held_in)
    };
    let mut out = None;
    let mut r = from / GROWTH;
    while r > floor {
        match probe(stations, r, &mut inside) {
            Ok(true) => r /= GROWTH,
            Ok(false) => {
                out = Some(r);
                break;
            }
            Err(_) => return 0.0,
        }
    }
    let Some(mut lo) = out else {
        return 0.0;
    };
    for _ in 0..EDGE_BISECTIONS {
        let mid = 0.5 * (lo + inside.0);
        match probe(stations, mid, &mut inside) {
            Ok(true) => {}
            Ok(false) => lo = mid,
            Err(_) => break,
        }
    }
    lo.max(floor)
}

/// What [`reach`] needs to know about the fit (its offsets and their priors are in the station
/// table it was solved in).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit<'a> {
    /// The converged Gaussian fix (at `scale`).
    pub fix: &'a BiasedFix,
    /// The noise scale the fix and the region use.
    pub scale: f32,
    /// Deviance differences are divided by this (N / N_eff of correlated residuals, as the
    /// covariance is multiplied by it).
    pub inflation: f32,
}

/// The likelihood-ratio region at threshold `k` (the ellipse's scale) along the major axis of
/// `covariance`, and `covariance` widened to hold it; `max_range` bounds the walk, metres.
/// `stations` is the table the fit was solved in: its fitted offsets start the walk and are
/// left as they were.
pub fn reach<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    fit: Fit<'_>,
    covariance: &[[f32; 2]; 2],
    k: f32,
    max_range: f32,
) -> Result<Reach, Error> {
    check_finite(&[fit.scale, fit.inflation, k, max_range])?;
    if !(k > 0.0 && fit.inflation > 0.0 && max_range > 0.0) {
        return Err(Error::OutOfRange);
    }
    let (l1, _, orientation) = linalg::eigen2(covariance).ok_or(Error::NonFinite)?;
    if !(l1 > 0.0) {
        return Err(Error::DegenerateGeometry);
    }
    let u = [libm::cosf(orientation), libm::sinf(orientation)];
    let n = [-u[1], u[0]];
    let centre = fit.fix.position;
    let options = BiasedOptions {
        scale: fit.scale,
        position_sd_m: POSITION_SD_M,
        ..BiasedOptions::default()
    };
    let slice = |stations: &mut [StationSlot], position: [f32; 2], offsets: StartOffsets| {
        profile(
            items,
            stations,
            Start { position, offsets },
            n,
            &Gaussian,
            options,
        )
    };
    let at_fix = slice(stations, centre, StartOffsets::Fitted)?;
    let mut cov = *covariance;
    let mut bounded = true;
    let mut ends = [None; 2];
    let mut farthest = [[0.0f32; 2]; 2];
    let first = libm::sqrtf(k * l1);
    // The slice at `s` lies at least `BOWL` of the quadratic's deviance up.
    let in_bowl = |s: f32, d: f32| d >= BOWL * s * s / l1;
    // Each direction's walk starts from the slice at the fix, whose offsets are kept aside;
    // each later slice from the one before it (the table's current offsets).
    for row in stations.iter_mut() {
        row.keep_current();
    }
    for (side, sign) in [1.0f32, -1.0].into_iter().enumerate() {
        let mut last = (0.0f32, 0.0f32, at_fix);
        // The end on this side: where the walk left the region, `None` once it ran out.
        let mut end = Some(End {
            inside: [0.0; 2],
            outside: [0.0; 2],
            sideways: false,
        });
        let mut left = false;
        let mut offsets = StartOffsets::Saved;
        let mut s = first;
        let mut inside = true;
        for _ in 0..MAX_SLICES {
            if s > max_range {
                if inside {
                    bounded = false;
                    end = None;
                }
                break;
            }
            // Start where the last slice's best fit was, moved out along the axis.
            let step = sign * (s - last.0);
            let from = [
                last.2.position[0] + step * u[0],
                last.2.position[1] + step * u[1],
            ];
            let Ok(p) = slice(stations, from, offsets) else {
                // No fit here: the edge is known only to lie before this slice's start.
                if let Some(e) = end.as_mut() {
                    e.outside = [from[0] - centre[0], from[1] - centre[1]];
                }
                left = true;
                break;
            };
            offsets = StartOffsets::Current;
            let q = [p.position[0] - centre[0], p.position[1] - centre[1]];
            if !(libm::hypotf(q[0], q[1]) <= max_range) {
                // The slice's best fit ran off sideways past the search's range: the region
                // is open, but along the axis its edge lies before this slice.
                bounded = false;
                if let Some(e) = end.as_mut() {
                    e.outside = [from[0] - centre[0], from[1] - centre[1]];
                    e.sideways = true;
                }
                left = true;
                break;
            }
            let d = (p.deviance - at_fix.deviance) / fit.inflation;
            if d <= k {
                // The slice's own width at this deviance: (k - d) = t^2 / var_t.
                let w = libm::sqrtf((k - d) * fit.inflation) * p.along_sd;
                for side in [-1.0f32, 0.0, 1.0] {
                    hold(
                        &mut cov,
                        [q[0] + side * w * n[0], q[1] + side * w * n[1]],
                        k,
                    );
                }
                inside = true;
                left = false;
                if let Some(e) = end.as_mut() {
                    e.inside = q;
                }
                farthest[side] = q;
            } else {
                if inside {
                    // The edge, between the last slice inside and this one.
                    let f = ((k - last.1) / (d - last.1)).clamp(0.0, 1.0);
                    let edge = [
                        last.2.position[0] + f * (p.position[0] - last.2.position[0]) - centre[0],
                        last.2.position[1] + f * (p.position[1] - last.2.position[1]) - centre[1],
                    ];
                    hold(&mut cov, edge, k);
                    if let Some(e) = end.as_mut() {
                        e.outside = q;
                    }
                    left = true;
                }
                inside = false;
                if d > STOP * k || (last.0 > 0.0 && in_bowl(last.0, last.1) && in_bowl(s, d)) {
                    break;
                }
            }
            last = (s, d, p);
            s *= GROWTH;
        }
        // A walk that stopped inside (a slice failed) has no edge: its last slice then.
        ends[side] = end.map(|e| {
            if left {
                e
            } else {
                End {
                    outside: e.inside,
                    ..e
                }
            }
        });
    }
    let (w1, _, _) = linalg::eigen2(&cov).ok_or(Error::NonFinite)?;
    let stretch = libm::sqrtf(w1 / l1);
    check_finite(&[cov[0][0], cov[0][1], cov[1][0], cov[1][1], stretch])?;
    Ok(Reach {
        covariance: cov,
        stretch,
        bounded,
        axis: u,
        ends,
        deviance: at_fix.deviance,
        farthest,
    })
}

/// Grow `cov` by a rank-one term along `q` so that q^T cov^-1 q <= k (Sherman-Morrison:
/// m / (1 + beta m) = k with m = q^T cov^-1 q), nothing if it already does.
fn hold(cov: &mut [[f32; 2]; 2], q: [f32; 2], k: f32) {
    let det = cov[0][0] * cov[1][1] - cov[0][1] * cov[1][0];
    if !(det > 0.0) {
        return;
    }
    let m = (cov[1][1] * q[0] * q[0] - (cov[0][1] + cov[1][0]) * q[0] * q[1]
        + cov[0][0] * q[1] * q[1])
        / det;
    if !(m > k) || !m.is_finite() {
        return;
    }
    // A hair beyond the boundary, so the point tests inside after rounding.
    let beta = 1.001 * (1.0 / k - 1.0 / m);
    let grown = [
        [
            cov[0][0] + beta * q[0] * q[0],
            cov[0][1] + beta * q[0] * q[1],
        ],
        [
            cov[1][0] + beta * q[1] * q[0],
            cov[1][1] + beta * q[1] * q[1],
        ],
    ];
    if grown.iter().flatten().all(|v| v.is_finite()) {
        *cov = grown;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fix::bias::{BiasPrior, ml_sources};
    use crate::model::bearing::{Bearing, predicted};

    /// Bearings without noise from a U round (0, 1000): the Fisher ellipse is a fine picture,
    /// and the walk leaves it as it was (up to the slices' rounding).
    #[test]
    fn a_well_observed_fix_keeps_its_ellipse() {
        let e = [0.0f32, 1000.0];
        let bs: [Bearing; 90] = core::array::from_fn(|k| {
            let a = core::f32::consts::PI * k as f32 / 89.0;
            let v = [-1000.0 * libm::cosf(a), 1000.0 - 1000.0 * libm::sinf(a)];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v) + if k % 2 == 0 { 0.03 } else { -0.03 },
                sigma: 0.03,
            }
        });
        let mut stations = [StationSlot::new(BiasPrior::calibrated(0.0))];
        let start = Start {
            position: [10.0, 990.0],
            offsets: StartOffsets::Prior,
        };
        let fix = ml_sources(
            &bs,
            &mut stations,
            start,
            &Gaussian,
            BiasedOptions::default(),
        )
        .unwrap();
        let fit = Fit {
            fix: &fix,
            scale: 1.0,
            inflation: 1.0,
        };
        let r = reach(&bs, &mut stations, fit, &fix.covariance, 5.991, 100_000.0).unwrap();
        // The quadratic is exact to a few per cent this close: at most 5 % longer.
        assert!(r.bounded && r.stretch < 1.05, "{r:?}");
    }

    #[test]
    fn hold_grows_only_as_needed() {
        let mut c = [[4.0f32, 0.0], [0.0, 1.0]];
        hold(&mut c, [1.0, 0.0], 1.0);
        assert_eq!(c, [[4.0, 0.0], [0.0, 1.0]]);
        hold(&mut c, [10.0, 0.0], 1.0);
        let m = 100.0 / c[0][0];
        assert!(m <= 1.0 && m > 0.99, "{m}");
    }
}
