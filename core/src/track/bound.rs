//! The posterior Cramér-Rao bound of a moving emitter (Tichavsky, Muravchik and Nehorai 1998,
//! the recursion of [`crate::fix::pcrb`]): the Fisher information of an epoch's bearings and
//! RSSI readings about the [`super::Layout`] state, and each step's transition and noise given
//! the motion the emitter truly had (the bound given the mode sequence: no tracker that must
//! also find out whether the emitter moves can beat it).
//!
//! Components the bound does not estimate (the mode, unused ones, parameters known exactly)
//! carry unit information that nothing changes, so the matrices stay invertible and those
//! components decouple.

use super::epoch::Epoch;
use super::motion::{Motion, identity};
use super::mover::Mover;
use crate::error::Error;
use crate::fix::pcrb::pcrb_step;
use crate::model::rssi::MIN_DISTANCE;

/// Velocity variance of a still emitter in the bound, (m/s)^2: it is known to be zero; a
/// small variance keeps the recursion's matrices invertible (chosen: (1 cm/s)^2).
pub const STILL_VELOCITY_VAR: f32 = 1e-4;

/// Which components the bound estimates: position, velocity and the parameters' means whose
/// prior variance is positive (`prior_var` in [`super::Layout::means`] order).
pub fn estimated<const D: usize, const K: usize>(model: &Mover<K>, prior_var: &[f32]) -> [bool; D] {
    let mut out: [bool; D] = core::array::from_fn(|i| i < 4);
    for (i, v) in model.layout.means().zip(prior_var) {
        if i < D && *v > 0.0 {
            out[i] = true;
        }
    }
    out
}

/// Fisher information of epoch `z`'s measurements about the true state `x`, Gaussian noise at
/// each measurement's own sigma, over the `estimated` components.
pub fn information<const D: usize, const K: usize>(
    model: &Mover<K>,
    x: &[f32; D],
    z: &Epoch<K>,
    estimated: &[bool; D],
) -> [[f32; D]; D] {
    let mut j = [[0.0f32; D]; D];
    let mut add = |h: &[f32; D], r: f32| {
        for a in 0..D {
            for b in 0..D {
                if estimated[a] && estimated[b] {
                    j[a][b] += h[a] * h[b] / r;
                }
            }
        }
    };
    let layout = model.layout;
    for o in z.bearings() {
        let b = &o.bearing;
        let (dx, dy) = (x[0] - b.vehicle[0], x[1] - b.vehicle[1]);
        let d2 = (dx * dx + dy * dy).max(MIN_DISTANCE * MIN_DISTANCE);
        let mut h = [0.0f32; D];
        h[0] = -dy / d2;
        h[1] = dx / d2;
        if let Some((i, _)) = layout
            .offset(usize::from(o.station))
            .filter(|(_, v)| *v < D)
        {
            h[i] = 1.0;
        }
        add(&h, b.sigma * b.sigma);
    }
    for l in z.levels() {
        let (dx, dy) = (x[0] - l.anchor[0], x[1] - l.anchor[1]);
        let d2 = (dx * dx + dy * dy).max(MIN_DISTANCE * MIN_DISTANCE);
        let mut h = [0.0f32; D];
        let mut eta = l.law.eta;
        if let Some(r) = layout.rssi().filter(|r| r + 4 < D) {
            eta += x[r + 1];
            h[r] = 1.0;
            h[r + 1] = -5.0 * core::f32::consts::LOG10_E * libm::logf(d2 / (l.law.d0 * l.law.d0));
        }
        let k = -10.0 * eta * core::f32::consts::LOG10_E / d2;
        h[0] = k * dx;
        h[1] = k * dy;
        add(&h, l.sigma_db * l.sigma_db);
    }
    j
}

/// The transition and noise from an update at which the emitter was `was_moving` to the next,
/// `dt` later, at which it is `moving`: constant velocity while it moves, the velocity zeroed
/// while still, drawn afresh (N(0, start speed^2)) when it starts.
pub fn transition<const D: usize>(
    motion: &Motion,
    dt: f32,
    was_moving: bool,
    moving: bool,
) -> ([[f32; D]; D], [[f32; D]; D]) {
    if was_moving && moving {
        return motion.moving::<D>(dt);
    }
    let f = motion.still::<D>();
    let mut q = [[0.0f32; D]; D];
    let v = if moving {
        motion.start_speed_sd * motion.start_speed_sd
    } else {
        STILL_VELOCITY_VAR
    };
    q[2][2] = v;
    q[3][3] = v;
    (f, q)
}

/// The information matrix of the prior: `position_var` on each axis, `velocity_var` on each
/// velocity, the parameters' prior variances (`prior_var`, [`super::Layout::means`] order),
/// unit information on the components not estimated.
pub fn prior<const D: usize, const K: usize>(
    model: &Mover<K>,
    position_var: f32,
    velocity_var: f32,
    prior_var: &[f32],
    estimated: &[bool; D],
) -> Result<[[f32; D]; D], Error> {
    let mut j = identity::<D>();
    let mut set = |i: usize, v: f32| -> Result<(), Error> {
        if i < D && estimated[i] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::OutOfRange);
            }
            j[i][i] = 1.0 / v;
        }
        Ok(())
    };
    for i in 0..2 {
        set(i, position_var)?;
        set(i + 2, velocity_var)?;
    }
    for (i, v) in model.layout.means().zip(prior_var) {
        set(i, *v)?;
    }
    Ok(j)
}

/// One step of the recursion: from J at the previous update to J at this one, given the
/// transition, its noise and this update's (expected) measurement information. The
/// components not estimated keep unit information.
pub fn step<const D: usize>(
    j: &[[f32; D]; D],
    f: &[[f32; D]; D],
    q: &[[f32; D]; D],
    information: &[[f32; D]; D],
    estimated: &[bool; D],
) -> Result<[[f32; D]; D], Error> {
    let mut f = *f;
    let mut q = *q;
    for i in 0..D {
        if !estimated[i] {
            for k in 0..D {
                f[i][k] = if i == k { 1.0 } else { 0.0 };
                f[k][i] = if i == k { 1.0 } else { 0.0 };
                q[i][k] = 0.0;
                q[k][i] = 0.0;
            }
        }
    }
    pcrb_step(j, &f, &q, information)
}

/// The position part of the bound from J: sqrt of the trace of the position block of J^-1,
/// metres (the rmse no unbiased tracker can beat at that update).
pub fn position_rmse<const D: usize>(j: &[[f32; D]; D]) -> Result<f32, Error> {
    let p = crate::linalg::inverse_scaled(j).ok_or(Error::DegenerateGeometry)?;
    let t = p[0][0] + p[1][1];
    if t.is_finite() && t >= 0.0 {
        Ok(libm::sqrtf(t))
    } else {
        Err(Error::NonFinite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fix::observation::Observation;
    use crate::model::bearing::{Bearing, predicted};
    use crate::track::Layout;

    #[test]
    fn the_bound_of_a_still_emitter_falls_like_one_over_root_n() {
        // Two stations at right angles 1 km away, 1 degree each, offsets known: the still
        // bound after n updates is the static CRLB of 2n bearings, sigma r / sqrt(n) per axis.
        let model = Mover::<2>::new(
            Motion::OUTDOOR,
            Layout {
                sources: 0,
                rssi: false,
            },
        );
        let x = [0.0f32, 0.0, 0.0, 0.0, 0.0];
        let sigma = 1.0f32.to_radians();
        let mut z = Epoch::<2>::new(1.0);
        for v in [[-1000.0f32, 0.0], [0.0, -1000.0]] {
            z.push_bearing(Observation::new(
                Bearing {
                    vehicle: v,
                    theta: predicted(&[0.0, 0.0], &v),
                    sigma,
                },
                0.0,
            ))
            .unwrap();
        }
        let est = estimated::<5, 2>(&model, &[]);
        let mut j = prior::<5, 2>(&model, 1e8, 100.0, &[], &est).unwrap();
        let info = information(&model, &x, &z, &est);
        for _ in 0..100 {
            let (f, q) = transition::<5>(&model.motion, 1.0, false, false);
            j = step(&j, &f, &q, &info, &est).unwrap();
        }
        let b = position_rmse(&j).unwrap();
        let expect = (2.0f32).sqrt() * 1000.0 * sigma / 10.0;
        assert!((b - expect).abs() < 0.02 * expect, "{b} {expect}");
    }
}
