//! Map files of a fix: KML for Google Earth and GIS tools, SVG for a quick look.
//!
//! Both are written by hand: a few fixed elements of numbers only (no user text to escape),
//! which a dependency would not make shorter.

use crate::locate::{Decoded, LocateReport, Solution};
use foxhunt_core::fix::ellipse::Ellipse;
use std::fmt::Write;

/// Points of the 95 % ellipse in local metres, closed (first point repeated).
pub fn ellipse_ring(s: &Solution) -> Vec<[f32; 2]> {
    let Ok(e) = Ellipse::from_covariance(&s.covariance, 0.95) else {
        return Vec::new();
    };
    let (c, si) = (e.orientation.cos(), e.orientation.sin());
    let mut ring: Vec<[f32; 2]> = (0..72)
        .map(|k| {
            let t = k as f32 * std::f32::consts::TAU / 72.0;
            let (a, b) = (e.major * t.cos(), e.minor * t.sin());
            [
                s.position[0] + a * c - b * si,
                s.position[1] + a * si + b * c,
            ]
        })
        .collect();
    ring.push(ring[0]);
    ring
}

/// A north-up square view of `pts`: the span shown (metres, at least `min_span`, padded by
/// `pad`), pixels per metre, and the map from local metres to pixels.
fn view(
    pts: &[[f32; 2]],
    size: f32,
    margin: f32,
    min_span: f32,
    pad: f32,
) -> (f32, f32, impl Fn([f32; 2]) -> (f32, f32)) {
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(min_span) * pad;
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let scale = (size - 2.0 * margin) / span;
    let px = move |p: [f32; 2]| {
        (
            size / 2.0 + (p[0] - centre[0]) * scale,
            size / 2.0 - (p[1] - centre[1]) * scale,
        )
    };
    (span, scale, px)
}

/// How far bearing lines are drawn: past the emitter, from the farthest vehicle position.
fn ray_length(s: &Solution, d: &Decoded) -> f32 {
    d.bearings
        .iter()
        .map(|b| (b.vehicle[0] - s.position[0]).hypot(b.vehicle[1] - s.position[1]))
        .fold(1.0f32, f32::max)
        * 1.3
}

/// KML: the emitter, the ellipse, the vehicle track and the bearing lines.
pub fn kml(r: &LocateReport, s: &Solution, d: &Decoded) -> String {
    let Some(frame) = d.frame else {
        return String::new();
    };
    let ll = |p: [f32; 2]| {
        frame
            .to_geodetic([f64::from(p[0]), f64::from(p[1])])
            .map(|g| format!("{:.8},{:.8},0", g.lon, g.lat))
            .unwrap_or_default()
    };
    let mut out = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>foxhunt fix</name>\n",
    );
    let _ = writeln!(
        out,
        "<Placemark><name>emitter</name><description>{:?}; CEP50 {:.1} m; CRLB {:.1} m</description><Point><coordinates>{:.8},{:.8},0</coordinates></Point></Placemark>",
        r.method, r.cep50_m, r.crlb_m, r.lon, r.lat
    );
    let ring: Vec<String> = ellipse_ring(s).into_iter().map(ll).collect();
    if !ring.is_empty() {
        let _ = writeln!(
            out,
            "<Placemark><name>95 % ellipse</name><Polygon><outerBoundaryIs><LinearRing><coordinates>{}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>",
            ring.join(" ")
        );
    }
    let track: Vec<String> = d
        .track
        .iter()
        .map(|f| format!("{:.8},{:.8},0", f.position.lon, f.position.lat))
        .collect();
    let _ = writeln!(
        out,
        "<Placemark><name>vehicle track</name><LineString><coordinates>{}</coordinates></LineString></Placemark>",
        track.join(" ")
    );
    let reach = ray_length(s, d);
    out.push_str("<Folder><name>bearings</name>\n");
    for b in &d.bearings {
        let end = [
            b.vehicle[0] + reach * b.theta.cos(),
            b.vehicle[1] + reach * b.theta.sin(),
        ];
        let _ = writeln!(
            out,
            "<Placemark><LineString><coordinates>{} {}</coordinates></LineString></Placemark>",
            ll(b.vehicle),
            ll(end)
        );
    }
    out.push_str("</Folder>\n</Document>\n</kml>\n");
    out
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

/// SVG: bearing rays, the track, the particle cloud, the ellipse, the emitter, a north arrow
/// and a scale bar, north up, 800 x 800 pixels.
pub fn svg(r: &LocateReport, s: &Solution, d: &Decoded) -> String {
    let ring = ellipse_ring(s);
    let mut pts: Vec<[f32; 2]> = d.track.iter().map(|f| f.local).collect();
    pts.extend(d.bearings.iter().map(|b| b.vehicle));
    pts.push(s.position);
    pts.extend(ring.iter().copied());
    let size = 800.0f32;
    let (span, scale, px) = view(&pts, size, 40.0, 10.0, 1.15);
    let path = |ps: &[[f32; 2]]| -> String {
        ps.iter()
            .enumerate()
            .map(|(i, p)| {
                let (x, y) = px(*p);
                format!("{}{x:.1},{y:.1}", if i == 0 { "M" } else { " L" })
            })
            .collect()
    };
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{size}\" height=\"{size}\" viewBox=\"0 0 {size} {size}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let reach = 2.0 * span;
    out.push_str("<g stroke=\"#e08a3c\" stroke-width=\"0.7\" stroke-opacity=\"0.6\">\n");
    for b in &d.bearings {
        let (x0, y0) = px(b.vehicle);
        let (x1, y1) = px([
            b.vehicle[0] + reach * b.theta.cos(),
            b.vehicle[1] + reach * b.theta.sin(),
        ]);
        let _ = writeln!(
            out,
            "<line x1=\"{x0:.1}\" y1=\"{y0:.1}\" x2=\"{x1:.1}\" y2=\"{y1:.1}\"/>"
        );
    }
    out.push_str("</g>\n");
    let track: Vec<[f32; 2]> = d.track.iter().map(|f| f.local).collect();
    if !track.is_empty() {
        let _ = writeln!(
            out,
            "<path d=\"{}\" fill=\"none\" stroke=\"#1f4e9c\" stroke-width=\"2.5\"/>",
            path(&track)
        );
    }
    out.push_str("<g fill=\"#6a6a6a\" fill-opacity=\"0.5\">\n");
    for p in &s.cloud {
        let (x, y) = px(*p);
        let _ = writeln!(out, "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"1.2\"/>");
    }
    out.push_str("</g>\n");
    if !ring.is_empty() {
        let _ = writeln!(
            out,
            "<path d=\"{} Z\" fill=\"#c0392b\" fill-opacity=\"0.15\" stroke=\"#c0392b\" stroke-width=\"1.5\"/>",
            path(&ring)
        );
    }
    let (ex, ey) = px(s.position);
    let _ = writeln!(
        out,
        "<circle cx=\"{ex:.1}\" cy=\"{ey:.1}\" r=\"5\" fill=\"#c0392b\"/>"
    );
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"sans-serif\" font-size=\"13\">emitter {:.6}, {:.6} (CEP50 {:.0} m)</text>",
        ex + 8.0,
        ey - 8.0,
        r.lat,
        r.lon,
        r.cep50_m
    );
    // North arrow, top right.
    out.push_str("<path d=\"M760,20 L770,50 L760,44 L750,50 Z\" fill=\"black\"/>\n<text x=\"755\" y=\"66\" font-family=\"sans-serif\" font-size=\"14\">N</text>\n");
    // Scale bar, bottom left.
    let bar = nice_length(span);
    let w = bar * scale;
    let _ = writeln!(
        out,
        "<rect x=\"40\" y=\"760\" width=\"{w:.1}\" height=\"6\" fill=\"black\"/>"
    );
    let label = if bar >= 1000.0 {
        format!("{} km", bar / 1000.0)
    } else {
        format!("{bar} m")
    };
    let _ = writeln!(
        out,
        "<text x=\"40\" y=\"752\" font-family=\"sans-serif\" font-size=\"13\">{label}</text>"
    );
    out.push_str("</svg>\n");
    out
}

/// SVG of an indoor track: the room, the anchors and the estimated path, 600 x 600 pixels.
pub fn track_svg(track: &crate::indoor::Track, anchors: &crate::indoor::AnchorsFile) -> String {
    let mut pts: Vec<[f32; 2]> = track.points.iter().map(|p| [p.x_m, p.y_m]).collect();
    pts.extend(anchors.anchor.iter().map(|a| [a.x, a.y]));
    if let Some([w, d]) = anchors.room {
        pts.extend([[0.0, 0.0], [w, d]]);
    }
    let size = 600.0f32;
    let (_, scale, px) = view(&pts, size, 30.0, 1.0, 1.1);
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{size}\" height=\"{size}\" viewBox=\"0 0 {size} {size}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    if let Some([w, d]) = anchors.room {
        let (x0, y0) = px([0.0, d]);
        let _ = writeln!(
            out,
            "<rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/>",
            w * scale,
            d * scale
        );
    }
    let path: String = track
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (x, y) = px([p.x_m, p.y_m]);
            format!("{}{x:.1},{y:.1}", if i == 0 { "M" } else { " L" })
        })
        .collect();
    let _ = writeln!(
        out,
        "<path d=\"{path}\" fill=\"none\" stroke=\"#1f4e9c\" stroke-width=\"2\"/>"
    );
    for a in &anchors.anchor {
        let (x, y) = px([a.x, a.y]);
        let _ = writeln!(
            out,
            "<path d=\"M{x:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z\" fill=\"#c0392b\"/>",
            y - 8.0,
            x + 7.0,
            y + 5.0,
            x - 7.0,
            y + 5.0
        );
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"sans-serif\" font-size=\"12\">0x{:04x}</text>",
            x + 9.0,
            y - 4.0,
            a.addr
        );
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::nice_length;

    #[test]
    fn scale_bar_lengths_are_round() {
        assert_eq!(nice_length(1000.0), 200.0);
        assert_eq!(nice_length(3000.0), 500.0);
        assert_eq!(nice_length(60.0), 10.0);
    }
}
