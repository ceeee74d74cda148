//! Test fixtures shared by the integration tests.
// Each test file compiles this module alone and uses only some of the fixtures.
#![allow(dead_code)]

pub mod broker;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::Child;
use std::sync::mpsc::{Receiver, channel};

/// A drive's capture through the DF unit's own code (the firmware's `Unit`, on the host): the
/// bytes its user port sends (its `$PFOXF` fixes, `$PFOXS` and `$PFOXL` health).
pub fn unit_output(drive: &[u8]) -> Vec<u8> {
    use foxhunt_bridge::unit::{Port, Unit, UnitConfig};
    let mut unit = Unit::new(UnitConfig::default());
    let mut out = Vec::new();
    for line in drive.split_inclusive(|b| *b == b'\n') {
        let port = Port::of_record(line).unwrap_or(Port::Gps);
        unit.feed(port, line, &mut |s| {
            out.extend_from_slice(s);
            true
        });
    }
    out
}

/// An OSM XML street grid of about 300 m around the sample drive's area (origin 47 N, 8 E).
pub fn grid_osm(path: &Path) {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n");
    let (lat0, lon0, dlat, dlon) = (46.995, 7.99, 0.0027, 0.004);
    let (rows, cols) = (10, 12);
    for j in 0..rows {
        for i in 0..cols {
            let id = 1 + j * cols + i;
            s += &format!(
                "  <node id=\"{id}\" lat=\"{:.6}\" lon=\"{:.6}\"/>\n",
                lat0 + dlat * j as f64,
                lon0 + dlon * i as f64
            );
        }
    }
    let mut way = 1000;
    for j in 0..rows {
        way += 1;
        s += &format!("  <way id=\"{way}\">");
        for i in 0..cols {
            s += &format!("<nd ref=\"{}\"/>", 1 + j * cols + i);
        }
        s += "<tag k=\"highway\" v=\"residential\"/></way>\n";
    }
    for i in 0..cols {
        way += 1;
        s += &format!("  <way id=\"{way}\">");
        for j in 0..rows {
            s += &format!("<nd ref=\"{}\"/>", 1 + j * cols + i);
        }
        s += "<tag k=\"highway\" v=\"tertiary\"/></way>\n";
    }
    s += "</osm>\n";
    std::fs::write(path, s).expect("write the extract");
}

/// `foxhunt ARGS` started with its standard input, output and error piped.
pub fn piped(args: &[&str]) -> Child {
    std::process::Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run foxhunt")
}

/// `foxhunt serve ARGS` on any free port, unpaced, once its input has ended (the server
/// stays until the caller stops it): the child and its address, `HOST:PORT`.
pub fn serve_ended<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (Child, String) {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(["serve", "--addr", "127.0.0.1:0", "--pace", "0"])
        .args(args)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("start foxhunt serve");
    let mut addr = None;
    for l in BufReader::new(child.stderr.take().expect("its stderr")).lines() {
        let l = l.expect("a line of its stderr");
        if let Some(a) = l.strip_prefix("foxhunt serve: http://") {
            addr = Some(a.trim_end_matches('/').to_string());
        }
        if l.contains("input ended") {
            break;
        }
    }
    (child, addr.expect("serve printed its address"))
}

/// The lines of `child`'s standard output as they come, read on a thread of their own (a live
/// command prints while its input is still open).
pub fn line_reader(child: &mut Child) -> Receiver<String> {
    lines(child.stdout.take().expect("stdout piped"))
}

/// The lines of `r` as they come, read on a thread of their own.
pub fn lines(r: impl std::io::Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(r).lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    rx
}

/// `foxhunt ARGS` run to its end, which must succeed: each line of its standard output as JSON
/// (a live `locate --json` prints one object per update).
pub fn json_lines(args: &[String]) -> Vec<serde_json::Value> {
    json_lines_from(args, None).0
}

/// [`json_lines`] with standard input read from `stdin` (none: nothing), and what the run
/// said on standard error.
pub fn json_lines_from<S: AsRef<std::ffi::OsStr>>(
    args: &[S],
    stdin: Option<&Path>,
) -> (Vec<serde_json::Value>, String) {
    let input = match stdin {
        Some(p) => std::process::Stdio::from(std::fs::File::open(p).expect("standard input")),
        None => std::process::Stdio::null(),
    };
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(args)
        .stdin(input)
        .output()
        .expect("run foxhunt");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    let lines = BufReader::new(&out.stdout[..])
        .lines()
        .map(|l| serde_json::from_str(&l.expect("line")).expect("JSON"))
        .collect();
    (lines, err)
}

/// `foxhunt simulate --condition CONDITION [--run RUN] --force --out OUT`, which must
/// succeed: the stations' records at `out`, their stations file and the emitter's true track
/// beside it (`*.stations.toml`, `*.truth.csv`).
pub fn simulate(condition: &str, run: Option<usize>, out: &Path) {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_foxhunt"));
    c.args(["simulate", "--condition", condition, "--force", "--out"])
        .arg(out);
    if let Some(r) = run {
        c.args(["--run", &r.to_string()]);
    }
    let sim = c.output().expect("run foxhunt simulate");
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
}

/// A track point's (`track --json`) distance from `truth` (east, north, metres) and whether
/// its 95 % ellipse holds it (false when the point has none).
pub fn error_and_held(p: &serde_json::Value, truth: [f64; 2]) -> (f64, bool) {
    let n = |k: &str| p[k].as_f64().expect(k);
    let d = [truth[0] - n("east_m"), truth[1] - n("north_m")];
    let e = &p["ellipse"];
    let held = e.is_object() && {
        let (a, b) = (
            e["major_m"].as_f64().expect("major"),
            e["minor_m"].as_f64().expect("minor"),
        );
        let o = e["orientation_deg"]
            .as_f64()
            .expect("orientation")
            .to_radians();
        // The major axis clockwise from north: (east, north) = (sin, cos).
        let along = d[0] * o.sin() + d[1] * o.cos();
        let across = d[0] * o.cos() - d[1] * o.sin();
        (along / a).powi(2) + (across / b).powi(2) <= 1.0
    };
    (d[0].hypot(d[1]), held)
}
