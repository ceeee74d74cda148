//! Fuzzing of the side-file readers (anchors, calibration, scenario files, OSM XML and PBF
//! road extracts): any bytes, and valid files with bytes flipped, cut or inserted, give a
//! value or one line of error, never a panic. The case count is proptest's (`PROPTEST_CASES`
//! runs them longer).

use foxhunt_sim::inputs::calibration::Calibration;
use foxhunt_sim::inputs::roads::RoadGraph;
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::track::indoor::AnchorsFile;
use proptest::prelude::*;
use std::path::PathBuf;

mod common;

const ANCHORS: &str = include_str!("../../serial-bridge/captures/rssi-sim.anchors.toml");

const CALIBRATION: &str = "offset_deg = 4.0\noffset_sd_deg = 0.5\nnoise_deg = 1.0\n\
    bearings = 60\nrejected = 0\ntransmitter = [47.007, 8.0176]\n";

/// A calibration whose drive turned: the direction-dependent error's table with its sd.
const CALIBRATION_DIRECTION: &str = "offset_deg = -2.5\noffset_sd_deg = 0.12\nnoise_deg = 2.0\n\
    bearings = 480\nrejected = 2\ndirection_span = 0.47\n\
    direction_deg = [3.1, -1.2, 0.4, 2.2]\ndirection_error_deg = 0.15\n\
    transmitter = [47.007, 8.0176]\n";

const SCENARIO: &str = "name = \"my-drive\"\nemitter = [1200.0, 800.0]\nroute = \"loop300\"\n\
    bearing_sigma_deg = 1.117\nwild_fraction = 0.0\nprocess_var = 1.0\nparticles = 100\n\
    runs = 100\nseed = 1\n";

/// An edit of a valid file: flip a byte, cut the file, or insert bytes.
#[derive(Debug, Clone)]
enum Edit {
    Flip(usize, u8),
    Cut(usize),
    Insert(usize, Vec<u8>),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Flip(i, b)),
        any::<usize>().prop_map(Edit::Cut),
        (
            any::<usize>(),
            proptest::collection::vec(any::<u8>(), 1..16)
        )
            .prop_map(|(i, b)| Edit::Insert(i, b)),
    ];
    proptest::collection::vec(edit, 1..6)
}

fn apply(valid: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut v = valid.to_vec();
    for e in edits {
        let at = |i: usize, n: usize| if n == 0 { 0 } else { i % n };
        match e {
            Edit::Flip(i, b) if !v.is_empty() => {
                let k = at(*i, v.len());
                v[k] ^= b | 1;
            }
            Edit::Flip(..) => {}
            Edit::Cut(i) => v.truncate(at(*i, v.len() + 1)),
            Edit::Insert(i, b) => {
                let k = at(*i, v.len() + 1);
                v.splice(k..k, b.iter().copied());
            }
        }
    }
    v
}

/// One line of error, or a value: what every reader must give.
fn one_line<T>(r: Result<T, String>) -> Result<(), TestCaseError> {
    if let Err(e) = r {
        prop_assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    }
    Ok(())
}

/// Each TOML reader on `text`.
fn toml_readers(text: &str) -> Result<(), TestCaseError> {
    one_line(AnchorsFile::from_toml(text))?;
    one_line(Calibration::from_toml(text))?;
    one_line(Scenario::from_toml(text))?;
    Ok(())
}

/// A scratch file for the road readers, which read paths.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("foxhunt-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

/// The street grid's OSM XML, written once (the tests run at once).
fn grid() -> Vec<u8> {
    static GRID: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    GRID.get_or_init(|| {
        let p = scratch("grid.osm");
        common::grid_osm(&p);
        std::fs::read(&p).expect("grid")
    })
    .clone()
}

const PBF: &[u8] = include_bytes!("data/osm/test.osm.pbf");

proptest! {
    #[test]
    fn toml_side_files_never_panic_on_any_text(text in ".{0,400}") {
        toml_readers(&text)?;
    }

    #[test]
    fn toml_side_files_never_panic_on_edited_files(e in edits(), which in 0..4usize) {
        let valid = [ANCHORS, CALIBRATION, SCENARIO, CALIBRATION_DIRECTION][which];
        let text = String::from_utf8_lossy(&apply(valid.as_bytes(), &e)).into_owned();
        toml_readers(&text)?;
    }

    #[test]
    fn road_extracts_never_panic(e in edits(), pbf in any::<bool>(), raw in proptest::collection::vec(any::<u8>(), 0..64)) {
        let (valid, name) = if pbf { (PBF.to_vec(), "fuzz.osm.pbf") } else { (grid(), "fuzz.osm") };
        let path = scratch(&format!("{}-{name}", std::thread::current().name().unwrap_or("t").replace("::", "-")));
        // Edited valid files, and bare bytes.
        for bytes in [apply(&valid, &e), raw.clone()] {
            std::fs::write(&path, &bytes).expect("write");
            one_line(RoadGraph::load(&path))?;
        }
    }
}

#[test]
fn the_valid_side_files_read() {
    AnchorsFile::from_toml(ANCHORS).expect("anchors");
    Calibration::from_toml(CALIBRATION).expect("calibration");
    let turned = Calibration::from_toml(CALIBRATION_DIRECTION).expect("calibration");
    assert!(turned.direction().is_some_and(|d| d.sd > 0.0));
    // Absurd or broken harmonics are one line naming the key.
    for (bad, key) in [
        ("direction_deg = [20.0, 0.0, 0.4, 2.2]", "direction_deg"),
        ("direction_deg = [nan, -1.2, 0.4, 2.2]", "direction_deg"),
        ("direction_deg = [3.1, -1.2, inf, 2.2]", "direction_deg"),
        (
            "direction_error_deg = 0.15\ndirection_error_deg = 0.15",
            "duplicate",
        ),
    ] {
        let text = CALIBRATION_DIRECTION.replace("direction_deg = [3.1, -1.2, 0.4, 2.2]", bad);
        let e = Calibration::from_toml(&text).expect_err(bad);
        assert!(e.contains(key) && !e.contains('\n'), "{bad}: {e}");
    }
    for (from, bad, key) in [
        (
            "direction_error_deg = 0.15",
            "direction_error_deg = nan",
            "direction_error_deg",
        ),
        (
            "direction_error_deg = 0.15",
            "direction_error_deg = 0.0",
            "direction_error_deg",
        ),
        (
            "direction_error_deg = 0.15",
            "direction_error_deg = 40.0",
            "direction_error_deg",
        ),
        ("direction_error_deg = 0.15", "", "come together"),
        (
            "direction_span = 0.47",
            "direction_span = -1.0",
            "direction_span",
        ),
    ] {
        let text = CALIBRATION_DIRECTION.replace(from, bad);
        let e = Calibration::from_toml(&text).expect_err(bad);
        assert!(e.contains(key) && !e.contains('\n'), "{bad}: {e}");
    }
    Scenario::from_toml(SCENARIO).expect("scenario");
    let p = scratch("valid.osm");
    std::fs::write(&p, grid()).expect("write");
    RoadGraph::load(&p).expect("XML grid");
    let p = scratch("valid.osm.pbf");
    std::fs::write(&p, PBF).expect("write");
    // The PBF test file's ways may or may not be drivable: it must read, graph or not.
    let r = RoadGraph::load(&p);
    assert!(
        r.as_ref().map_or_else(|e| !e.contains("not OSM"), |_| true),
        "{r:?}"
    );
}
