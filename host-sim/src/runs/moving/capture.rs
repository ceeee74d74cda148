//! A moving-emitter scenario's run written as its stations would log it: KrakenSDR XML records,
//! each with its STATION_ID (`mast-N` for a fixed station, `anchor-N` indoors, `car-N` for a
//! vehicle), position, heading and epoch, on 433.920 MHz; the stations file that goes with
//! them (each station's noise and offset prior, and a calibrated direction-dependent error's
//! table); and the truth, the emitter's position every second, as CSV.

use super::{MovingScenario, Route};
use crate::runs::network::START_MS;
use crate::runs::writer::{CaptureWriter, StationBearing, course_deg};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::device::DeviceClass;
use foxhunt_core::model::bearing::theta_to_azimuth;
use std::fmt::Write;

/// The channel the scenario's emitter sends on, MHz.
pub const FREQ_MHZ: f32 = 433.92;

/// A written run.
#[derive(Debug, Clone)]
pub struct MovingCapture {
    /// The records.
    pub bytes: Vec<u8>,
    /// The stations file (TOML).
    pub stations: String,
    /// `t_s,lat,lon,east_m,north_m,moving`: the emitter every update.
    pub truth: String,
}

/// Station `s`'s id.
fn id(scenario: &MovingScenario, s: usize, route: &Route) -> String {
    match route {
        Route::Fixed(_) if scenario.aoa.is_some() => format!("anchor-{}", s + 1),
        Route::Fixed(_) => format!("mast-{}", s + 1),
        Route::Square { .. } => format!("car-{}", s + 1),
    }
}

/// Run `run` of `scenario`, its local frame's origin (the city's south-west corner) at `origin`.
/// Scenarios without bearings (RSSI alone) have no KrakenSDR records: an error.
pub fn capture(
    scenario: &MovingScenario,
    run: usize,
    origin: LatLon,
) -> Result<MovingCapture, String> {
    if !scenario.bearings {
        return Err(format!(
            "{} measures RSSI alone: it is a bench scenario (`foxhunt bench --scenario \
             moving/{}`), with no KrakenSDR records to write",
            scenario.name, scenario.name
        ));
    }
    let frame = LocalFrame::new(origin, 0.0).map_err(|_| "origin out of range".to_string())?;
    let r = scenario.simulate(run);
    let mut w = CaptureWriter::new();
    for u in &r.updates {
        for o in u.epoch.bearings() {
            let s = usize::from(o.station);
            let Some(st) = scenario.stations.get(s) else {
                continue;
            };
            let fixed = matches!(st.route, Route::Fixed(_));
            // A fixed array's zero faces north; a car's heading is its course.
            let heading_deg = if fixed {
                0.0
            } else {
                course_deg(st.route.at(u.t_s), st.route.at(u.t_s + 1.0))
            };
            w.station_bearing(
                &frame,
                &StationBearing {
                    id: &id(scenario, s, &st.route),
                    fixed,
                    at: o.bearing.vehicle,
                    azimuth_deg: theta_to_azimuth(o.bearing.theta).to_degrees(),
                    heading_deg,
                    freq_mhz: Some(FREQ_MHZ),
                    epoch_ms: START_MS + (f64::from(u.t_s) * 1000.0).round() as u64,
                },
            )?;
        }
    }
    let mut stations = String::new();
    for (s, st) in scenario.stations.iter().enumerate() {
        // An indoor array's noise is its reports' own: its class widens them on a track.
        let (antenna, noise) = match scenario.aoa {
            Some(_) => {
                let class = DeviceClass::IndoorAoa;
                (class.name(), st.sigma / class.track().report_sd_factor)
            }
            None => (DeviceClass::Uca.name(), st.sigma),
        };
        let _ = write!(
            stations,
            "[[station]]\nid = {:?}\noffset_deg = {}\noffset_sd_deg = {}\nnoise_deg = {:.3}\nantenna = {antenna:?}\nunmodelled_deg = 0\n",
            id(scenario, s, &st.route),
            scenario.offset_mean.to_degrees(),
            scenario.offset_sd.to_degrees(),
            noise.to_degrees()
        );
        // A calibrated direction-dependent error: its table and sd.
        if let Some(t) = r.tables.get(s).copied().flatten() {
            let [a1, b1, a2, b2] = t.mean.map(f32::to_degrees);
            let _ = writeln!(
                stations,
                "direction_deg = [{a1:.4}, {b1:.4}, {a2:.4}, {b2:.4}]\ndirection_error_deg = {:.4}",
                t.sd.to_degrees()
            );
        }
        stations.push('\n');
    }
    let mut truth = String::from("t_s,lat,lon,east_m,north_m,moving\n");
    for (u, (p, _, moving)) in r.updates.iter().zip(&r.truth) {
        let g = frame
            .to_geodetic([f64::from(p[0]), f64::from(p[1])])
            .map_err(|_| "the emitter left the globe".to_string())?;
        let _ = writeln!(
            truth,
            "{},{:.7},{:.7},{:.1},{:.1},{}",
            u.t_s, g.lat, g.lon, p[0], p[1], moving
        );
    }
    Ok(MovingCapture {
        bytes: w.into_bytes(),
        stations,
        truth,
    })
}
