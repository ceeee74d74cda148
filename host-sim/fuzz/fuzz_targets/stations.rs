//! Arbitrary bytes as a stations file (`--stations`), read from a scratch file as the command
//! reads it: a network or one line of error, never a panic.
#![no_main]
use foxhunt_sim::inputs::stations::Network;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scratch() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| {
        std::env::temp_dir().join(format!("foxhunt-fuzz-{}.stations.toml", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    std::fs::write(scratch(), data).expect("scratch file");
    if let Err(e) = Network::load(scratch()) {
        assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    }
});
