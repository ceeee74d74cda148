//! KML of a fix, for Google Earth and most GIS tools.

use super::{ellipse_ring, lonlat, rays, regions, sources, wedge_length, wedge_ring, xml_text};
use crate::inputs::capture::Decoded;
use crate::locate::explain::range_words;
use crate::locate::report::Located;
use std::fmt::Write;

/// KML: every emitter and other source with its ellipse, the DF stations, the vehicle track and
/// the bearings.
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
    for r in regions(l) {
        let ring: Vec<String> = wedge_ring(r, wedge_length(r, d))
            .into_iter()
            .map(|p| coords(lonlat(&frame, p)))
            .collect();
        if !ring.is_empty() {
            let _ = writeln!(
                out,
                "<Placemark><name>region: {:.0} % wedge</name><description>bearing {:.1} deg +- {:.1} deg from the observers; range {}{}; {} bearings</description><Polygon><outerBoundaryIs><LinearRing><coordinates>{}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>",
                100.0 * r.confidence,
                r.bearing_deg,
                r.half_width_deg,
                range_words(r),
                if r.max_range_m.is_none() {
                    " (drawn to the map's edge)"
                } else {
                    ""
                },
                r.used,
                ring.join(" ")
            );
        }
    }
    out.push_str("<Folder><name>stations</name>\n");
    for s in &l.report.stations {
        let (Some(lat), Some(lon)) = (s.lat, s.lon) else {
            continue;
        };
        let _ = writeln!(
            out,
            "<Placemark><name>{}</name><description>{} station; offset {:.2} +- {:.2} deg ({}); {} bearings</description><Point><coordinates>{}</coordinates></Point></Placemark>",
            xml_text(&s.id),
            if s.fixed { "fixed" } else { "mobile" },
            s.offset_deg,
            s.offset_sd_deg,
            s.offset_from,
            s.bearings,
            coords([lon, lat])
        );
    }
    out.push_str("</Folder>\n");
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
