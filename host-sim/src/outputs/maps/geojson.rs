//! GeoJSON of a fix (RFC 7946: longitude first, polygons closed, nothing crossing the
//! antimeridian).

use super::{ellipse_ring, lonlat, rays, regions, sources, wedge_length, wedge_ring};
use crate::inputs::capture::Decoded;
use crate::locate::report::Located;
use crate::outputs::json::Short;
use serde_json::{Value, json};

/// A line as GeoJSON pieces that never cross the antimeridian (RFC 7946, 3.1.9): where two
/// consecutive points are more than 180 degrees of longitude apart, the line is cut at +-180
/// at the interpolated latitude.
pub fn split_antimeridian(line: &[[f64; 2]]) -> Vec<Vec<[f64; 2]>> {
    let mut parts: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut current: Vec<[f64; 2]> = Vec::new();
    for &p in line {
        if let Some(&q) = current.last()
            && (p[0] - q[0]).abs() > 180.0
        {
            // Cross eastward (q near +180, p near -180) or westward.
            let east = q[0] > 0.0;
            let edge = if east { 180.0 } else { -180.0 };
            let p_unwrapped = if east { p[0] + 360.0 } else { p[0] - 360.0 };
            let t = (edge - q[0]) / (p_unwrapped - q[0]);
            let lat = q[1] + t * (p[1] - q[1]);
            current.push([edge, lat]);
            parts.push(std::mem::take(&mut current));
            current.push([-edge, lat]);
        }
        current.push(p);
    }
    if current.len() > 1 || parts.is_empty() {
        parts.push(current);
    }
    parts
}

/// A GeoJSON line geometry: a LineString, or a MultiLineString when it crosses the antimeridian.
fn line_geometry(line: &[[f64; 2]]) -> Value {
    let parts = split_antimeridian(line);
    match parts.as_slice() {
        [one] => json!({"type": "LineString", "coordinates": one}),
        _ => json!({"type": "MultiLineString", "coordinates": parts}),
    }
}

/// A ring's longitudes made continuous (no jump across the antimeridian).
fn unwrap_longitudes(ring: &mut [[f64; 2]]) {
    for i in 1..ring.len() {
        let prev = ring[i - 1][0];
        while ring[i][0] - prev > 180.0 {
            ring[i][0] -= 360.0;
        }
        while ring[i][0] - prev < -180.0 {
            ring[i][0] += 360.0;
        }
    }
}

/// Clip a closed ring to one side of the meridian `edge` (Sutherland-Hodgman): `keep_west`
/// keeps longitudes at or below it.
fn clip(ring: &[[f64; 2]], edge: f64, keep_west: bool) -> Vec<[f64; 2]> {
    let inside = |p: &[f64; 2]| {
        if keep_west {
            p[0] <= edge
        } else {
            p[0] >= edge
        }
    };
    let mut out = Vec::new();
    for w in ring.windows(2) {
        let (a, b) = (w[0], w[1]);
        let cross = |a: [f64; 2], b: [f64; 2]| {
            let t = (edge - a[0]) / (b[0] - a[0]);
            [edge, a[1] + t * (b[1] - a[1])]
        };
        match (inside(&a), inside(&b)) {
            (true, true) => out.push(b),
            (true, false) => out.push(cross(a, b)),
            (false, true) => {
                out.push(cross(a, b));
                out.push(b);
            }
            (false, false) => {}
        }
    }
    if let Some(&first) = out.first() {
        out.push(first);
    }
    out
}

/// A GeoJSON polygon geometry: a Polygon, or a MultiPolygon cut at the antimeridian.
pub fn polygon_geometry(ring: &[[f64; 2]]) -> Value {
    let mut r = ring.to_vec();
    unwrap_longitudes(&mut r);
    let (lo, hi) = r.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p[0]), hi.max(p[0]))
    });
    let edge = if hi > 180.0 {
        180.0
    } else if lo < -180.0 {
        -180.0
    } else {
        return json!({"type": "Polygon", "coordinates": [r]});
    };
    let shift = |mut part: Vec<[f64; 2]>| {
        for p in part.iter_mut() {
            if p[0] > 180.0 {
                p[0] -= 360.0;
            } else if p[0] < -180.0 {
                p[0] += 360.0;
            }
        }
        part
    };
    let west = shift(clip(&r, edge, true));
    let east = shift(clip(&r, edge, false));
    json!({"type": "MultiPolygon", "coordinates": [[west], [east]]})
}

/// Every emitter and other source with its ellipse, the DF stations, the track and the bearing
/// rays as GeoJSON (RFC 7946: longitude first, polygons closed, nothing crossing the
/// antimeridian).
pub fn geojson(l: &Located, d: &Decoded) -> Value {
    let Some(frame) = d.frame else {
        return json!({"type": "FeatureCollection", "features": []});
    };
    let mut features = Vec::new();
    for (r, s) in sources(l) {
        let kind = if s.other { "other_source" } else { "emitter" };
        features.push(json!({"type": "Feature",
            "properties": {"kind": kind, "method": l.report.method,
                "freq_mhz": r.freq_mhz.short(), "cep50_m": r.cep50_m.short(),
                "crlb_m": r.crlb_m.short(), "semi_major_m": r.ellipse.major_m.short(),
                "semi_minor_m": r.ellipse.minor_m.short(), "bias_deg": r.bias_deg.short(),
                "used": r.used},
            "geometry": {"type": "Point", "coordinates": [r.lon, r.lat]}}));
        let ring: Vec<[f64; 2]> = ellipse_ring(s.position, &s.ellipse)
            .into_iter()
            .map(|p| lonlat(&frame, p))
            .collect();
        if !ring.is_empty() {
            features.push(json!({"type": "Feature",
                "properties": {"kind": "ellipse", "of": kind,
                    "confidence": s.ellipse.confidence.short()},
                "geometry": polygon_geometry(&ring)}));
        }
    }
    // Each open range: its apex and its wedge.
    for r in regions(l) {
        features.push(json!({"type": "Feature",
            "properties": {"kind": "region", "method": l.report.method,
                "freq_mhz": r.freq_mhz.short(), "bearing_deg": r.bearing_deg.short(),
                "half_width_deg": r.half_width_deg.short(),
                "min_range_m": r.min_range_m.short(), "max_range_m": r.max_range_m.short(),
                "parallel": r.parallel, "used": r.used},
            "geometry": {"type": "Point", "coordinates": [r.lon, r.lat]}}));
        let ring: Vec<[f64; 2]> = wedge_ring(r, wedge_length(r, d))
            .into_iter()
            .map(|p| lonlat(&frame, p))
            .collect();
        if !ring.is_empty() {
            features.push(json!({"type": "Feature",
                "properties": {"kind": "wedge", "of": "region",
                    "confidence": r.confidence.short(), "unbounded": r.max_range_m.is_none()},
                "geometry": polygon_geometry(&ring)}));
        }
    }
    // Each station where it stood (a vehicle: its first bearing), its kind and offset.
    for s in &l.report.stations {
        let (Some(lat), Some(lon)) = (s.lat, s.lon) else {
            continue;
        };
        features.push(json!({"type": "Feature",
            "properties": {"kind": "station", "id": s.id,
                "station": if s.fixed { "fixed" } else { "mobile" },
                "offset_deg": s.offset_deg, "offset_sd_deg": s.offset_sd_deg,
                "offset_from": s.offset_from, "bearings": s.bearings},
            "geometry": {"type": "Point", "coordinates": [lon, lat]}}));
    }
    let track: Vec<[f64; 2]> = d
        .track
        .iter()
        .map(|f| [f.position.lon, f.position.lat])
        .collect();
    if track.len() > 1 {
        features.push(json!({"type": "Feature", "properties": {"kind": "track"},
            "geometry": line_geometry(&track)}));
    }
    for (a, b) in rays(l, d) {
        features.push(json!({"type": "Feature", "properties": {"kind": "bearing"},
            "geometry": line_geometry(&[lonlat(&frame, a), lonlat(&frame, b)])}));
    }
    json!({"type": "FeatureCollection", "features": features})
}
