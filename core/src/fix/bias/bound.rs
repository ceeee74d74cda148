//! The bias-aware bound: the Fisher information about [x, y, b] and the position block of its
//! inverse.

use super::super::{geometry_of, usable as plain_usable};
use super::problem::usable;
use super::stations::{StationSlot, offset_variances, reduce};
use super::{BiasPrior, Sighting};
use crate::error::{Error, check_finite};
use crate::linalg::inverse_scaled;
use crate::model::bearing::Bearing;

/// Fisher information about [x, y, b] of one unit's bearings at emitter `p`, the prior's
/// information on b included (infinite for a calibrated unit: then b is dropped and the
/// position block is the plain 2 x 2 information with a 1 in the corner).
pub fn information(p: &[f32; 2], bearings: &[Bearing], prior: BiasPrior) -> Option<[[f32; 3]; 3]> {
    let mut j = [[0.0f32; 3]; 3];
    let mut any = false;
    for b in plain_usable(bearings) {
        let dx = p[0] - b.vehicle[0];
        let dy = p[1] - b.vehicle[1];
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return None;
        }
        let k = 1.0 / (b.sigma * b.sigma);
        let jac = [-dy / d2, dx / d2, 1.0];
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += k * jac[r] * jac[c];
            }
        }
        any = true;
    }
    if !prior.is_free() {
        j[0][2] = 0.0;
        j[1][2] = 0.0;
        j[2][0] = 0.0;
        j[2][1] = 0.0;
        j[2][2] = 1.0;
    } else {
        j[2][2] += prior.information();
    }
    (any && j.iter().flatten().all(|v| v.is_finite())).then_some(j)
}

/// The bias-aware bound for an emitter at `p`: the marginal position block of the inverse
/// 3 x 3 information (with the prior), and the bound on the offset's sd.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedCrlb {
    /// Position covariance bound, m^2.
    pub covariance: [[f32; 2]; 2],
    /// sqrt(trace) of it, metres: the smallest position rmse once the offset is unknown.
    pub rmse: f32,
    /// Bound on the offset's sd, radians (0 for a calibrated unit).
    pub bias_sd: f32,
}

/// The bias-aware CRLB (Bayesian where the prior is proper). With a calibrated unit it is the
/// plain CRLB; on a drive that surrounds the emitter it is close to it; on a straight road
/// the prior's sd times the range dominates it.
pub fn crlb(p: &[f32; 2], bearings: &[Bearing], prior: BiasPrior) -> Result<BiasedCrlb, Error> {
    prior.check()?;
    crlb_stations(p, bearings, &mut [StationSlot::new(prior)])
}

/// The bias-aware bound for an emitter at `p` seen by the stations of `stations` (one row per
/// station index, each with its prior in force; sightings of a station beyond the table are
/// left out): every offset eliminated per station (the station table's arrow, see
/// [`super::StationSlot`]), so a fixed station's share is its prior's. `bias_sd` is the bound
/// of the station with most bearings. The rows' fitted offsets are left as they were.
pub fn crlb_stations<T: Sighting>(
    p: &[f32; 2],
    items: &[T],
    stations: &mut [StationSlot],
) -> Result<BiasedCrlb, Error> {
    check_finite(p)?;
    for s in stations.iter() {
        s.in_force.check()?;
    }
    // Centred: the information is translation-invariant, the f32 sums are not.
    let n = stations.len();
    let geo = geometry_of(usable(items, n).map(|(b, _, _)| b))?;
    let o = geo.origin;
    let centred = [p[0] - o[0], p[1] - o[1]];
    for s in stations.iter_mut() {
        s.n = 0;
        s.clear_blocks();
    }
    for (_, s, _) in usable(items, n) {
        if let Some(row) = stations.get_mut(s) {
            row.n += 1;
        }
    }
    for s in stations.iter_mut() {
        s.hfree = s.n > 0 && s.direction().is_free();
        s.n = 0;
    }
    for (b, s, u) in usable(items, n) {
        let Some(row) = stations.get_mut(s) else {
            continue;
        };
        let (dx, dy) = (
            centred[0] - (b.vehicle[0] - o[0]),
            centred[1] - (b.vehicle[1] - o[1]),
        );
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return Err(Error::DegenerateGeometry);
        }
        row.n += 1;
        row.add([-dy / d2, dx / d2], u, 1.0 / (b.sigma * b.sigma), 0.0);
    }
    for s in stations.iter_mut() {
        s.free = s.n > 0 && s.in_force.is_free();
    }
    let r = reduce(stations, 0.0).ok_or(Error::DegenerateGeometry)?;
    let covariance = inverse_scaled(&r.matrix).ok_or(Error::DegenerateGeometry)?;
    let trace = covariance[0][0] + covariance[1][1];
    if !(trace > 0.0) || !trace.is_finite() {
        return Err(Error::DegenerateGeometry);
    }
    let main = (0..n)
        .max_by_key(|&i| (stations[i].n, core::cmp::Reverse(i)))
        .unwrap_or(0);
    let bias_sd = match stations.get_mut(main..=main) {
        Some(one) if one[0].free => {
            let mut row = [one[0]];
            offset_variances(&mut row, &covariance, true).ok_or(Error::DegenerateGeometry)?;
            row[0].sd
        }
        _ => 0.0,
    };
    Ok(BiasedCrlb {
        covariance,
        rmse: libm::sqrtf(trace),
        bias_sd,
    })
}
