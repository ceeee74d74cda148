use super::geojson::polygon_geometry;
use super::svg::nice_length;
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

#[test]
fn an_open_range_is_drawn_as_a_wedge() {
    // Six 15 degree bearings on 300 m: no fix but a region, which the maps draw as a wedge
    // from the observers' centroid out past the drive (unbounded).
    let (bytes, _) = crate::runs::field::capture(
        crate::runs::field::Condition::OpenNoisyFew,
        0,
        crate::runs::simulate::DEFAULT_ORIGIN,
    )
    .expect("capture");
    let d = crate::inputs::capture::decode(&bytes, Default::default(), false);
    let no_fix = crate::locate::locate_answer(&d, &Default::default()).expect_err("no fix");
    let l = no_fix.located.expect("a region");
    let g = geojson(&l, &d);
    let kinds: Vec<&str> = g["features"]
        .as_array()
        .expect("features")
        .iter()
        .filter_map(|f| f["properties"]["kind"].as_str())
        .collect();
    assert!(
        kinds.contains(&"region") && kinds.contains(&"wedge"),
        "{kinds:?}"
    );
    let wedge = g["features"]
        .as_array()
        .expect("features")
        .iter()
        .find(|f| f["properties"]["kind"] == "wedge")
        .expect("a wedge");
    assert_eq!(wedge["properties"]["unbounded"], true);
    assert_eq!(wedge["geometry"]["type"], "Polygon");
    let k = kml(&l, &d);
    assert!(k.contains("<name>region: 95 % wedge</name>"), "{k}");
}
