//! Where to drive when the range is open: across the line of bearing. A region (an open
//! range: docs/src/field.md, "Regions") holds a direction and no range; the range comes from
//! the bearing turning as the vehicle moves across it. The move is a straight leg at right
//! angles to the bearing, on the side the vehicle already heads toward (less turning), long
//! enough that at the region's nearest plausible range the bearing turns by about its own
//! half-width twice over; it is no claim about where the emitter is.

use serde::Serialize;

/// The shortest leg suggested, metres.
pub const MIN_LEG_M: f32 = 300.0;
/// The longest, metres.
pub const MAX_LEG_M: f32 = 3000.0;
/// The range the leg is sized for when the region's nearest range is closer than this, metres.
pub const MIN_RANGE_FOR_LEG_M: f32 = 1000.0;

/// What a leg across needs of a region (the locate report's figures).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineOfBearing {
    /// The bearing, degrees clockwise from north.
    pub bearing_deg: f32,
    /// Its half-width, degrees.
    pub half_width_deg: f32,
    /// The nearest range the bearings allow, metres.
    pub min_range_m: f32,
}

/// A leg across a region's line of bearing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Across {
    /// The heading to drive, degrees clockwise from north.
    pub heading_deg: f32,
    /// How far, metres.
    pub distance_m: f32,
    /// Where the leg ends (east, north), local metres.
    #[serde(skip)]
    pub to: [f32; 2],
}

/// The leg across `region` from `vehicle` (local metres), the vehicle heading `heading` (degrees
/// clockwise from north; `None`: either side).
pub fn across(region: &LineOfBearing, vehicle: [f32; 2], heading: Option<f32>) -> Across {
    let sides = [region.bearing_deg + 90.0, region.bearing_deg - 90.0];
    let turn = |a: f32| heading.map_or(0.0, |h| ((a - h + 540.0).rem_euclid(360.0) - 180.0).abs());
    let side = if turn(sides[1]) < turn(sides[0]) {
        sides[1]
    } else {
        sides[0]
    };
    let heading_deg = side.rem_euclid(360.0);
    // A baseline b turns the bearing of a point at range r by about b / r: twice the
    // half-width (both edges of the wedge) at the nearest plausible range.
    let range = region.min_range_m.max(MIN_RANGE_FOR_LEG_M);
    let turn_rad = (2.0 * region.half_width_deg).to_radians().min(1.0);
    let distance_m = (range * turn_rad).clamp(MIN_LEG_M, MAX_LEG_M);
    let h = heading_deg.to_radians();
    Across {
        heading_deg,
        distance_m,
        to: [
            vehicle[0] + distance_m * h.sin(),
            vehicle[1] + distance_m * h.cos(),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(bearing_deg: f32, half_width_deg: f32, min_range_m: f32) -> LineOfBearing {
        LineOfBearing {
            bearing_deg,
            half_width_deg,
            min_range_m,
        }
    }

    #[test]
    fn the_leg_is_square_to_the_bearing_on_the_side_already_headed() {
        let r = region(10.0, 5.0, 4000.0);
        let a = across(&r, [0.0, 0.0], Some(120.0));
        assert!((a.heading_deg - 100.0).abs() < 1e-3, "{a:?}");
        let b = across(&r, [0.0, 0.0], Some(250.0));
        assert!((b.heading_deg - 280.0).abs() < 1e-3, "{b:?}");
        // 4 km x 10 degrees: about 700 m, within the leg's bounds.
        assert!((a.distance_m - 698.0).abs() < 2.0, "{a:?}");
        let east = a.to[0] / a.distance_m;
        assert!((east - 100f32.to_radians().sin()).abs() < 1e-4);
    }

    #[test]
    fn the_leg_stays_within_its_bounds() {
        assert_eq!(
            across(&region(0.0, 0.1, 0.0), [0.0; 2], None).distance_m,
            MIN_LEG_M
        );
        assert_eq!(
            across(&region(0.0, 30.0, 50_000.0), [0.0; 2], None).distance_m,
            MAX_LEG_M
        );
    }
}
