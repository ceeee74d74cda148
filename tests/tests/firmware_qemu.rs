//! The firmware image on the emulated MCU agrees with the host bit for bit.
//!
//! Builds `foxhunt-firmware` for thumbv7em-none-eabihf (in its own target directory, so it
//! does not wait on the lock of the `cargo test` that runs this), runs it on QEMU's
//! netduinoplus2 board (STM32F405, Cortex-M4F) under a timeout, and compares what it prints
//! with the same replay run here on the host: the same capture, seed and filter.

use foxhunt_bridge::BridgeConfig;
use foxhunt_bridge::replay::{replay, write_summary};
use std::path::PathBuf;
use std::process::Command;

const CAPTURE: &[u8] = include_bytes!("../../serial-bridge/captures/aoa-drive.nmea");

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn firmware_fix_equals_the_host_fix_bit_for_bit() {
    let qemu = Command::new("qemu-system-arm").arg("--version").output();
    assert!(
        qemu.is_ok_and(|o| o.status.success()),
        "qemu-system-arm not found: apt-get install qemu-system-arm (.ci/run does)"
    );
    let target_dir = workspace().join("target/firmware-test");
    let build = Command::new(env!("CARGO"))
        .current_dir(workspace())
        .env("CARGO_TARGET_DIR", &target_dir)
        .args([
            "build",
            "--profile",
            "firmware",
            "-p",
            "foxhunt-bridge",
            "--bin",
            "foxhunt-firmware",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .status()
        .expect("cargo runs");
    assert!(build.success(), "firmware build failed");
    let image = target_dir.join("thumbv7em-none-eabihf/firmware/foxhunt-firmware");
    // The image reads the drive from this host file over semihosting, as it would from a UART.
    let capture = workspace().join("serial-bridge/captures/aoa-drive.nmea");
    let run = Command::new("timeout")
        .args([
            "120",
            "qemu-system-arm",
            "-machine",
            "netduinoplus2",
            "-nographic",
        ])
        .arg("-semihosting-config")
        .arg(format!(
            "enable=on,target=native,arg=foxhunt-firmware,arg={}",
            capture.display()
        ))
        .arg("-kernel")
        .arg(&image)
        .output()
        .expect("qemu runs");
    let mcu = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "image failed ({:?}): {mcu}",
        run.status
    );

    let config = BridgeConfig {
        sigma_rad: foxhunt_core::canonical::AOA_SIGMA,
        ..BridgeConfig::default()
    };
    // Fed one byte at a time and in 64-byte reads, as the image does: same answer.
    let host = replay::<100>(CAPTURE, 1, config, 1, usize::MAX);
    assert_eq!(host, replay::<100>(CAPTURE, 64, config, 1, usize::MAX));
    let mut expected = String::new();
    write_summary(&host, &mut expected).expect("string");
    let mcu_summary: String = mcu
        .lines()
        .filter(|l| !l.starts_with("stack "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(mcu_summary, expected);
    eprintln!("{mcu}");

    // And the fix is a fix: aoa-drive's emitter is at (1200, 800) in the frame whose origin
    // is the first GPS fix; its CRLB is 51 m, so 4 sigma is about 200 m.
    let ml = host.ml.expect("ML fix");
    let err = (ml.position[0] - 1200.0).hypot(ml.position[1] - 800.0);
    assert!(err < 200.0, "ML fix {err} m from the emitter");
    assert_eq!(host.bearings, 60);
}
