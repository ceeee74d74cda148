//! A stated direction-dependent error taken out of the bearings a track is given
//! (docs/src/tracking.md, "A stated direction-dependent error").
//!
//! A stations file's `direction_deg` (a calibration's table of the first and second harmonic
//! of the bearing relative to the antenna) and `direction_error_deg` (its sd) describe what a
//! unit adds to each bearing as a function of where the signal comes from relative to its
//! front: a vehicle's course, a fixed array's boresight. `locate` fits the coefficients with
//! the position under that prior; the tracker's state holds each station's offset but no
//! harmonics, so a track takes the table as known: each bearing is corrected by the table's
//! error at its relative bearing (the front from the station's positions so far, so a live
//! line's bearing is corrected as the recording's is), and the table's uncertainty joins the
//! bearing's noise (2 sd^2: the four coefficients' variance at any direction). A calibration's
//! sd of 0.15-0.3 degrees adds little; a prior with no table (mean zero, a few degrees) widens
//! every bearing by it, which holds an error that changes with the direction only where the
//! track forgets faster than the direction changes.

use crate::estimate::Priors;
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior, StationSlot};
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::model::bearing::wrap;

/// Each station's stated table, its stated front and its course so far, by station index.
#[derive(Debug, Clone, Default)]
pub struct Directions {
    rows: Vec<Option<(StationSlot, Option<f32>)>>,
}

impl Directions {
    /// Correct bearing `o` (its station the capture's index) by its station's stated table in
    /// `priors`, if it states one; stations with none are left as they are. Call in time order.
    ///
    /// Until a station has moved its front is the one stated (`boresight_deg`); where none
    /// is, the front is not known (a vehicle's first bearings, before its course): the
    /// bearing is left as it is and the table's error at an unknown direction joins its
    /// noise (its mean square over the directions, half the coefficients' squares).
    pub fn correct(&mut self, o: &mut Observation, priors: &Priors) {
        let s = usize::from(o.station);
        if self.rows.len() <= s {
            self.rows.resize(s + 1, None);
        }
        let (row, stated) = self.rows[s].get_or_insert_with(|| {
            let (prior, front) = priors
                .direction_of(s)
                .unwrap_or((DirectionPrior::NONE, None));
            let slot =
                StationSlot::new(BiasPrior::default()).with_direction(prior, Priors::front(front));
            (slot, front)
        });
        let table = row.direction();
        if table == DirectionPrior::NONE {
            return;
        }
        let unknown = match row.course_at(o.bearing.vehicle).or(*stated) {
            Some(front) => {
                let phi = wrap(o.bearing.theta - front);
                o.bearing.theta = wrap(o.bearing.theta - table.error_at(phi));
                0.0
            }
            None => 0.5 * table.mean.iter().map(|c| c * c).sum::<f32>(),
        };
        let b = &mut o.bearing;
        b.sigma = (b.sigma * b.sigma + unknown + 2.0 * table.sd * table.sd).sqrt();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::stations::station_setup;
    use foxhunt_core::model::bearing::Bearing;

    #[test]
    fn a_stated_table_is_taken_out_along_the_course_and_widens_the_noise() {
        let mut setup = station_setup(
            ["car", "other"].into_iter(),
            None,
            BiasPrior::default(),
            false,
        );
        let table = DirectionPrior {
            mean: [2.0f32, 0.0, 0.0, 1.0].map(f32::to_radians),
            sd: 0.3f32.to_radians(),
        };
        setup.priors.direction = vec![Some((table, Some(0.0))), None];
        let mut d = Directions::default();
        // The car drives north (course 90 degrees counter-clockwise from east): a bearing
        // due east is 90 degrees right of its front.
        let at = |y: f32, station: u16| Observation {
            bearing: Bearing {
                vehicle: [0.0, y],
                theta: 0.0,
                sigma: 1f32.to_radians(),
            },
            time_s: y,
            freq_mhz: None,
            station,
            stamped: true,
        };
        let mut first = at(0.0, 0);
        d.correct(&mut first, &setup.priors);
        let mut moved = at(10.0, 0);
        d.correct(&mut moved, &setup.priors);
        // phi = -90 degrees: a1 cos phi = 0, b2 sin 2 phi = 0: nothing; before it moved the
        // front is the stated one (east, phi = 0): a1 = 2 degrees taken out.
        assert!(
            (first.bearing.theta.to_degrees() + 2.0).abs() < 1e-4,
            "{first:?}"
        );
        assert!(moved.bearing.theta.to_degrees().abs() < 1e-4, "{moved:?}");
        let widened = (1.0f32 + 2.0 * 0.09).sqrt();
        assert!((moved.bearing.sigma.to_degrees() - widened).abs() < 1e-4);
        // A station with no table is untouched.
        let mut other = at(10.0, 1);
        d.correct(&mut other, &setup.priors);
        assert_eq!(other, at(10.0, 1));
    }

    #[test]
    fn before_a_vehicle_moves_an_unstated_front_widens_the_bearing_instead() {
        let mut setup = station_setup(["car"].into_iter(), None, BiasPrior::default(), false);
        let table = DirectionPrior {
            mean: [3.0f32, 0.0, 0.0, 4.0].map(f32::to_radians),
            sd: 0.0,
        };
        setup.priors.direction = vec![Some((table, None))];
        let mut d = Directions::default();
        let at = |y: f32, theta_deg: f32| {
            Observation::new(
                Bearing {
                    vehicle: [0.0, y],
                    theta: theta_deg.to_radians(),
                    sigma: 1f32.to_radians(),
                },
                y,
            )
        };
        let mut first = at(0.0, 0.0);
        d.correct(&mut first, &setup.priors);
        // Not corrected: north would have taken a1 cos(-90) + b2 sin(-180) = 0 and east 3
        // degrees out; the mean square over the directions, (9 + 16) / 2, joins the noise.
        assert_eq!(first.bearing.theta, 0.0);
        let widened = (1.0f32 + 12.5).sqrt();
        assert!(
            (first.bearing.sigma.to_degrees() - widened).abs() < 1e-3,
            "{first:?}"
        );
        // Once it has moved north a bearing 45 degrees left of it is corrected there:
        // 3 cos 45 + 4 sin 90 degrees.
        let mut moved = at(10.0, 135.0);
        d.correct(&mut moved, &setup.priors);
        let taken = 135.0 - moved.bearing.theta.to_degrees();
        assert!(
            (taken - (3.0 * 0.5f32.sqrt() + 4.0)).abs() < 1e-3,
            "{moved:?}"
        );
        assert!((moved.bearing.sigma.to_degrees() - 1.0).abs() < 1e-5);
    }
}
