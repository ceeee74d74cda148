//! `locate --method unit` is the DF unit's computation: the bundled drive fed to the firmware's
//! `Unit` (the code the MCU image runs, tests/tests/firmware_qemu.rs) record by record in the
//! capture's order gives, bit for bit, the position, ellipse and noise `locate --method unit`
//! reports.

use foxhunt_bridge::unit::{Port, Unit};
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

#[test]
fn locate_by_the_unit_method_is_what_the_unit_says() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures/aoa-drive.nmea");
    let capture = std::fs::read(&path).expect("bundled drive");
    let mut unit = Unit::default();
    let mut port = Port::Gps;
    let mut out = |_: &[u8]| true;
    for record in capture.split_inclusive(|&b| b == b'\n') {
        port = Port::of_record(record).unwrap_or(port);
        unit.feed(port, record, &mut out);
    }
    for p in Port::ALL {
        unit.idle(p, &mut out);
    }
    let fix = *unit.last_fix().expect("the unit fixed");
    assert!(fix.status.has_position(), "{fix:?}");

    let run = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(["locate", "--method", "unit", "--json"])
        .arg(&path)
        .output()
        .expect("foxhunt runs");
    assert_eq!(run.status.code(), Some(0), "{run:?}");
    let json: Value = serde_json::from_slice(&run.stdout).expect("JSON");
    let e = &json["emitters"][0];
    // JSON carries each f32 as its shortest decimal, which reads back as the same f32.
    let f = |v: &Value| v.as_f64().expect("number") as f32;
    let host = [
        f(&e["east_m"]),
        f(&e["north_m"]),
        f(&e["ellipse"]["major_m"]),
        f(&e["ellipse"]["minor_m"]),
        f(&e["cep50_m"]),
        f(&e["sigma_deg"]),
    ];
    let mcu = [
        fix.position[0],
        fix.position[1],
        fix.major,
        fix.minor,
        fix.cep50,
        fix.sigma.to_degrees(),
    ];
    eprintln!("unit {mcu:?}\nhost {host:?}");
    assert_eq!(host, mcu);
    assert_eq!(e["used"].as_u64(), Some(u64::from(fix.window)));
}
