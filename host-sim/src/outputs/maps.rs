//! Every map the command draws: GeoJSON, KML and SVG of a fix, and the SVG of an indoor track.
//! The three fix formats share one ellipse ring and one bearing-ray length.
//!
//! All are written by hand: a few fixed elements of numbers and fixed words (no user text to
//! escape), which a dependency would not make shorter.

use crate::inputs::capture::Decoded;
use crate::locate::report::{Drawn, Located, SourceReport, geodetic};
use crate::track::indoor::{AnchorsFile, Track};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::ellipse::Ellipse;
use serde_json::{Value, json};
use std::fmt::Write;

/// Vertices of the ellipse ring (the first repeated at the end to close it).
const RING_VERTICES: usize = 72;

/// Points of an ellipse about `position` in local metres, closed (first point repeated);
/// empty when its axes are not finite.
pub fn ellipse_ring(position: [f32; 2], e: &Ellipse) -> Vec<[f32; 2]> {
    if !(e.major.is_finite() && e.minor.is_finite() && e.orientation.is_finite()) {
        return Vec::new();
    }
    let (c, si) = (e.orientation.cos(), e.orientation.sin());
    let mut ring: Vec<[f32; 2]> = (0..RING_VERTICES)
        .map(|k| {
            let t = k as f32 * std::f32::consts::TAU / RING_VERTICES as f32;
            let (a, b) = (e.major * t.cos(), e.minor * t.sin());
            [position[0] + a * c - b * si, position[1] + a * si + b * c]
        })
        .collect();
    ring.push(ring[0]);
    ring
}

/// How far bearing rays are drawn: past every source, 1.3 times the farthest vehicle
/// position's distance from one.
pub fn ray_length(l: &Located, d: &Decoded) -> f32 {
    l.drawn
        .iter()
        .flat_map(|s| {
            d.bearings()
                .map(|b| (b.vehicle[0] - s.position[0]).hypot(b.vehicle[1] - s.position[1]))
        })
        .fold(1.0f32, f32::max)
        * 1.3
}

/// The far end of each bearing's ray, in local metres.
fn rays(l: &Located, d: &Decoded) -> Vec<([f32; 2], [f32; 2])> {
    let reach = ray_length(l, d);
    d.bearings()
        .map(|b| {
            let end = [
                b.vehicle[0] + reach * b.theta.cos(),
                b.vehicle[1] + reach * b.theta.sin(),
            ];
            (b.vehicle, end)
        })
        .collect()
}

/// [longitude, latitude] of local metres.
fn lonlat(frame: &LocalFrame, p: [f32; 2]) -> [f64; 2] {
    let g = geodetic(frame, p);
    [g.lon, g.lat]
}

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
fn polygon_geometry(ring: &[[f64; 2]]) -> Value {
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

/// The report's sources with what the maps draw of them: (report, drawing, is an emitter).
fn sources(l: &Located) -> impl Iterator<Item = (&SourceReport, &Drawn)> {
    l.report
        .emitters
        .iter()
        .chain(l.report.other_sources.iter())
        .zip(l.drawn.iter())
}

/// Every emitter and other source with its ellipse, the track and the bearing rays as GeoJSON
/// (RFC 7946: longitude first, polygons closed, nothing crossing the antimeridian).
pub fn geojson(l: &Located, d: &Decoded) -> Value {
    let Some(frame) = d.frame else {
        return json!({"type": "FeatureCollection", "features": []});
    };
    let mut features = Vec::new();
    for (r, s) in sources(l) {
        let kind = if s.other { "other_source" } else { "emitter" };
        features.push(json!({"type": "Feature",
            "properties": {"kind": kind, "method": l.report.method, "freq_mhz": r.freq_mhz,
                "cep50_m": r.cep50_m, "crlb_m": r.crlb_m, "semi_major_m": r.ellipse.major_m,
                "semi_minor_m": r.ellipse.minor_m, "bias_deg": r.bias_deg, "used": r.used},
            "geometry": {"type": "Point", "coordinates": [r.lon, r.lat]}}));
        let ring: Vec<[f64; 2]> = ellipse_ring(s.position, &s.ellipse)
            .into_iter()
            .map(|p| lonlat(&frame, p))
            .collect();
        if !ring.is_empty() {
            features.push(json!({"type": "Feature",
                "properties": {"kind": "ellipse", "of": kind, "confidence": s.ellipse.confidence},
                "geometry": polygon_geometry(&ring)}));
        }
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

/// KML: every emitter and other source with its ellipse, the vehicle track and the bearings.
pub fn kml(l: &Located, d: &Decoded) -> String {
    let Some(frame) = d.frame else {
        return String::new();
    };
    let coords = |p: [f64; 2]| format!("{:.8},{:.8},0", p[0], p[1]);
    let mut out = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>foxhunt fix</name>\n",
    );
    for (r, s) in sources(l) {
        let name = if s.other { "other source" } else { "emitter" };
        let _ = writeln!(
            out,
            "<Placemark><name>{name}</name><description>method {}; {:.0} % ellipse semi-axes {:.1} m x {:.1} m; CEP50 {:.1} m; bound {:.1} m; {} bearings</description><Point><coordinates>{}</coordinates></Point></Placemark>",
            l.report.method,
            100.0 * r.ellipse.confidence,
            r.ellipse.major_m,
            r.ellipse.minor_m,
            r.cep50_m,
            r.crlb_m,
            r.used,
            coords([r.lon, r.lat])
        );
        let ring: Vec<String> = ellipse_ring(s.position, &s.ellipse)
            .into_iter()
            .map(|p| coords(lonlat(&frame, p)))
            .collect();
        if !ring.is_empty() {
            let _ = writeln!(
                out,
                "<Placemark><name>{name}: {:.0} % ellipse</name><Polygon><outerBoundaryIs><LinearRing><coordinates>{}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>",
                100.0 * s.ellipse.confidence,
                ring.join(" ")
            );
        }
    }
    let track: Vec<String> = d
        .track
        .iter()
        .map(|f| coords([f.position.lon, f.position.lat]))
        .collect();
    if track.len() > 1 {
        let _ = writeln!(
            out,
            "<Placemark><name>vehicle track</name><LineString><coordinates>{}</coordinates></LineString></Placemark>",
            track.join(" ")
        );
    }
    out.push_str("<Folder><name>bearings</name>\n");
    for (a, b) in rays(l, d) {
        let _ = writeln!(
            out,
            "<Placemark><LineString><coordinates>{} {}</coordinates></LineString></Placemark>",
            coords(lonlat(&frame, a)),
            coords(lonlat(&frame, b))
        );
    }
    out.push_str("</Folder>\n</Document>\n</kml>\n");
    out
}

/// A north-up square picture of local metres.
struct View {
    size: f32,
    span: f32,
    scale: f32,
    centre: [f32; 2],
}

impl View {
    /// The square that shows `pts` (at least `min_span` metres, padded by `pad`) in `size`
    /// pixels with a `margin`.
    fn fit(pts: &[[f32; 2]], size: f32, margin: f32, min_span: f32, pad: f32) -> Self {
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for p in pts.iter().filter(|p| p.iter().all(|v| v.is_finite())) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if lo[0] > hi[0] {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(min_span) * pad;
        Self {
            size,
            span,
            scale: (size - 2.0 * margin) / span,
            centre: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0],
        }
    }

    fn px(&self, p: [f32; 2]) -> (f32, f32) {
        (
            self.size / 2.0 + (p[0] - self.centre[0]) * self.scale,
            self.size / 2.0 - (p[1] - self.centre[1]) * self.scale,
        )
    }

    fn path(&self, ps: &[[f32; 2]]) -> String {
        ps.iter()
            .enumerate()
            .map(|(i, p)| {
                let (x, y) = self.px(*p);
                format!("{}{x:.1},{y:.1}", if i == 0 { "M" } else { " L" })
            })
            .collect()
    }

    /// A label at pixel (x, y) kept inside the picture: anchored at its end when it would run
    /// off the right edge (text is about 7 pixels per character at 13 px).
    fn label(&self, x: f32, y: f32, text: &str, out: &mut String) {
        let width = 7.0 * text.chars().count() as f32;
        let (x, anchor) = if x + width > self.size - 8.0 {
            (
                (x - 16.0).clamp(width.min(self.size - 8.0), self.size - 8.0),
                "end",
            )
        } else {
            (x.max(8.0), "start")
        };
        let y = y.clamp(16.0, self.size - 8.0);
        let _ = writeln!(
            out,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" text-anchor=\"{anchor}\" font-family=\"sans-serif\" font-size=\"13\">{text}</text>"
        );
    }

    /// Scale bar, bottom left, and north arrow, top right.
    fn furniture(&self, out: &mut String) {
        let s = self.size;
        let _ = writeln!(
            out,
            "<path d=\"M{:.0},20 L{:.0},50 L{:.0},44 L{:.0},50 Z\" fill=\"black\"/>\n<text x=\"{:.0}\" y=\"66\" font-family=\"sans-serif\" font-size=\"14\">N</text>",
            s - 40.0,
            s - 30.0,
            s - 40.0,
            s - 50.0,
            s - 45.0
        );
        let bar = nice_length(self.span);
        let label = if bar >= 1000.0 {
            format!("{} km", bar / 1000.0)
        } else {
            format!("{bar} m")
        };
        let _ = writeln!(
            out,
            "<rect x=\"20\" y=\"{:.0}\" width=\"{:.1}\" height=\"6\" fill=\"black\"/>\n<text x=\"20\" y=\"{:.0}\" font-family=\"sans-serif\" font-size=\"13\">{label}</text>",
            s - 30.0,
            bar * self.scale,
            s - 38.0
        );
    }
}

/// A scale-bar length: 1, 2 or 5 times a power of ten, near a fifth of `span` metres.
fn nice_length(span: f32) -> f32 {
    let target = (span / 5.0).max(1e-3);
    let p = 10f32.powf(target.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .filter(|l| *l <= target)
        .fold(p, f32::max)
}

fn svg_open(size: f32) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{size}\" height=\"{size}\" viewBox=\"0 0 {size} {size}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    )
}

/// A legend box, top left: (swatch markup at the origin, text) per entry.
fn legend(entries: &[(&str, String)], out: &mut String) {
    let h = 22.0 * entries.len() as f32 + 10.0;
    let _ = writeln!(
        out,
        "<g transform=\"translate(12,12)\"><rect width=\"250\" height=\"{h:.0}\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#999\"/>"
    );
    for (i, (swatch, text)) in entries.iter().enumerate() {
        let y = 20.0 + 22.0 * i as f32;
        let _ = writeln!(
            out,
            "<g transform=\"translate(12,{y:.0})\">{swatch}</g><text x=\"44\" y=\"{:.0}\" font-family=\"sans-serif\" font-size=\"12\">{text}</text>",
            y + 4.0
        );
    }
    out.push_str("</g>\n");
}

const TRACK_COLOUR: &str = "#1f4e9c";
const RAY_COLOUR: &str = "#e08a3c";
const FIX_COLOUR: &str = "#c0392b";

/// Where other sources are drawn: the emitters' colour would read as one more emitter.
const OTHER_COLOUR: &str = "#7d3c98";

/// SVG of a fix: bearing rays, the track, the method's particles (if it has any), every
/// emitter and other source with its ellipse, a legend, a north arrow and a scale bar; north
/// up, 800 x 800 pixels.
pub fn svg(l: &Located, d: &Decoded) -> String {
    let rings: Vec<(Vec<[f32; 2]>, &Drawn, &SourceReport)> = sources(l)
        .map(|(r, s)| (ellipse_ring(s.position, &s.ellipse), s, r))
        .collect();
    let track: Vec<[f32; 2]> = d.track.iter().map(|f| f.local).collect();
    let mut pts: Vec<[f32; 2]> = track.clone();
    pts.extend(d.bearings().map(|b| b.vehicle));
    for (ring, s, _) in &rings {
        pts.push(s.position);
        pts.extend(ring.iter().copied());
    }
    let v = View::fit(&pts, 800.0, 40.0, 10.0, 1.15);
    let mut out = svg_open(v.size);
    let _ = writeln!(
        out,
        "<g stroke=\"{RAY_COLOUR}\" stroke-width=\"0.7\" stroke-opacity=\"0.6\">"
    );
    for (a, b) in rays(l, d) {
        let ((x0, y0), (x1, y1)) = (v.px(a), v.px(b));
        let _ = writeln!(
            out,
            "<line x1=\"{x0:.1}\" y1=\"{y0:.1}\" x2=\"{x1:.1}\" y2=\"{y1:.1}\"/>"
        );
    }
    out.push_str("</g>\n");
    if track.len() > 1 {
        let _ = writeln!(
            out,
            "<path d=\"{}\" fill=\"none\" stroke=\"{TRACK_COLOUR}\" stroke-width=\"2.5\"/>",
            v.path(&track)
        );
    }
    if !l.cloud.is_empty() {
        out.push_str("<g fill=\"#6a6a6a\" fill-opacity=\"0.5\">\n");
        for p in &l.cloud {
            let (x, y) = v.px(*p);
            let _ = writeln!(out, "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"1.2\"/>");
        }
        out.push_str("</g>\n");
    }
    for (ring, s, r) in &rings {
        let colour = if s.other { OTHER_COLOUR } else { FIX_COLOUR };
        if !ring.is_empty() {
            let _ = writeln!(
                out,
                "<path d=\"{} Z\" fill=\"{colour}\" fill-opacity=\"0.15\" stroke=\"{colour}\" stroke-width=\"1.5\"/>",
                v.path(ring)
            );
        }
        let (ex, ey) = v.px(s.position);
        let _ = writeln!(
            out,
            "<circle cx=\"{ex:.1}\" cy=\"{ey:.1}\" r=\"5\" fill=\"{colour}\"/>"
        );
        let what = if s.other { "other source " } else { "" };
        v.label(
            ex + 8.0,
            ey - 8.0,
            &format!("{what}{:.6}, {:.6}", r.lat, r.lon),
            &mut out,
        );
    }
    let r = &l.report;
    let mut entries = vec![
        (
            format!(
                "<line x1=\"0\" y1=\"0\" x2=\"24\" y2=\"0\" stroke=\"{TRACK_COLOUR}\" stroke-width=\"2.5\"/>"
            ),
            "vehicle route".to_string(),
        ),
        (
            format!("<line x1=\"0\" y1=\"0\" x2=\"24\" y2=\"0\" stroke=\"{RAY_COLOUR}\"/>"),
            format!("bearings ({})", d.observations.len()),
        ),
    ];
    if let Some(e) = r.emitters.first() {
        entries.push((
            format!("<circle cx=\"12\" cy=\"0\" r=\"5\" fill=\"{FIX_COLOUR}\"/>"),
            format!("fix ({}), CEP50 {:.0} m", r.method, e.cep50_m),
        ));
        entries.push((
            format!("<ellipse cx=\"12\" cy=\"0\" rx=\"11\" ry=\"6\" fill=\"{FIX_COLOUR}\" fill-opacity=\"0.15\" stroke=\"{FIX_COLOUR}\"/>"),
            format!(
                "{:.0} % ellipse, semi-axes {:.0} x {:.0} m",
                100.0 * e.ellipse.confidence,
                e.ellipse.major_m,
                e.ellipse.minor_m
            ),
        ));
    }
    if !r.other_sources.is_empty() {
        entries.push((
            format!("<circle cx=\"12\" cy=\"0\" r=\"5\" fill=\"{OTHER_COLOUR}\"/>"),
            format!("other sources ({})", r.other_sources.len()),
        ));
    }
    if !l.cloud.is_empty() {
        entries.push((
            "<circle cx=\"12\" cy=\"0\" r=\"2\" fill=\"#6a6a6a\"/>".to_string(),
            format!("particles ({})", l.cloud.len()),
        ));
    }
    let entries: Vec<(&str, String)> = entries
        .iter()
        .map(|(a, b)| (a.as_str(), b.clone()))
        .collect();
    legend(&entries, &mut out);
    v.furniture(&mut out);
    out.push_str("</svg>\n");
    out
}

/// SVG of an indoor track: the room, the anchors and the estimated path, with a legend, a
/// north arrow and a scale bar; 600 x 600 pixels.
pub fn track_svg(track: &Track, anchors: &AnchorsFile) -> String {
    let path_pts: Vec<[f32; 2]> = track.points.iter().map(|p| [p.x_m, p.y_m]).collect();
    let mut pts = path_pts.clone();
    pts.extend(anchors.anchor.iter().map(|a| [a.x, a.y]));
    if let Some([w, d]) = anchors.room {
        pts.extend([[0.0, 0.0], [w, d]]);
    }
    let v = View::fit(&pts, 600.0, 30.0, 1.0, 1.25);
    let mut out = svg_open(v.size);
    if let Some([w, d]) = anchors.room {
        let (x0, y0) = v.px([0.0, d]);
        let _ = writeln!(
            out,
            "<rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/>",
            w * v.scale,
            d * v.scale
        );
    }
    if path_pts.len() > 1 {
        let _ = writeln!(
            out,
            "<path d=\"{}\" fill=\"none\" stroke=\"{TRACK_COLOUR}\" stroke-width=\"2\"/>",
            v.path(&path_pts)
        );
    }
    for a in &anchors.anchor {
        let (x, y) = v.px([a.x, a.y]);
        let _ = writeln!(
            out,
            "<path d=\"M{x:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z\" fill=\"{FIX_COLOUR}\"/>",
            y - 8.0,
            x + 7.0,
            y + 5.0,
            x - 7.0,
            y + 5.0
        );
        v.label(x + 9.0, y - 4.0, &format!("0x{:04x}", a.addr), &mut out);
    }
    let entries = [
        (
            format!(
                "<line x1=\"0\" y1=\"0\" x2=\"24\" y2=\"0\" stroke=\"{TRACK_COLOUR}\" stroke-width=\"2\"/>"
            ),
            format!("estimated track ({} steps)", track.points.len()),
        ),
        (
            format!("<path d=\"M12,-7 L19,5 L5,5 Z\" fill=\"{FIX_COLOUR}\"/>"),
            "anchor (short address)".to_string(),
        ),
        (
            "<rect x=\"2\" y=\"-6\" width=\"20\" height=\"12\" fill=\"none\" stroke=\"black\"/>"
                .to_string(),
            "room".to_string(),
        ),
    ];
    let entries: Vec<(&str, String)> = entries
        .iter()
        .map(|(a, b)| (a.as_str(), b.clone()))
        .collect();
    legend(&entries, &mut out);
    v.furniture(&mut out);
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bar_lengths_are_round() {
        assert_eq!(nice_length(1000.0), 200.0);
        assert_eq!(nice_length(3000.0), 500.0);
        assert_eq!(nice_length(60.0), 10.0);
    }

    #[test]
    fn lines_are_cut_at_the_antimeridian() {
        let line = [[179.0, 10.0], [-179.0, 12.0], [-178.0, 12.0]];
        let parts = split_antimeridian(&line);
        assert_eq!(parts.len(), 2, "{parts:?}");
        assert_eq!(parts[0].last(), Some(&[180.0, 11.0]));
        assert_eq!(parts[1][0], [-180.0, 11.0]);
        let west = [[-179.5, 0.0], [179.5, 2.0]];
        let parts = split_antimeridian(&west);
        assert_eq!(parts[0].last(), Some(&[-180.0, 1.0]));
        assert_eq!(parts[1][0], [180.0, 1.0]);
        assert_eq!(split_antimeridian(&[[1.0, 1.0], [2.0, 2.0]]).len(), 1);
    }

    #[test]
    fn polygons_are_cut_at_the_antimeridian() {
        let ring = [
            [179.0, 0.0],
            [-179.0, 0.0],
            [-179.0, 1.0],
            [179.0, 1.0],
            [179.0, 0.0],
        ];
        let g = polygon_geometry(&ring);
        assert_eq!(g["type"], "MultiPolygon", "{g}");
        for part in g["coordinates"].as_array().unwrap() {
            for p in part[0].as_array().unwrap() {
                let lon = p[0].as_f64().unwrap();
                assert!((-180.0..=180.0).contains(&lon), "{g}");
            }
        }
        let plain = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 0.0]];
        assert_eq!(polygon_geometry(&plain)["type"], "Polygon");
    }
}
