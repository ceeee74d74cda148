//! A field condition's run written as a capture.

use super::drives::simulate;
use super::{Condition, Truth};
use crate::runs::writer::CaptureWriter;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;

/// A field condition's run written as the bytes a DF unit and its GPS would send: per bearing a
/// GGA fix at the vehicle and a `$PFOXB` carrying its own position, time and frequency
/// (433.920 MHz where the condition has none), the route's first point at `origin`. The truths
/// come back in the capture's local frame (origin: that first point). The long drives are
/// simulated on the ellipsoid with the convergence already turned out and are not written; on
/// the others (a few km) the meridians' convergence between the vehicle and the origin is
/// under 0.05 degrees and is left in.
pub fn capture(
    condition: Condition,
    run: usize,
    origin: LatLon,
) -> Result<(Vec<u8>, Vec<Truth>), String> {
    use foxhunt_bridge::nmea::{Pfoxb, Reference, UtcTime};
    use foxhunt_core::model::bearing::theta_to_azimuth;
    if matches!(
        condition,
        Condition::Long47 | Condition::Long70 | Condition::Long70Uncorrected
    ) {
        return Err(format!(
            "`{}` is simulated on the ellipsoid and is not written as a capture",
            condition.name()
        ));
    }
    let d = simulate(condition, run);
    if !d.stations.is_empty() || condition == Condition::DirectionDependent {
        // A calibration, a device class and a direction-dependent error's prior are a
        // stations file's, which a capture of `$PFOXB` sentences does not carry.
        return Err(format!(
            "`{}` needs its stations file (calibration, device class, direction-dependent \
             error) and is not written as a capture",
            condition.name()
        ));
    }
    let start = d
        .observations
        .first()
        .map(|o| o.bearing.vehicle)
        .ok_or("the condition made no bearings")?;
    let frame = LocalFrame::new(origin, 0.0).map_err(|_| "origin out of range".to_string())?;
    let geo = |p: [f32; 2]| {
        frame
            .to_geodetic([f64::from(p[0] - start[0]), f64::from(p[1] - start[1])])
            .map_err(|_| "a route point is out of range".to_string())
    };
    // 10:00:00 UTC, the bearings' own times after it.
    let time = |t: f32| UtcTime {
        ms_of_day: 36_000_000 + (f64::from(t) * 1000.0).round() as u32,
    };
    let mut w = CaptureWriter::new();
    for o in &d.observations {
        let position = geo(o.bearing.vehicle)?;
        w.gga(time(o.time_s), position)?;
        w.pfoxb(&Pfoxb {
            time: time(o.time_s),
            azimuth_deg: f64::from(theta_to_azimuth(o.bearing.theta).to_degrees()) % 360.0,
            reference: Reference::True,
            quality: 80.0,
            freq_mhz: f64::from(o.freq_mhz.unwrap_or(433.92)),
            position: Some(position),
        })?;
    }
    let truths = d
        .emitters
        .iter()
        .map(|t| Truth {
            position: [t.position[0] - start[0], t.position[1] - start[1]],
            freq_mhz: t.freq_mhz,
        })
        .collect();
    Ok((w.into_bytes(), truths))
}
