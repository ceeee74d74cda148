//! The `foxhunt` command as a user runs it.

use std::process::Command;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("foxhunt-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Write `text` to `name` in `dir`; its path.
fn scratch_file(dir: &std::path::Path, name: &str, text: impl AsRef<[u8]>) -> String {
    let f = dir.join(name);
    std::fs::write(&f, text).expect("write");
    f.to_str().expect("path").to_string()
}

/// A bundled capture's absolute path (the command runs in a scratch folder).
fn capture(name: &str) -> String {
    format!(
        "{}/../serial-bridge/captures/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The command's standard output as one JSON value per line.
fn json_lines(out: &std::process::Output) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect()
}

/// Run the command in a scratch folder: `locate` writes its maps to the working directory,
/// which must not be the source tree.
fn foxhunt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .current_dir(scratch("cwd"))
        .args(args)
        .output()
        .expect("run foxhunt")
}

#[test]
fn bench_json_has_the_stable_fields() {
    let out = foxhunt(&["bench", "--runs", "4", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let rows = rows.as_array().expect("array");
    assert!(rows.len() >= 9);
    for key in [
        "scenario",
        "method",
        "particles",
        "runs",
        "rmse",
        "rel_x",
        "rel_y",
        "crlb",
        "ratio",
        "time_s",
        "paper",
    ] {
        assert!(rows[0].get(key).is_some(), "missing {key}");
    }
    assert_eq!(rows[0]["scenario"], "aoa-afsa");
    assert_eq!(rows[0]["runs"], 4);
    assert!(rows[0]["paper"].is_string());
}

#[test]
fn bench_runs_a_scenario_file() {
    let dir = scratch("cli");
    let f = scratch_file(
        &dir,
        "drive.toml",
        "name = \"mine\"\nemitter = [800.0, 600.0]\npoints = [[0.0, 0.0], [100.0, 0.0], [200.0, 50.0], [250.0, 150.0]]\nruns = 3\n",
    );
    let out = foxhunt(&["bench", "--scenario-file", &f, "--markdown"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("| mine | ml |"), "{text}");

    let f = scratch_file(
        &dir,
        "drive.toml",
        "emitter = [1.0, 2.0]\nroute = \"loop300\"\nspeed = 3\n",
    );
    let out = foxhunt(&["bench", "--scenario-file", &f]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed"));
}

#[test]
fn unknown_scenario_is_a_one_line_error() {
    let out = foxhunt(&["bench", "--scenario", "nowhere"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown scenario `nowhere`") && err.contains("aoa-afsa"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1);
}

fn sentence(body: &str) -> String {
    let mut s = String::new();
    foxhunt_bridge::nmea::write_sentence(&mut s, body).expect("string");
    s
}

#[test]
fn locate_the_bundled_drive_as_json() {
    let out = foxhunt(&["locate", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for key in [
        "lat", "lon", "east_m", "north_m", "cep50_m", "crlb_m", "method", "used", "rejected",
    ] {
        assert!(r.get(key).is_some(), "missing {key}: {r}");
    }
    for key in ["major_m", "minor_m", "orientation_deg", "confidence"] {
        assert!(r["ellipse"].get(key).is_some(), "missing ellipse.{key}");
    }
    // The sample's emitter is at (1200, 800) m from the first fix; its CRLB is about 51 m.
    let (e, n) = (
        r["east_m"].as_f64().expect("e"),
        r["north_m"].as_f64().expect("n"),
    );
    assert!((e - 1200.0).hypot(n - 800.0) < 250.0, "{r}");
    assert_eq!(r["method"], "ml");
}

#[test]
fn bad_captures_give_one_line_errors_and_exit_1() {
    let dir = scratch("bad");
    let fix = |t: &str, lon: &str| {
        sentence(&format!(
            "GPGGA,{t},4700.0000,N,{lon},E,1,08,1.0,0.0,M,0.0,M,,"
        ))
    };
    let bearing = |t: &str| sentence(&format!("PFOXB,{t},45.0,T,80,433.92"));
    let garbage: Vec<u8> = (0..4000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8 | 0x80)
        .collect();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty", Vec::new(), "empty"),
        ("nofix", bearing("120000.00").into_bytes(), "no GPS fix"),
        (
            "nobearing",
            fix("120000.000", "00800.0000").into_bytes(),
            "no bearing",
        ),
        (
            "onebearing",
            [fix("120000.000", "00800.0000"), bearing("120000.00")]
                .concat()
                .into_bytes(),
            "only one usable bearing",
        ),
        ("garbage", garbage, "no GPS fix"),
    ];
    for (name, bytes, expect) in cases {
        let path = scratch_file(&dir, name, bytes);
        let out = foxhunt(&["locate", &path]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(expect) && err.lines().count() == 1,
            "{name}: {err}"
        );
        assert!(out.stdout.is_empty(), "{name}: printed a fix");
    }
    let out = foxhunt(&["locate", dir.join("missing").to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
    let parallel = [
        fix("120000.000", "00800.0000"),
        bearing("120000.00"),
        fix("120001.000", "00800.0000"),
        bearing("120001.00"),
    ]
    .concat();
    let path = scratch_file(&dir, "stationary", parallel);
    let out = foxhunt(&["locate", &path]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("never moved") || err.contains("parallel"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn frames_prints_one_object_per_frame_then_the_counters() {
    let out = foxhunt(&["frames", &capture("aoa-drive.nmea")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 182 + 1);
    assert_eq!(lines[0]["kind"], "gga");
    assert_eq!(lines[1]["kind"], "rmc");
    assert!(lines[1]["speed_kn"].is_number() && lines[1]["course_deg"].is_number());
    assert_eq!(lines[2]["kind"], "pfoxb");
    for key in ["azimuth_deg", "reference", "quality", "freq_mhz", "time"] {
        assert!(lines[2].get(key).is_some(), "pfoxb.{key}");
    }
    assert_eq!(lines[182]["kind"], "counters");
    assert_eq!(lines[182]["sentences"], 182);
}

#[test]
fn track_names_unknown_anchors() {
    let dir = scratch("track");
    let anchors = scratch_file(
        &dir,
        "other.toml",
        "[[anchor]]\naddr = 0x0001\nx = 0.0\ny = 0.0\n[[anchor]]\naddr = 0x0002\nx = 5.0\ny = 0.0\n[[anchor]]\naddr = 0x0003\nx = 0.0\ny = 5.0\n",
    );
    let out = foxhunt(&["track", &capture("rssi-sim.znp"), "--anchors", &anchors]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no frame from a known anchor") && err.contains("0x0101"),
        "{err}"
    );
    let out = foxhunt(&[
        "track",
        &capture("rssi-sim.znp"),
        "--anchors",
        &capture("rssi-sim.anchors.toml"),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let points: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(points.as_array().map(Vec::len), Some(60));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn locate_reads_a_serial_line_and_updates_the_fix() {
    use serialport::SerialPort;
    use std::io::Write;
    // A pseudo-terminal pair stands in for the USB serial adapter.
    let (mut master, slave) = serialport::TTYPort::pair().expect("pty pair");
    let path = slave.name().expect("slave path");
    // foxhunt opens the device exclusively: let go of the test's own handle first.
    drop(slave);
    let child = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "locate",
            &path,
            "--baud",
            "4800",
            "--quiet-exit",
            "1.5",
            "--json",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run foxhunt");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let bytes = std::fs::read(capture("aoa-drive.nmea")).expect("capture");
    for chunk in bytes.chunks(97) {
        master.write_all(chunk).expect("write");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let out = child.wait_with_output().expect("foxhunt ends");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines = json_lines(&out);
    // An update per read that brought bearings (once a fix exists), then the final fix.
    let used: Vec<u64> = lines
        .iter()
        .map(|l| l["used"].as_u64().expect("used"))
        .collect();
    assert!(used.len() >= 10, "only {} updates", used.len());
    assert!(used.windows(2).all(|w| w[0] <= w[1]), "{used:?}");
    let file = foxhunt(&["locate", &capture("aoa-drive.nmea"), "--json"]);
    let from_file: serde_json::Value = serde_json::from_slice(&file.stdout).expect("JSON");
    let last = lines.last().expect("final fix");
    assert_eq!(last["lat"], from_file["lat"]);
    assert_eq!(last["used"], 60);
}
