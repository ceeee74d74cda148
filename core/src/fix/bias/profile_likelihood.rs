//! The profile likelihood: the best fit with the position held on a line.

use super::problem::{At, set_up};
use super::solve::{descend, marginal};
use super::stations::StationSlot;
use super::{BiasedOptions, Sighting, Start};
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;

/// One point of the profile likelihood: the best fit with the position held on a line (the
/// offsets there are the table's current ones: [`super::StartOffsets::Current`] starts the
/// next slice from them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// The best position on the line, metres.
    pub position: [f32; 2],
    /// -2 ln L there (the offsets' prior included), up to a constant shared by every point
    /// of the same sightings, loss and scale: differences are likelihood-ratio statistics.
    pub deviance: f32,
    /// Standard deviation of the position along the line, offsets integrated out, metres.
    pub along_sd: f32,
}

/// The profile likelihood at one slice: the position free only along the unit vector
/// `along` through `start.position` (its component across the line held), the offsets free.
/// Where the Fisher ellipse is a poor picture of the likelihood (a range the bearings barely
/// observe), walking such slices outward shows how far the data really allow the fix to go.
/// The table's fitted offsets and sds are left as they were.
pub fn profile<T: Sighting, L: Likelihood>(
    items: &[T],
    stations: &mut [StationSlot],
    start: Start,
    along: [f32; 2],
    loss: &L,
    options: BiasedOptions,
) -> Result<ProfilePoint, Error> {
    check_finite(&along)?;
    let norm = libm::hypotf(along[0], along[1]);
    if !(norm > 0.0) {
        return Err(Error::OutOfRange);
    }
    let along = [along[0] / norm, along[1] / norm];
    let (problem, mut p, geo) = set_up(items, stations, start, loss, options)?;
    descend(&problem, stations, &mut p, options, Some(along));
    let (c, _) = marginal(&problem, stations, p, Some(along))?;
    let point = ProfilePoint {
        position: [p[0] + geo.origin[0], p[1] + geo.origin[1]],
        deviance: 2.0 * problem.cost(stations, p, At::Current),
        along_sd: libm::sqrtf(c[0][0].max(0.0)),
    };
    check_finite(&point.position)?;
    check_finite(&[point.deviance, point.along_sd])?;
    for s in stations.iter() {
        check_finite(&[s.x])?;
    }
    Ok(point)
}
