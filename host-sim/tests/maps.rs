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
    // Track, rays, cloud, ellipse, arrow and bar cover well over 1 % of the 640 000 pixels.
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
