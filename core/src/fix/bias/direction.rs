//! A station's direction-dependent error: what its antenna adds to a bearing as a function of
//! the bearing relative to the antenna (a vehicle's heading, a fixed array's front), on top of
//! the constant offset (docs/src/field.md, "Direction-dependent error").
//!
//! e(phi) = a_1 cos phi + b_1 sin phi + a_2 cos 2 phi + b_2 sin 2 phi, phi the measured bearing
//! less the antenna's front (both counter-clockwise, like the model bearing theta), added to
//! theta as the offset is. Pseudo-Doppler units and small arrays show mostly these two
//! harmonics, 2-5 degrees in amplitude. With phi taken from the measured bearing the
//! coefficients enter linearly, so they are nuisance parameters like the offset: a Gaussian
//! prior each (one sd for the four), estimated with the position and eliminated per station
//! ([`super::StationSlot`]).

use crate::error::{Error, check_finite};
use crate::model::bearing::{Bearing, wrap};

/// Coefficients of the model: a_1, b_1, a_2, b_2 (first and second harmonic).
pub const HARMONICS: usize = 4;

/// The regressors of the coefficients at relative bearing `phi` (radians): cos phi, sin phi,
/// cos 2 phi, sin 2 phi.
#[inline]
pub fn harmonics(phi: f32) -> [f32; HARMONICS] {
    let (s, c) = (libm::sinf(phi), libm::cosf(phi));
    [c, s, c * c - s * s, 2.0 * s * c]
}

/// What is known of a station's direction-dependent error before the drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionPrior {
    /// Expected coefficients a_1, b_1, a_2, b_2, radians (a calibration's table; 0 where
    /// nothing is known).
    pub mean: [f32; HARMONICS],
    /// Standard deviation of each coefficient about its mean, radians: 0 when the table is
    /// known exactly (or the station has no such error), finite otherwise (an unbounded
    /// coefficient is never identified by a drive that does not circle the emitter).
    pub sd: f32,
}

impl Default for DirectionPrior {
    /// None: no direction-dependent error modelled.
    fn default() -> Self {
        Self::NONE
    }
}

impl DirectionPrior {
    /// No direction-dependent error.
    pub const NONE: Self = Self {
        mean: [0.0; HARMONICS],
        sd: 0.0,
    };

    /// `Ok` when the means are finite and the sd finite and >= 0.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&self.mean)?;
        check_finite(&[self.sd])?;
        if self.sd >= 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// Whether the coefficients are unknowns (sd > 0).
    pub fn is_free(&self) -> bool {
        self.sd > 0.0 && self.sd.is_finite()
    }

    /// 1 / sd^2 (0 when not free).
    pub(super) fn information(&self) -> f32 {
        if self.is_free() {
            1.0 / (self.sd * self.sd)
        } else {
            0.0
        }
    }

    /// The error the mean coefficients give at relative bearing `phi`, radians.
    pub fn error_at(&self, phi: f32) -> f32 {
        error(&self.mean, phi)
    }
}

/// The error coefficients `c` give at relative bearing `phi`, radians.
#[inline]
pub fn error(c: &[f32; HARMONICS], phi: f32) -> f32 {
    crate::linalg::dot(c, &harmonics(phi))
}

/// Each of one station's `bearings` (time order) relative to its antenna, into `out`, for a
/// calibration (which reads the whole drive at once): the front its course, as the fix takes
/// it (from where it last moved [`FRONT_STEP_M`](super::FRONT_STEP_M) to where it is; before it
/// first moves, its first course), centred: the mean of the course arriving at the bearing and
/// the next one, so a turning vehicle's course is its heading at the bearing and not half a
/// step behind (on a 1 Hz loop that lag would bend the second harmonic by as much as its sd).
/// `front` (theta) for a station that never moves. `out` shorter than `bearings` takes the
/// first ones.
pub fn relative_to_course(bearings: &[Bearing], front: f32, out: &mut [f32]) {
    let mut row = super::StationSlot::new(super::BiasPrior::default())
        .with_direction(DirectionPrior::NONE, front);
    row.start_track();
    // First each bearing's arriving course (NaN before the station moved) ...
    for (b, r) in bearings.iter().zip(out.iter_mut()) {
        *r = row.course_at(b.vehicle).unwrap_or(f32::NAN);
    }
    // ... then centred on the next one's, and turned into the relative bearing.
    let n = bearings.len().min(out.len());
    for k in 0..n {
        let course = out[k];
        let next = out.get(k + 1).copied().filter(|_| k + 1 < n);
        let centred = match next {
            Some(c) if c.is_finite() && course.is_finite() => course + 0.5 * wrap(c - course),
            _ => course,
        };
        let at = if centred.is_finite() {
            centred
        } else {
            row.still_front()
        };
        out[k] = wrap(bearings[k].theta - at);
    }
}
