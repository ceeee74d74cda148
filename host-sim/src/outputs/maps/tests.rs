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
