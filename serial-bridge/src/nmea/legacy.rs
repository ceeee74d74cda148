//! The free encoders of the first releases, kept for their callers: each is now the `emit` of
//! its sentence type.

use super::{Date, Gga, LatLon, Line, Pfoxb, Rmc, UtcTime};
use core::fmt;

/// The body of a GGA sentence (talker GP) for a fix: [`Gga::emit`] with quality 1.
pub fn gga_body(
    out: &mut Line,
    time: UtcTime,
    p: LatLon,
    satellites: u8,
    hdop: f32,
) -> fmt::Result {
    Gga {
        talker: *b"GP",
        time,
        position: p,
        quality: Some(1),
        satellites: Some(satellites),
        hdop: Some(hdop),
        altitude_m: Some(0.0),
    }
    .emit(out)
}

/// The body of an RMC sentence (talker GP): [`Rmc::emit`].
pub fn rmc_body(
    out: &mut Line,
    time: UtcTime,
    date: Date,
    p: LatLon,
    speed_kn: f64,
    course_deg: f64,
) -> fmt::Result {
    Rmc {
        talker: *b"GP",
        time,
        date: Some(date),
        position: p,
        speed_kn: Some(speed_kn),
        course_deg: Some(course_deg),
    }
    .emit(out)
}

/// The body of a PFOXB sentence: [`Pfoxb::emit`].
pub fn pfoxb_body(out: &mut Line, b: &Pfoxb) -> fmt::Result {
    b.emit(out)
}
