//! The moving-emitter tracker follows a drone on the emulated Cortex-M4F: the step-bench image's
//! `track-256-step` (the host's default tracker, `sir-robust` with four stations' offsets
//! Rao-Blackwellised, at N = 256; `serial-bridge/src/bin/step-bench/track.rs`) over 300 s of a
//! drone crossing an 8 km square east at 12 m/s, four corner stations each reporting a bearing
//! ten times a second with 2 degree noise and unknown 2 degree offsets, RUNS seeds.
//!
//! Bars, and why: the host's tracker on the same geometry at 1 Hz is 270-300 m rmse (N = 1000
//! and 200, docs/src/tracking.md), about twice the PCRB of 124 m, the offsets' doubt
//! dominating (2 degrees at 4 km is 140 m). Measured here over 8 seeds: 227 m pooled (304 m,
//! 107-583 m per run, with the first cloud at its bearings' own doubt). A tracker that stopped following would be off by the drone's travel, 2 km on
//! average over the counted 270 s. The pooled bar, 500 m, is the host's N = 200 figure (306 m)
//! with room for the smaller cloud and the eight runs' spread (per-run sd about 130 m: a
//! standard error near 50 m, so the measured figure sits nearly four of them below); each run's bar,
//! 1 500 m, fails only a run that lost the drone.

use std::path::PathBuf;
use std::process::Command;

const RUNS: u64 = 8;
/// 300 s at 10 Hz.
const STEPS: usize = 3000;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The step-bench image, built in the firmware tests' own target directory.
fn image() -> PathBuf {
    let target = workspace().join("target/firmware-test");
    let build = Command::new("cargo")
        .current_dir(workspace())
        .env("CARGO_TARGET_DIR", &target)
        .args([
            "build",
            "-q",
            "--profile",
            "firmware",
            "-p",
            "foxhunt-bridge",
        ])
        .args([
            "--bin",
            "foxhunt-step-bench",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .status()
        .expect("cargo runs");
    assert!(build.success(), "the step-bench image did not build");
    target.join("thumbv7em-none-eabihf/firmware/foxhunt-step-bench")
}

/// The image's report of one run: (rmse after the warm-up, state bytes, step stack bytes).
fn run(elf: &PathBuf, seed: u64) -> (f64, u64, u64) {
    let out = Command::new("timeout")
        .arg("600")
        .arg("qemu-system-arm")
        .args([
            "-machine",
            "netduinoplus2",
            "-nographic",
            "-semihosting-config",
        ])
        .arg(format!(
            "enable=on,target=native,arg=step-bench,arg=track-256-step,arg={STEPS},arg={seed}"
        ))
        .arg("-kernel")
        .arg(elf)
        .output()
        .expect("qemu-system-arm not found: apt-get install qemu-system-arm (.ci/run does)");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "seed {seed}: the image failed:\n{text}"
    );
    // "state B B, step stack S B, D 13, rmse R m after 30 s"
    let line = text
        .lines()
        .find(|l| l.starts_with("state "))
        .unwrap_or_else(|| panic!("seed {seed}: no report:\n{text}"));
    let number = |after: &str| -> f64 {
        line.split(after)
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("seed {seed}: cannot read {after:?} in {line}"))
    };
    (
        number("rmse "),
        number("state ") as u64,
        number("step stack ") as u64,
    )
}

#[test]
fn the_mcu_tracker_follows_a_moving_emitter() {
    let elf = image();
    let mut squares = 0.0;
    let mut failed = Vec::new();
    for seed in 1..=RUNS {
        let (rmse, state, stack) = run(&elf, seed);
        println!("seed {seed}: rmse {rmse:.0} m, state {state} B, step stack {stack} B");
        squares += rmse * rmse;
        if !(rmse < 1500.0) {
            failed.push(format!("seed {seed}: rmse {rmse:.0} m, lost the drone"));
        }
    }
    let pooled = (squares / RUNS as f64).sqrt();
    println!("pooled rmse over {RUNS} runs: {pooled:.0} m");
    if !(pooled < 500.0) {
        failed.push(format!("pooled rmse {pooled:.0} m above 500 m"));
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
