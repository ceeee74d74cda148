//! Every map the command draws: GeoJSON, KML and SVG of a fix, and the SVG of an indoor track.
//! The three fix formats share one ellipse ring and one bearing-ray length.
//!
//! All are written by hand: a few fixed elements of numbers and fixed words (no user text to
//! escape), which a dependency would not make shorter.

mod geojson;
mod kml;
mod svg;
#[cfg(test)]
mod tests;

pub use geojson::{geojson, polygon_geometry, split_antimeridian};
pub use kml::kml;
pub use svg::{svg, track_svg};

use crate::inputs::capture::Decoded;
use crate::locate::report::{Drawn, Located, SourceReport, geodetic};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::ellipse::Ellipse;

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
pub(super) fn rays(l: &Located, d: &Decoded) -> Vec<([f32; 2], [f32; 2])> {
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
pub fn lonlat(frame: &LocalFrame, p: [f32; 2]) -> [f64; 2] {
    let g = geodetic(frame, p);
    [g.lon, g.lat]
}

/// The report's sources with what the maps draw of them: (report, drawing, is an emitter).
pub(super) fn sources(l: &Located) -> impl Iterator<Item = (&SourceReport, &Drawn)> {
    l.report
        .emitters
        .iter()
        .chain(l.report.other_sources.iter())
        .zip(l.drawn.iter())
}

/// Each station's latest bearing, by its index in the decoded stations (`None`: none yet).
pub fn latest_bearings(d: &Decoded) -> Vec<Option<foxhunt_core::Bearing>> {
    let mut latest = vec![None; d.stations.len()];
    for o in &d.observations {
        if let Some(slot) = latest.get_mut(usize::from(o.station)) {
            *slot = Some(o.bearing);
        }
    }
    latest
}

/// `text` with XML's special characters escaped (a station id is the records' text): KML and CoT.
pub fn xml_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}
