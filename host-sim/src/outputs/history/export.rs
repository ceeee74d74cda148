//! A history exported (`foxhunt history`): the bearings and the fixes as CSV, both as
//! GeoJSON. Each row is written as it is read, so an export of a long network run holds one
//! row in memory at a time.

use super::{FixRow, Reader, Window};
use crate::inputs::mqtt::BearingMessage;
use crate::outputs::maps::{ellipse_ring, polygon_geometry};
use crate::outputs::terminal::Stop;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::ellipse::Ellipse;
use serde_json::{Value, json};
use std::io::Write;

/// The bearings CSV's header (the bearings table's columns, and the time in RFC 3339).
pub const BEARINGS_HEADER: &str =
    "time_ms,time,channel,station,lat,lon,bearing_deg,sigma_deg,freq_mhz,quality,kind";
/// The fixes CSV's header (the fixes table's columns but the report).
pub const FIXES_HEADER: &str = "update_id,time_ms,time,written_ms,channel,outcome,method,\
                                bearings,used,lat,lon,major_m,minor_m,orientation_deg,\
                                confidence,sigma_deg";

/// A CSV field: quoted when it holds a comma, a quote or a line end (RFC 4180).
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// A time as RFC 3339 UTC, its fraction of a second as far as it goes (empty when out of
/// range).
pub fn rfc3339(ms: i64) -> String {
    time::OffsetDateTime::from_unix_timestamp_nanos(i128::from(ms) * 1_000_000)
        .ok()
        .and_then(|t| {
            t.format(&time::format_description::well_known::Rfc3339)
                .ok()
        })
        .unwrap_or_default()
}

/// An optional number as a CSV field.
fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// One bearing as a CSV line.
pub fn bearing_line(m: &BearingMessage) -> String {
    format!(
        "{},{},{},{},{:.7},{:.7},{:.3},{:.3},{},{},{}",
        m.time_ms,
        rfc3339(m.time_ms),
        field(&m.channel()),
        field(&m.station),
        m.lat,
        m.lon,
        m.bearing_deg,
        m.sigma_deg,
        opt(m.freq_mhz),
        m.quality,
        field(&m.kind)
    )
}

/// One fix row as a CSV line.
pub fn fix_line(r: &FixRow) -> String {
    format!(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        r.update_id,
        opt(r.time_ms),
        r.time_ms.map_or(String::new(), rfc3339),
        r.written_ms,
        field(r.channel.as_deref().unwrap_or("")),
        field(&r.outcome),
        field(&r.method),
        r.bearings,
        opt(r.used),
        opt(r.lat.map(|v| format!("{v:.7}"))),
        opt(r.lon.map(|v| format!("{v:.7}"))),
        opt(r.major_m.map(|v| format!("{v:.2}"))),
        opt(r.minor_m.map(|v| format!("{v:.2}"))),
        opt(r.orientation_deg.map(|v| format!("{v:.1}"))),
        opt(r.confidence.map(|v| format!("{v:.3}"))),
        opt(r.sigma_deg.map(|v| format!("{v:.3}"))),
    )
}

/// Write the bearings of `window` as CSV to `out`; how many.
pub fn bearings_csv(h: &Reader, window: Window, out: &mut impl Write) -> Result<u64, Stop> {
    writeln!(out, "{BEARINGS_HEADER}").map_err(|e| e.to_string())?;
    let mut failed = Ok(());
    let n = h.bearings(window, |m| {
        if failed.is_ok() {
            failed = writeln!(out, "{}", bearing_line(&m));
        }
    })?;
    failed.map_err(|e| e.to_string())?;
    Ok(n)
}

/// Write the fixes of `window` as CSV to `out`; how many rows.
pub fn fixes_csv(h: &Reader, window: Window, out: &mut impl Write) -> Result<u64, Stop> {
    writeln!(out, "{FIXES_HEADER}").map_err(|e| e.to_string())?;
    h.fixes(window, |r| {
        writeln!(out, "{}", fix_line(&r)).map_err(|e| Stop::Error(e.to_string()))
    })
}

/// A bearing as a GeoJSON point at its station, its fields the properties.
fn bearing_feature(m: &BearingMessage) -> Value {
    json!({
        "type": "Feature",
        "geometry": {"type": "Point", "coordinates": [m.lon, m.lat]},
        "properties": {
            "feature": "bearing", "channel": m.channel(), "station": m.station,
            "time_ms": m.time_ms, "time": rfc3339(m.time_ms), "bearing_deg": m.bearing_deg,
            "sigma_deg": m.sigma_deg, "freq_mhz": m.freq_mhz, "quality": m.quality,
            "kind": m.kind,
        },
    })
}

/// A fix row's features: its point (an emitter or a region's apex) and, with an ellipse, the
/// ellipse; none for a row without a position.
fn fix_features(r: &FixRow) -> Vec<Value> {
    let (Some(lat), Some(lon)) = (r.lat, r.lon) else {
        return Vec::new();
    };
    let properties = json!({
        "feature": "fix", "update_id": r.update_id, "time_ms": r.time_ms,
        "time": r.time_ms.map(rfc3339), "channel": r.channel, "outcome": r.outcome,
        "method": r.method, "bearings": r.bearings, "used": r.used,
        "major_m": r.major_m, "minor_m": r.minor_m, "orientation_deg": r.orientation_deg,
        "confidence": r.confidence, "sigma_deg": r.sigma_deg,
    });
    let mut v = vec![json!({
        "type": "Feature",
        "geometry": {"type": "Point", "coordinates": [lon, lat]},
        "properties": properties.clone(),
    })];
    let ellipse = match (r.major_m, r.minor_m, r.orientation_deg, r.confidence) {
        (Some(major), Some(minor), Some(o), Some(c)) => Some(Ellipse {
            major: major as f32,
            minor: minor as f32,
            // Clockwise from north in the table; anticlockwise from east in the core.
            orientation: (90.0 - o as f32).to_radians(),
            confidence: c as f32,
        }),
        _ => None,
    };
    let frame = LocalFrame::new(LatLon { lat, lon }, 0.0).ok();
    if let (Some(e), Some(frame)) = (ellipse, frame) {
        let ring: Vec<[f64; 2]> = ellipse_ring([0.0, 0.0], &e)
            .iter()
            .filter_map(|p| frame.to_geodetic([f64::from(p[0]), f64::from(p[1])]).ok())
            .map(|g| [g.lon, g.lat])
            .collect();
        if ring.len() > 3 {
            let mut p = properties;
            p["feature"] = json!("ellipse");
            v.push(
                json!({"type": "Feature", "geometry": polygon_geometry(&ring), "properties": p}),
            );
        }
    }
    v
}

/// Write the bearings and fixes of `window` as one GeoJSON FeatureCollection (RFC 7946) to
/// `out`: each bearing a point at its station, each fix its point and ellipse; how many
/// bearings and fix rows.
pub fn geojson(h: &Reader, window: Window, out: &mut impl Write) -> Result<(u64, u64), Stop> {
    let io = |e: std::io::Error| Stop::Error(e.to_string());
    write!(out, "{{\"type\":\"FeatureCollection\",\"features\":[").map_err(io)?;
    let mut first = true;
    let mut failed = Ok(());
    let mut put = |f: &Value, out: &mut dyn Write| -> std::io::Result<()> {
        if !first {
            out.write_all(b",\n")?;
        }
        first = false;
        out.write_all(f.to_string().as_bytes())
    };
    let bearings = h.bearings(window, |m| {
        if failed.is_ok() {
            failed = put(&bearing_feature(&m), out);
        }
    })?;
    failed.map_err(io)?;
    let fixes = h.fixes(window, |r| {
        for f in fix_features(&r) {
            put(&f, out).map_err(io)?;
        }
        Ok(())
    })?;
    writeln!(out, "]}}").map_err(io)?;
    Ok((bearings, fixes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_with_commas_and_quotes_are_quoted() {
        assert_eq!(field("a,b"), "\"a,b\"");
        assert_eq!(field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(field("plain"), "plain");
    }

    #[test]
    fn times_are_rfc3339_utc() {
        assert_eq!(rfc3339(1_780_272_000_123), "2026-06-01T00:00:00.123Z");
        assert_eq!(
            super::super::parse_time("2026-06-01T00:00:00.123Z"),
            Ok(1_780_272_000_123)
        );
        assert_eq!(
            super::super::parse_time("1780272000123"),
            Ok(1_780_272_000_123)
        );
        assert!(super::super::parse_time("yesterday").is_err());
    }

    proptest::proptest! {
        /// Any station id or reason reads back from its CSV field as it was.
        #[test]
        fn a_field_reads_back(text in "\\PC{0,30}") {
            let f = field(&text);
            let back = match f.strip_prefix('"').and_then(|r| r.strip_suffix('"')) {
                Some(inner) => inner.replace("\"\"", "\""),
                None => {
                    proptest::prop_assert!(!f.contains([',', '"', '\n', '\r']));
                    f.clone()
                }
            };
            proptest::prop_assert_eq!(back, text);
        }
    }
}
