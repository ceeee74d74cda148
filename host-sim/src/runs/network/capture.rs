//! A network condition's run written as its stations would log it: KrakenSDR XML records, each
//! with its STATION_ID, position, heading and epoch, and the stations file that goes with
//! them (each station's noise and offset prior, the reference transmitters).

use super::{NetworkCondition, simulate};
use crate::runs::field::Truth;
use crate::runs::writer::{CaptureWriter, StationBearing, course_deg};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::model::bearing::theta_to_azimuth;
use std::fmt::Write;

/// 2026-06-01 10:00:00 UTC, ms since 1970: the first record's epoch.
pub const START_MS: u64 = 1_780_308_000_000;

/// The capture's bytes, its stations file (TOML) and the emitters, the local frame's origin at
/// `origin` (the emitter sits there).
pub fn capture(
    c: NetworkCondition,
    run: usize,
    origin: LatLon,
) -> Result<(Vec<u8>, String, Vec<Truth>), String> {
    let n = simulate(c, run);
    let frame = LocalFrame::new(origin, 0.0).map_err(|_| "origin out of range".to_string())?;
    let geo = |p: [f32; 2]| {
        frame
            .to_geodetic([f64::from(p[0]), f64::from(p[1])])
            .map_err(|_| "a station is out of range".to_string())
    };
    let mut w = CaptureWriter::new();
    for o in &n.drive.observations {
        let s = usize::from(o.station);
        let st = &n.drive.stations[s];
        let track = &n.tracks[s];
        // A fixed array's zero faces north; a car's heading is its course.
        let k = (o.time_s as usize).min(track.len().saturating_sub(2));
        let heading_deg = match (st.fixed, track.get(k), track.get(k + 1)) {
            (false, Some(a), Some(b)) => course_deg(*a, *b),
            _ => 0.0,
        };
        w.station_bearing(
            &frame,
            &StationBearing {
                id: &st.id,
                fixed: st.fixed,
                at: o.bearing.vehicle,
                azimuth_deg: theta_to_azimuth(o.bearing.theta).to_degrees(),
                heading_deg,
                freq_mhz: o.freq_mhz,
                epoch_ms: START_MS + (f64::from(o.time_s) * 1000.0).round() as u64,
            },
        )?;
    }
    let mut toml = String::new();
    for st in &n.drive.stations {
        let _ = writeln!(
            toml,
            "[[station]]\nid = {:?}\noffset_deg = {}\noffset_sd_deg = {}\nnoise_deg = {:.3}\nantenna = \"uca\"\nunmodelled_deg = 0\n",
            st.id,
            st.prior.mean.to_degrees(),
            st.prior.sd.to_degrees(),
            st.sigma.to_degrees()
        );
    }
    for (i, r) in n.references.iter().enumerate() {
        let p = geo(r.position)?;
        let _ = writeln!(
            toml,
            "[[reference]]\nname = \"beacon-{}\"\nposition = [{:.7}, {:.7}]\nfreq_mhz = {}\n",
            i + 1,
            p.lat,
            p.lon,
            r.freq_mhz
        );
    }
    Ok((w.into_bytes(), toml, n.drive.emitters.clone()))
}
