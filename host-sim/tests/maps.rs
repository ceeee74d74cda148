//! The map files of `foxhunt locate`: GeoJSON by RFC 7946's rules, KML well formed, and an
//! SVG that a real renderer draws.

use std::process::Command;

fn locate_maps(dir: &std::path::Path, method: &str) -> (serde_json::Value, String, String) {
    let (g, k, s) = (
        dir.join("fix.geojson"),
        dir.join("fix.kml"),
        dir.join("fix.svg"),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "locate",
            "../serial-bridge/captures/aoa-drive.nmea",
            "--method",
            method,
        ])
        .args([
            "--geojson",
            g.to_str().expect("path"),
            "--kml",
            k.to_str().expect("path"),
        ])
        .args(["--svg", s.to_str().expect("path")])
        .output()
        .expect("run foxhunt");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |p: &std::path::Path| std::fs::read_to_string(p).expect("map file");
    (
        serde_json::from_str(&read(&g)).expect("GeoJSON is JSON"),
        read(&k),
        read(&s),
    )
}

#[test]
fn geojson_kml_and_svg_are_valid_and_drawn() {
    let dir = std::env::temp_dir().join(format!("foxhunt-maps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let (geo, kml, svg) = locate_maps(&dir, "ml");
    // A batch fix draws no particles; the legend names what is drawn, the method included.
    assert!(
        !svg.contains("r=\"1.2\""),
        "an ML fix drew a particle cloud"
    );
    for words in [
        "vehicle route",
        "bearings (60)",
        "fix (ml)",
        "95 % ellipse, semi-axes",
    ] {
        assert!(svg.contains(words), "legend lacks `{words}`");
    }
    labels_inside(&svg, 800.0);
    let (_, _, sir) = locate_maps(&dir, "sir");
    assert!(sir.contains("r=\"1.2\"") && sir.contains("particles (1000)"));

    // RFC 7946: a FeatureCollection; positions are [longitude, latitude] in range; linear
    // rings are closed with four or more positions.
    assert_eq!(geo["type"], "FeatureCollection");
    let features = geo["features"].as_array().expect("features");
    let kinds: Vec<&str> = features
        .iter()
        .filter_map(|f| f["properties"]["kind"].as_str())
        .collect();
    for k in ["emitter", "ellipse", "track", "bearing"] {
        assert!(kinds.contains(&k), "no {k} feature");
    }
    let check = |p: &serde_json::Value| {
        let (lon, lat) = (p[0].as_f64().expect("lon"), p[1].as_f64().expect("lat"));
        // The sample drive is at 47 N, 8 E: longitude first, or these swap.
        assert!(
            (lon - 8.0).abs() < 0.2 && (lat - 47.0).abs() < 0.2,
            "[{lon}, {lat}]"
        );
    };
    for f in features {
        let g = &f["geometry"];
        match g["type"].as_str().expect("geometry type") {
            "Point" => check(&g["coordinates"]),
            "LineString" => g["coordinates"]
                .as_array()
                .expect("line")
                .iter()
                .for_each(check),
            "Polygon" => {
                for ring in g["coordinates"].as_array().expect("rings") {
                    let r = ring.as_array().expect("ring");
                    assert!(r.len() >= 4);
                    assert_eq!(r.first(), r.last(), "ring not closed");
                    r.iter().for_each(check);
                }
            }
            other => panic!("unexpected geometry {other}"),
        }
    }

    assert!(kml.starts_with("<?xml") && kml.trim_end().ends_with("</kml>"));
    assert_eq!(
        kml.matches("<Placemark>").count(),
        kml.matches("</Placemark>").count()
    );

    // Render with resvg: the image must carry the drawing, not just the white background.
    let tree =
        resvg::usvg::Tree::from_str(&svg, &resvg::usvg::Options::default()).expect("SVG parses");
    let mut pixmap = resvg::tiny_skia::Pixmap::new(800, 800).expect("pixmap");
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::identity(),
        &mut pixmap.as_mut(),
    );
    let inked = pixmap
        .pixels()
        .iter()
        .filter(|p| p.red() < 200 || p.green() < 200 || p.blue() < 200)
        .count();
    // Track, rays, ellipse, legend, arrow and bar cover well over 1 % of the 640 000 pixels.
    assert!(inked > 6_400, "only {inked} pixels drawn");
    // Red ellipse/emitter pixels exist (the fill colour #c0392b).
    assert!(
        pixmap
            .pixels()
            .iter()
            .any(|p| p.red() > 150 && p.green() < 100 && p.blue() < 100)
    );
    pixmap.save_png(dir.join("fix.png")).expect("png");
    eprintln!(
        "rendered {} ({inked} pixels inked)",
        dir.join("fix.png").display()
    );
}

/// Every text element's anchor lies inside the picture, and one that starts near the right
/// edge is anchored at its end (so it runs leftward, into the picture).
fn labels_inside(svg: &str, size: f32) {
    for t in svg.split("<text ").skip(1) {
        let attr = |name: &str| -> Option<String> {
            let start = t.find(&format!("{name}=\""))? + name.len() + 2;
            Some(t[start..].split('"').next()?.to_string())
        };
        let x: f32 = attr("x").and_then(|v| v.parse().ok()).expect("x");
        let y: f32 = attr("y").and_then(|v| v.parse().ok()).expect("y");
        assert!(
            (0.0..=size).contains(&x) && (0.0..=size).contains(&y),
            "<text {t}"
        );
        let text = t
            .split('>')
            .nth(1)
            .unwrap_or_default()
            .split('<')
            .next()
            .unwrap_or_default();
        let width = 7.0 * text.chars().count() as f32;
        if attr("text-anchor").as_deref() != Some("end") {
            assert!(
                x + width <= size + 1.0,
                "runs off the right edge: <text {t}"
            );
        }
    }
}

#[test]
fn the_track_svg_has_a_legend_and_a_scale_bar() {
    let dir = std::env::temp_dir().join(format!("foxhunt-track-svg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let svg = dir.join("track.svg");
    let out = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "track",
            "../serial-bridge/captures/rssi-sim.znp",
            "--anchors",
            "../serial-bridge/captures/rssi-sim.anchors.toml",
            "--svg",
            svg.to_str().expect("path"),
        ])
        .output()
        .expect("run foxhunt");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).expect("svg");
    for words in [
        "estimated track (60 steps)",
        "anchor (short address)",
        "room",
        " m</text>",
    ] {
        assert!(text.contains(words), "track SVG lacks `{words}`");
    }
    labels_inside(&text, 600.0);
    resvg::usvg::Tree::from_str(&text, &resvg::usvg::Options::default()).expect("SVG parses");
}

#[test]
fn geojson_lines_are_cut_at_the_antimeridian() {
    // A drive that starts just west of 180 E heads east across it.
    let dir = std::env::temp_dir().join(format!("foxhunt-antimeridian-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let cap = dir.join("dateline.nmea");
    let geo = dir.join("dateline.geojson");
    let sim = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "simulate",
            "--origin",
            "10.0,179.995",
            "--out",
            cap.to_str().expect("path"),
        ])
        .output()
        .expect("run foxhunt");
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let out = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .arg("locate")
        .arg(&cap)
        .args(["--geojson", geo.to_str().expect("path")])
        .output()
        .expect("run foxhunt");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&geo).expect("geojson")).expect("JSON");
    let mut multi = 0;
    for f in g["features"].as_array().expect("features") {
        let geom = &f["geometry"];
        let lines: Vec<&serde_json::Value> = match geom["type"].as_str().expect("type") {
            "LineString" => vec![&geom["coordinates"]],
            "MultiLineString" => {
                multi += 1;
                geom["coordinates"]
                    .as_array()
                    .expect("parts")
                    .iter()
                    .collect()
            }
            _ => continue,
        };
        for line in lines {
            let pts = line.as_array().expect("points");
            for w in pts.windows(2) {
                let (a, b) = (
                    w[0][0].as_f64().expect("lon"),
                    w[1][0].as_f64().expect("lon"),
                );
                assert!(
                    (a - b).abs() < 180.0,
                    "a segment crosses the antimeridian: {line}"
                );
                assert!((-180.0..=180.0).contains(&a), "{line}");
            }
        }
    }
    assert!(multi > 0, "nothing was cut: the drive does cross 180 E");
}
