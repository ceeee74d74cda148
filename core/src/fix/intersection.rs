//! Two-bearing intersection (seed 002 eqs. 22-23, in vector form p1 + s d1 = p2 + t d2, which
//! needs no tangent and so survives bearings along the north axis).

use crate::error::Error;
use crate::model::bearing::Bearing;

/// Default minimum crossing angle, radians (10 degrees).
pub const MIN_CROSSING: f32 = 10.0 * core::f32::consts::PI / 180.0;

/// Where two bearing lines cross. Rejects crossings shallower than `min_angle` (radians) and
/// crossings behind either vehicle (the rays point away from each other).
pub fn intersect(a: &Bearing, b: &Bearing, min_angle: f32) -> Result<[f32; 2], Error> {
    a.check()?;
    b.check()?;
    if !min_angle.is_finite() {
        return Err(Error::NonFinite);
    }
    let d1 = a.direction();
    let d2 = b.direction();
    let cross = d1[0] * d2[1] - d1[1] * d2[0];
    if libm::fabsf(cross) < libm::sinf(min_angle.clamp(1e-6, core::f32::consts::FRAC_PI_2)) {
        return Err(Error::ShallowCrossing);
    }
    let dp = [b.vehicle[0] - a.vehicle[0], b.vehicle[1] - a.vehicle[1]];
    let s = (dp[0] * d2[1] - dp[1] * d2[0]) / cross;
    let t = (dp[0] * d1[1] - dp[1] * d1[0]) / cross;
    if s <= 0.0 || t <= 0.0 {
        return Err(Error::BehindVehicle);
    }
    let p = [a.vehicle[0] + s * d1[0], a.vehicle[1] + s * d1[1]];
    if p[0].is_finite() && p[1].is_finite() {
        Ok(p)
    } else {
        Err(Error::NonFinite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::predicted;

    fn bearing(v: [f32; 2], p: [f32; 2]) -> Bearing {
        Bearing {
            vehicle: v,
            theta: predicted(&p, &v),
            sigma: 0.01,
        }
    }

    #[test]
    fn crosses_at_the_emitter() {
        let e = [1200.0, 800.0];
        let p = intersect(
            &bearing([0.0, 0.0], e),
            &bearing([600.0, 0.0], e),
            MIN_CROSSING,
        );
        let p = p.unwrap();
        assert!(
            (p[0] - 1200.0).abs() < 0.05 && (p[1] - 800.0).abs() < 0.05,
            "{p:?}"
        );
    }

    #[test]
    fn rejects_shallow_and_behind() {
        let e = [1200.0, 800.0];
        let a = bearing([0.0, 0.0], e);
        let b = bearing([1.0, 0.0], e);
        assert_eq!(intersect(&a, &b, MIN_CROSSING), Err(Error::ShallowCrossing));
        let c = Bearing {
            theta: a.theta + core::f32::consts::PI,
            ..bearing([600.0, 0.0], e)
        };
        assert_eq!(
            intersect(&bearing([0.0, 0.0], [300.0, 300.0]), &c, MIN_CROSSING),
            Err(Error::BehindVehicle)
        );
    }
}
