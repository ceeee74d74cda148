//! The profile likelihood: the best fit with the position held on a line.

use super::problem::{on_line, set_up};
use super::solve::descend;
use super::{BiasPrior, BiasedOptions, MAX_SOURCES, Sighting, Start};
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::linalg::inverse_scaled;

/// One point of the profile likelihood: the best fit with the position held on a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// The best position on the line, metres.
    pub position: [f32; 2],
    /// The offsets there, radians.
    pub bias: [f32; MAX_SOURCES],
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
pub fn profile<T: Sighting, L: Likelihood>(
    items: &[T],
    priors: &[BiasPrior; MAX_SOURCES],
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
    let (problem, mut x, geo) = set_up(items, priors, start, loss, options)?;
    descend(&problem, &mut x, options, Some(along));
    let (h, g) = problem.normal(&x);
    let (h, _) = on_line(&h, &g, along);
    let c = inverse_scaled(&h).ok_or(Error::DegenerateGeometry)?;
    let point = ProfilePoint {
        position: [x[0] + geo.origin[0], x[1] + geo.origin[1]],
        bias: core::array::from_fn(|s| x[2 + s]),
        deviance: 2.0 * problem.cost(&x),
        along_sd: libm::sqrtf(c[0][0].max(0.0)),
    };
    check_finite(&point.position)?;
    check_finite(&point.bias)?;
    check_finite(&[point.deviance, point.along_sd])?;
    Ok(point)
}
