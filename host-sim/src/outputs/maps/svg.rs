//! SVG pictures: a fix on its drive (north up, to scale, with a legend), and an indoor track.

use super::{ellipse_ring, rays, sources};
use crate::inputs::capture::Decoded;
use crate::locate::report::Located;
use crate::locate::report::{Drawn, SourceReport};
use crate::track::indoor::AnchorsFile;
use std::fmt::Write;

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
pub(super) fn nice_length(span: f32) -> f32 {
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
/// north arrow and a scale bar; 600 x 600 pixels. `path`: the track's positions in the
/// anchors file's metres.
pub fn track_svg(path: &[[f32; 2]], anchors: &AnchorsFile) -> String {
    let path_pts: Vec<[f32; 2]> = path.to_vec();
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
            format!("estimated track ({} steps)", path.len()),
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
