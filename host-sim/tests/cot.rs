//! `locate --cot` as a TAK client receives it: the events are sent over loopback to a listener
//! that decodes each with takproto (TAK's protocol library; `.ci/run` installs it), and what
//! TAK would draw is checked against the fix the same run printed: the emitter's point and its
//! 95 % ellipse, each station and its latest line of bearing.

mod common;

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};

const LISTENER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/tak/listen.py");

/// A takproto listener on a loopback port (`udp COUNT` or `tcp`), its output and the port.
fn listener(args: &[&str]) -> (Child, BufReader<ChildStdout>, u16) {
    let mut child = Command::new("python3")
        .arg(LISTENER)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 runs (.ci/run installs it with takproto)");
    let mut out = BufReader::new(child.stdout.take().expect("stdout"));
    let mut first = String::new();
    out.read_line(&mut first).expect("the listener's port");
    let Ok(port) = first.trim().parse() else {
        let err = child.wait_with_output().expect("listener").stderr;
        panic!(
            "the TAK listener did not start (is takproto installed? `pip install takproto`): {}",
            String::from_utf8_lossy(&err)
        )
    };
    (child, out, port)
}

/// The events the listener decoded, once it ends.
fn received((mut child, out, _): (Child, BufReader<ChildStdout>, u16)) -> Vec<Value> {
    let events = out
        .lines()
        .map(|l| serde_json::from_str(&l.expect("line")).expect("JSON"))
        .collect();
    let status = child.wait().expect("listener");
    assert!(status.success(), "the listener failed: {status}");
    events
}

fn by_uid<'a>(events: &'a [Value], uid: &str) -> &'a Value {
    events
        .iter()
        .find(|e| e["uid"] == uid)
        .unwrap_or_else(|| panic!("no event {uid} in {events:#?}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

/// An XML attribute's value in takproto's `xmlDetail` (the elements it has no field for).
fn attr(detail: &str, element: &str, name: &str) -> f64 {
    let at = detail
        .find(&format!("<{element} "))
        .unwrap_or_else(|| panic!("no <{element}> in {detail}"));
    let rest = &detail[at..];
    let key = format!("{name}=\"");
    let start = rest.find(&key).expect("attribute") + key.len();
    let end = start + rest[start..].find('"').expect("closing quote");
    rest[start..end].parse().expect("a number")
}

/// Every `<link point="lat,lon"/>` of a line.
fn points(detail: &str) -> Vec<[f64; 2]> {
    detail
        .split("<link point=\"")
        .skip(1)
        .map(|p| {
            let text = &p[..p.find('"').expect("closing quote")];
            let (lat, lon) = text.split_once(',').expect("lat,lon");
            [lat.parse().expect("lat"), lon.parse().expect("lon")]
        })
        .collect()
}

/// Azimuth of the chord from `a` to `b` ([lat, lon] degrees), clockwise from north at `a`,
/// with the WGS 84 ellipsoid's radii of curvature at `a`.
fn azimuth(a: [f64; 2], b: [f64; 2]) -> f64 {
    let (big_a, e2) = (6_378_137.0, 6.694_379_990_14e-3);
    let lat = a[0].to_radians();
    let w: f64 = 1.0 - e2 * lat.sin().powi(2);
    let north = (b[0] - a[0]).to_radians() * big_a * (1.0 - e2) / w.powf(1.5);
    let east = (b[1] - a[1]).to_radians() * big_a / w.sqrt() * lat.cos();
    east.atan2(north).to_degrees().rem_euclid(360.0)
}

/// The events of the emitter of `report`'s first emitter match its fix and ellipse.
fn check_emitter(events: &[Value], report: &Value, uid: &str) {
    let fix = &report["emitters"][0];
    let point = by_uid(events, uid);
    assert_eq!(point["type"], "a-u-G");
    // The events carry 7 decimals of a degree (1 cm).
    assert!((f(&point["lat"]) - f(&fix["lat"])).abs() < 1e-6, "{point}");
    assert!((f(&point["lon"]) - f(&fix["lon"])).abs() < 1e-6, "{point}");
    let major = f(&fix["ellipse"]["major_m"]);
    // `ce`: the 95 % ellipse's semi-major axis, to the decimetre written.
    assert!((f(&point["ce"]) - major).abs() <= 0.051, "{point}");
    let ellipse = by_uid(events, &format!("{uid}-ellipse"));
    assert_eq!(ellipse["type"], "u-d-c-e");
    let shape = ellipse["detail"]["xmlDetail"].as_str().expect("detail");
    for (name, want) in [
        ("major", major),
        ("minor", f(&fix["ellipse"]["minor_m"])),
        (
            "angle",
            f(&fix["ellipse"]["orientation_deg"]).rem_euclid(360.0),
        ),
    ] {
        let got = attr(shape, "ellipse", name);
        println!("{uid} ellipse {name}: {got} (report {want:.2})");
        assert!((got - want).abs() <= 0.051, "{name}: {got} against {want}");
    }
}

/// Each station of `report` is a point and its line of bearing starts there, pointing the way
/// its name says.
fn check_stations(events: &[Value], report: &Value) {
    let stations = report["stations"].as_array().expect("stations");
    assert!(!stations.is_empty());
    for s in stations {
        let id = s["id"].as_str().expect("id");
        let point = by_uid(events, &format!("foxhunt-station-{id}"));
        assert_eq!(point["type"], "a-f-G-E-S");
        let line = by_uid(events, &format!("foxhunt-lob-{id}"));
        assert_eq!(line["type"], "u-d-f");
        let pts = points(line["detail"]["xmlDetail"].as_str().expect("detail"));
        assert_eq!(pts.len(), 2, "{line}");
        // The line starts where the station is drawn.
        assert!(
            (pts[0][0] - f(&point["lat"])).abs() < 1e-6,
            "{line} {point}"
        );
        assert!(
            (pts[0][1] - f(&point["lon"])).abs() < 1e-6,
            "{line} {point}"
        );
        let callsign = line["detail"]["contact"]["callsign"]
            .as_str()
            .expect("name");
        let said: f64 = callsign
            .trim_end_matches(" deg")
            .rsplit(' ')
            .next()
            .and_then(|d| d.parse().ok())
            .expect("the bearing in the callsign");
        let drawn = azimuth(pts[0], pts[1]);
        // The line is straight in the fix's plane, and a chord kilometres long turns against
        // the meridians it crosses: its azimuth differs from the azimuth at its start by up to
        // the meridians' convergence along it, delta-longitude times sin(latitude) (0.16
        // degrees for 20 km east at 47 N); 0.06 more for the name's one decimal and the
        // points' seven.
        let convergence = (pts[1][1] - pts[0][1]).abs() * pts[0][0].to_radians().sin().abs();
        let off = (drawn - said + 180.0).rem_euclid(360.0) - 180.0;
        println!(
            "{id}: line of bearing {said} deg, chord {drawn:.3} deg, convergence {convergence:.3}"
        );
        assert!(off.abs() <= convergence + 0.06, "{callsign}: chord {drawn}");
    }
}

#[test]
fn the_sample_fix_reaches_tak_over_udp() {
    // One emitter (point + ellipse) and one station (point + line): four datagrams.
    let ear = listener(&["udp", "4"]);
    let port = ear.2;
    let url = format!("udp://127.0.0.1:{port}");
    let lines = common::json_lines(&["locate".into(), "--json".into(), "--cot".into(), url]);
    let events = received(ear);
    assert_eq!(events.len(), 4, "{events:#?}");
    check_emitter(&events, &lines[0], "foxhunt-emitter-433920");
    check_stations(&events, &lines[0]);
    // The events stay on TAK's screen for five minutes after they were sent.
    let e = by_uid(&events, "foxhunt-emitter-433920");
    let (start, stale): (u64, u64) = (
        e["startTime"].as_str().expect("ms").parse().expect("ms"),
        e["staleTime"].as_str().expect("ms").parse().expect("ms"),
    );
    assert_eq!(stale - start, 300_000);
}

#[test]
fn a_network_fix_reaches_a_tak_server_over_tcp() {
    let dir = std::env::temp_dir().join(format!("foxhunt-cot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    let capture = dir.join("net.xml");
    let capture = capture.to_str().expect("path").to_string();
    let sim = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(["simulate", "--condition", "network-reference", "--run", "2"])
        .args(["--out", &capture])
        .output()
        .expect("simulate");
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let stations = dir.join("net.stations.toml");
    let ear = listener(&["tcp"]);
    let port = ear.2;
    let lines = common::json_lines(&[
        "locate".into(),
        capture,
        "--stations".into(),
        stations.to_str().expect("path").into(),
        "--json".into(),
        "--cot".into(),
        format!("tcp://127.0.0.1:{port}"),
    ]);
    let events = received(ear);
    let n = lines[0]["stations"].as_array().expect("stations").len();
    let emitters = lines[0]["emitters"].as_array().expect("emitters").len();
    println!("{n} stations, {emitters} emitters, {} events", events.len());
    assert!(n >= 3, "a network of {n}");
    assert_eq!(events.len(), 2 * emitters + 2 * n);
    let uid = events
        .iter()
        .find(|e| e["type"] == "a-u-G")
        .and_then(|e| e["uid"].as_str())
        .expect("an emitter");
    check_emitter(&events, &lines[0], uid);
    check_stations(&events, &lines[0]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_tak_address_is_a_usage_error_and_a_closed_one_an_error() {
    let run = |url: &str| {
        Command::new(env!("CARGO_BIN_EXE_foxhunt"))
            .args(["locate", "--cot", url])
            .output()
            .expect("run foxhunt")
    };
    let bad = run("http://127.0.0.1:8087");
    assert_eq!(bad.status.code(), Some(2));
    // A port nobody listens on: bind one, learn it, close it.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let closed = run(&format!("tcp://127.0.0.1:{port}"));
    let err = String::from_utf8_lossy(&closed.stderr);
    println!("{err}");
    assert_eq!(closed.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("TAK at tcp://127.0.0.1:{port}")),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

#[test]
fn a_live_line_sends_every_update() {
    let ear = listener(&["tcp"]);
    let port = ear.2;
    let drive = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../serial-bridge/captures/aoa-drive.nmea"
    ))
    .expect("the sample drive");
    let mut child = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "locate",
            "-",
            "--json",
            "--cot",
            &format!("tcp://127.0.0.1:{port}"),
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("run foxhunt");
    // The drive in two halves, a pause between: at least two updates.
    let mut stdin = child.stdin.take().expect("stdin");
    let half = drive.len() / 2;
    std::io::Write::write_all(&mut stdin, &drive[..half]).expect("first half");
    std::thread::sleep(std::time::Duration::from_millis(500));
    std::io::Write::write_all(&mut stdin, &drive[half..]).expect("second half");
    drop(stdin);
    let out = child.wait_with_output().expect("foxhunt");
    assert!(out.status.success());
    let updates: Vec<Value> = out
        .stdout
        .lines()
        .map(|l| serde_json::from_str(&l.expect("line")).expect("JSON"))
        .filter(|v: &Value| v["emitters"].is_array())
        .collect();
    let events = received(ear);
    println!(
        "{} updates with a fix, {} events",
        updates.len(),
        events.len()
    );
    assert!(updates.len() >= 2, "{} updates", updates.len());
    // Four events (emitter, ellipse, station, line) for every update with a fix; the last
    // is the fix the run ended on.
    assert_eq!(events.len(), 4 * updates.len());
    let last = &events[events.len() - 4..];
    check_emitter(
        last,
        updates.last().expect("an update"),
        "foxhunt-emitter-433920",
    );
}

#[test]
fn a_moving_emitter_s_track_reaches_tak_with_its_course_and_speed() {
    let dir = std::env::temp_dir().join(format!("foxhunt-cot-track-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    let xml = dir.join("drone.xml");
    common::simulate("move-fixed-turning", Some(1), &xml);
    // The track's last point and its ellipse: two datagrams.
    let ear = listener(&["udp", "2"]);
    let url = format!("udp://127.0.0.1:{}", ear.2);
    let stations = dir.join("drone.stations.toml");
    let lines = common::json_lines(&[
        "track".into(),
        xml.to_string_lossy().into_owned(),
        "--stations".into(),
        stations.to_string_lossy().into_owned(),
        "--json".into(),
        "--cot".into(),
        url,
    ]);
    let events = received(ear);
    assert_eq!(events.len(), 2, "{events:#?}");
    let last = lines[0]["tracks"][0]["points"]
        .as_array()
        .and_then(|p| p.last())
        .expect("a point")
        .clone();
    let uid = "foxhunt-track-433920";
    let point = by_uid(&events, uid);
    assert_eq!(point["type"], "a-u-G");
    assert!((f(&point["lat"]) - f(&last["lat"])).abs() < 1e-6, "{point}");
    assert!((f(&point["lon"]) - f(&last["lon"])).abs() < 1e-6, "{point}");
    assert!((f(&point["ce"]) - f(&last["ellipse"]["major_m"])).abs() <= 0.051);
    // CoT's <track> (takproto decodes it into its own field): the speed and the course
    // (true, at the point) the velocity gives.
    let track = &point["detail"]["track"];
    let (ve, vn) = (f(&last["vel_e_mps"]), f(&last["vel_n_mps"]));
    let (speed, course) = (f(&track["speed"]), f(&track["course"]));
    println!("TAK track: {speed} m/s toward {course} deg; the point's velocity ({ve}, {vn})");
    assert!((speed - ve.hypot(vn)).abs() < 0.01, "{speed}");
    // The frame's north and the point's true north differ by the meridians' convergence
    // over the few kilometres from the frame's origin: well under a degree here.
    let frame_course = ve.atan2(vn).to_degrees().rem_euclid(360.0);
    let diff = (course - frame_course + 540.0).rem_euclid(360.0) - 180.0;
    assert!(diff.abs() < 0.5, "course {course} against {frame_course}");
    let ellipse = by_uid(&events, &format!("{uid}-ellipse"));
    assert_eq!(ellipse["type"], "u-d-c-e");
    let shape = ellipse["detail"]["xmlDetail"].as_str().expect("detail");
    assert!((attr(shape, "ellipse", "minor") - f(&last["ellipse"]["minor_m"])).abs() <= 0.051);
    std::fs::remove_dir_all(&dir).ok();
}
