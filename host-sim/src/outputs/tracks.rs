//! A moving emitter's tracks as `foxhunt track` writes them: JSON (one object, docs/src/
//! formats/json.md#track), CSV (one line per point), and GeoJSON and KML (the track line and
//! every point with its 95 % ellipse).

use crate::locate::report::EllipseReport;
use crate::outputs::json::Short;
use crate::outputs::maps::{ellipse_ring, polygon_geometry, split_antimeridian};
use crate::track::moving::TrackPoint;
use crate::track::tracks::{StationNoise, Tracks};
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::device::DeviceClass;
use serde_json::{Map, Value, json};
use std::fmt::Write;

/// Milliseconds of a point's time.
fn t_ms(p: &TrackPoint) -> i64 {
    (f64::from(p.t_s) * 1000.0).round() as i64
}

/// A number JSON can hold: non-finite values become null.
fn num(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

/// The ellipse of a point as JSON (null when its covariance gives none), its orientation
/// clockwise from north as `locate` reports it.
fn ellipse(p: &TrackPoint) -> Value {
    p.ellipse().map_or(Value::Null, |e| {
        let r = EllipseReport::from(&e);
        json!({
            "major_m": r.major_m.short(),
            "minor_m": r.minor_m.short(),
            "orientation_deg": r.orientation_deg.short(),
            "confidence": r.confidence.short(),
        })
    })
}

/// One point as JSON: latitude and longitude only when the tracks are placed.
pub fn point(t: &Tracks, p: &TrackPoint) -> Value {
    let mut o = Map::new();
    o.insert("t_ms".into(), json!(t_ms(p)));
    if let Some(g) = t.geodetic(p.position) {
        o.insert("lat".into(), num(g.lat));
        o.insert("lon".into(), num(g.lon));
    }
    o.insert("east_m".into(), p.position[0].short());
    o.insert("north_m".into(), p.position[1].short());
    o.insert("vel_e_mps".into(), p.velocity[0].short());
    o.insert("vel_n_mps".into(), p.velocity[1].short());
    o.insert("ellipse".into(), ellipse(p));
    o.insert("p_moving".into(), p.p_moving.short());
    Value::Object(o)
}

/// One point of a live track, a line of its own: the point's fields and its channel's
/// `freq_mhz`.
pub fn live_point(t: &Tracks, freq_mhz: Option<f32>, p: &TrackPoint) -> Value {
    let mut v = point(t, p);
    if let Some(m) = v.as_object_mut() {
        m.insert("freq_mhz".into(), freq_mhz.short());
    }
    v
}

/// `{"tracks": [{"freq_mhz", "points": [...]}]}`, and `"untracked"`: why, for a channel with
/// no track.
pub fn json(t: &Tracks) -> Value {
    let tracks: Vec<Value> = t
        .tracks
        .iter()
        .map(|c| {
            let mut v = json!({
                "freq_mhz": c.freq_mhz.short(),
                "points": c.points.iter().map(|p| point(t, p)).collect::<Vec<_>>(),
            });
            if let Some(m) = v.as_object_mut() {
                if let Some(why) = &c.untracked {
                    m.insert("untracked".into(), why.as_str().into());
                }
                if !c.noise.is_empty() {
                    m.insert("stations".into(), c.noise.iter().map(station).collect());
                }
            }
            v
        })
        .collect();
    json!({ "tracks": tracks })
}

/// A DF station's noise on a track: its id, the noise its bearings were given and the one
/// tracked (degrees), their scatter about the track in given sds, whether the noise was
/// estimated, and the class the track took it as from its scatter (none stated).
fn station(s: &StationNoise) -> Value {
    let n = &s.noise;
    json!({
        "id": s.id,
        "given_deg": n.given.to_degrees().short(),
        "noise_deg": n.tracked().to_degrees().short(),
        "scatter": n.scatter.short(),
        "estimated": !s.stated,
        "class_from_scatter": n.array.then_some(DeviceClass::IndoorAoa.name()),
    })
}

/// The CSV header.
pub const CSV_HEADER: &str = "freq_mhz,t_ms,lat,lon,east_m,north_m,vel_e_mps,vel_n_mps,\
                              major_m,minor_m,orientation_deg,p_moving";

/// One point as a CSV line (empty fields for what it lacks).
pub fn csv_line(t: &Tracks, freq_mhz: Option<f32>, p: &TrackPoint) -> String {
    let mut s = String::new();
    let freq = freq_mhz.map_or(String::new(), |f| format!("{f:.4}"));
    let (lat, lon) = t
        .geodetic(p.position)
        .map_or((String::new(), String::new()), |g| {
            (format!("{:.7}", g.lat), format!("{:.7}", g.lon))
        });
    let (major, minor, orient) = p.ellipse().map_or_else(
        || (String::new(), String::new(), String::new()),
        |e| {
            (
                format!("{:.2}", e.major),
                format!("{:.2}", e.minor),
                format!("{:.1}", EllipseReport::from(&e).orientation_deg),
            )
        },
    );
    let _ = write!(
        s,
        "{freq},{},{lat},{lon},{:.2},{:.2},{:.3},{:.3},{major},{minor},{orient},{:.3}",
        t_ms(p),
        p.position[0],
        p.position[1],
        p.velocity[0],
        p.velocity[1],
        p.p_moving
    );
    s
}

/// Every track as CSV: the header, then one line per point.
pub fn csv(t: &Tracks) -> String {
    let mut out = format!("{CSV_HEADER}\n");
    for c in &t.tracks {
        for p in &c.points {
            out.push_str(&csv_line(t, c.freq_mhz, p));
            out.push('\n');
        }
    }
    out
}

/// The tracks as GeoJSON: per channel its line, and each point with its ellipse (RFC 7946);
/// `None` when the tracks are not placed on the earth.
pub fn geojson(t: &Tracks) -> Option<Value> {
    t.frame.as_ref()?;
    let lonlat = |p: [f32; 2]| t.geodetic(p).map(|g| [g.lon, g.lat]);
    let mut features = Vec::new();
    for c in t.tracks.iter().filter(|c| !c.points.is_empty()) {
        let line: Vec<[f64; 2]> = c.points.iter().filter_map(|p| lonlat(p.position)).collect();
        let parts = split_antimeridian(&line);
        let geometry = match parts.as_slice() {
            [one] => json!({"type": "LineString", "coordinates": one}),
            _ => json!({"type": "MultiLineString", "coordinates": parts}),
        };
        features.push(json!({"type": "Feature",
            "properties": {"kind": "track", "freq_mhz": c.freq_mhz},
            "geometry": geometry}));
        for p in &c.points {
            let Some(at) = lonlat(p.position) else {
                continue;
            };
            features.push(json!({"type": "Feature",
                "properties": point(t, p),
                "geometry": {"type": "Point", "coordinates": at}}));
            if let Some(e) = p.ellipse() {
                let ring: Vec<[f64; 2]> = ellipse_ring(p.position, &e)
                    .into_iter()
                    .filter_map(lonlat)
                    .collect();
                if ring.len() > 3 {
                    features.push(json!({"type": "Feature",
                        "properties": {"kind": "ellipse", "t_ms": t_ms(p),
                            "confidence": num(f64::from(e.confidence))},
                        "geometry": polygon_geometry(&ring)}));
                }
            }
        }
    }
    Some(json!({"type": "FeatureCollection", "features": features}))
}

/// KML of the tracks (Google Earth and most GIS tools): per channel a folder with the track
/// line and every point (its time from the track's start, velocity and probability of moving)
/// with its 95 % ellipse. `None` when the tracks are not placed on the earth.
pub fn kml(t: &Tracks) -> Option<String> {
    t.frame.as_ref()?;
    let coords = |g: LatLon| format!("{:.8},{:.8},0", g.lon, g.lat);
    let mut out = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>foxhunt track</name>\n",
    );
    for c in t.tracks.iter().filter(|c| !c.points.is_empty()) {
        let name = c
            .freq_mhz
            .map_or_else(|| "track".to_string(), |f| format!("track {f:.3} MHz"));
        let _ = writeln!(out, "<Folder><name>{name}</name>");
        let line: Vec<String> = c
            .points
            .iter()
            .filter_map(|p| t.geodetic(p.position).map(coords))
            .collect();
        if line.len() > 1 {
            let _ = writeln!(
                out,
                "<Placemark><name>{name}</name><LineString><coordinates>{}</coordinates></LineString></Placemark>",
                line.join(" ")
            );
        }
        for p in &c.points {
            let Some(at) = t.geodetic(p.position) else {
                continue;
            };
            let ring: Vec<String> = p
                .ellipse()
                .map(|e| ellipse_ring(p.position, &e))
                .unwrap_or_default()
                .into_iter()
                .filter_map(|q| t.geodetic(q).map(coords))
                .collect();
            let polygon = if ring.len() > 3 {
                format!(
                    "<Polygon><outerBoundaryIs><LinearRing><coordinates>{}</coordinates></LinearRing></outerBoundaryIs></Polygon>",
                    ring.join(" ")
                )
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "<Placemark><name>t {:.1} s</name><description>velocity {:.2} m/s east, {:.2} m/s north; P(moving) {:.2}</description><MultiGeometry><Point><coordinates>{}</coordinates></Point>{polygon}</MultiGeometry></Placemark>",
                p.t_s,
                p.velocity[0],
                p.velocity[1],
                p.p_moving,
                coords(at)
            );
        }
        out.push_str("</Folder>\n");
    }
    out.push_str("</Document>\n</kml>\n");
    Some(out)
}
