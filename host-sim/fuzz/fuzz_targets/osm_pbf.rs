//! Arbitrary bytes as an OSM PBF extract: the blob reader on its own, then the whole road
//! graph from a scratch `.osm.pbf` file. An element list or one line of error, never a panic.
#![no_main]
use foxhunt_sim::inputs::osm_pbf::PbfReader;
use foxhunt_sim::inputs::roads::RoadGraph;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scratch() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| {
        std::env::temp_dir().join(format!("foxhunt-fuzz-{}.osm.pbf", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let mut elements = 0u64;
    if let Err(e) = PbfReader::new(data, "fuzz").read_all(|_| elements += 1) {
        let line = e.to_string();
        assert!(!line.is_empty() && !line.contains('\n'), "{line:?}");
    }
    std::fs::write(scratch(), data).expect("scratch file");
    if let Err(e) = RoadGraph::load(scratch()) {
        assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    }
});
