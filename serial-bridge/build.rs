//! The firmware image links with cortex-m-rt's `link.x` and the workspace's `memory.x`; host
//! builds link nothing extra. The firmware image also links defmt's `defmt.x`.

use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let memory = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../memory.x");
    if let Err(e) = std::fs::copy(&memory, out.join("memory.x")) {
        panic!("cannot copy {}: {e}", memory.display());
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        // Only the firmware image logs through defmt (the step bench prints over semihosting).
        println!("cargo:rustc-link-arg-bin=foxhunt-firmware=-Tdefmt.x");
    }
}
