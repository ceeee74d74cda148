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
use crate::locate::report::{Drawn, Located, RegionReport, SourceReport, geodetic};
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

/// Vertices of each arc of a region's wedge.
const ARC_VERTICES: usize = 24;

/// The wedge of a region in local metres, closed: the arc at its nearest range (the apex when
/// that is 0) and the arc at its farthest, `unbounded_m` for an unbounded region (a wedge
/// drawn that far, not a claim that it ends there); empty when a figure is not finite.
pub fn wedge_ring(r: &RegionReport, unbounded_m: f32) -> Vec<[f32; 2]> {
    let far = r
        .max_range_m
        .unwrap_or(unbounded_m.max(2.0 * r.min_range_m));
    let (b, w) = (r.bearing_deg.to_radians(), r.half_width_deg.to_radians());
    if !([r.east_m, r.north_m, b, w, r.min_range_m, far]
        .iter()
        .all(|v| v.is_finite()))
    {
        return Vec::new();
    }
    let at = |range: f32, azimuth: f32| {
        [
            r.east_m + range * azimuth.sin(),
            r.north_m + range * azimuth.cos(),
        ]
    };
    let arc = |range: f32, reverse: bool| -> Vec<[f32; 2]> {
        (0..=ARC_VERTICES)
            .map(|k| {
                let k = if reverse { ARC_VERTICES - k } else { k };
                at(range, b - w + 2.0 * w * k as f32 / ARC_VERTICES as f32)
            })
            .collect()
    };
    let mut ring = if r.min_range_m > 0.0 {
        arc(r.min_range_m, false)
    } else {
        vec![[r.east_m, r.north_m]]
    };
    ring.extend(arc(far, true));
    ring.push(ring[0]);
    ring
}

/// The regions of a report's channels (open ranges).
pub(super) fn regions(l: &Located) -> impl Iterator<Item = &RegionReport> {
    l.report.channels.iter().filter_map(|c| c.region.as_ref())
}

/// How far an unbounded region's wedge is drawn: past every vehicle position, 1.3 times the
/// farthest one's distance from the apex, and at least 5 km.
pub fn wedge_length(r: &RegionReport, d: &Decoded) -> f32 {
    d.bearings()
        .map(|b| (b.vehicle[0] - r.east_m).hypot(b.vehicle[1] - r.north_m) * 1.3)
        .fold(5000.0f32, f32::max)
}

/// How far bearing rays are drawn: past every source, 1.3 times the farthest vehicle
/// position's distance from one (and as far as a region's wedge).
pub fn ray_length(l: &Located, d: &Decoded) -> f32 {
    l.drawn
        .iter()
        .flat_map(|s| {
            d.bearings()
                .map(|b| (b.vehicle[0] - s.position[0]).hypot(b.vehicle[1] - s.position[1]))
        })
        .fold(1.0f32, f32::max)
        .max(
            regions(l)
                .map(|r| wedge_length(r, d) / 1.3)
                .fold(0.0, f32::max),
        )
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
