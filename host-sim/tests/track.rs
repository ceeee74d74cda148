//! `foxhunt track` through the binary: bearings of a recorded drive, MT-frame RSSI with an
//! anchors file, the JSON schema, CSV and GeoJSON, a live line, and one-line refusals.

use foxhunt_bridge::nmea::write_sentence;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

mod common;

fn capture(name: &str) -> String {
    format!(
        "{}/../serial-bridge/captures/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("foxhunt-track-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn foxhunt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .current_dir(scratch("cwd"))
        .args(args)
        .output()
        .expect("run foxhunt")
}

/// `foxhunt ARGS` with `input` on standard input, run to its end.
fn fed(args: &[&str], input: &[u8]) -> Output {
    let mut child = common::piped(args);
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(input)
        .expect("write");
    child.wait_with_output().expect("wait")
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

const POINT_KEYS: [&str; 7] = [
    "t_ms",
    "east_m",
    "north_m",
    "vel_e_mps",
    "vel_n_mps",
    "ellipse",
    "p_moving",
];

#[test]
fn a_drone_seen_by_four_masts_gives_a_placed_track_around_it() {
    let dir = scratch("placed");
    let (xml, stations) = drone(&dir);
    let v = json(&foxhunt(&[
        "track",
        xml.to_str().expect("path"),
        "--stations",
        stations.to_str().expect("path"),
        "--json",
    ]));
    let tracks = v["tracks"].as_array().expect("tracks");
    assert_eq!(tracks.len(), 1, "{v}");
    assert!(tracks[0].get("untracked").is_none(), "{v}");
    let points = tracks[0]["points"].as_array().expect("points");
    assert!(points.len() > 500, "{} points", points.len());
    for p in points {
        for k in POINT_KEYS.iter().chain(&["lat", "lon"]) {
            assert!(p.get(*k).is_some(), "a point lacks `{k}`: {p}");
        }
    }
    let last = points.last().expect("a point");
    let e = &last["ellipse"];
    for k in ["major_m", "minor_m", "orientation_deg", "confidence"] {
        assert!(e[k].is_number(), "ellipse lacks `{k}`: {e}");
    }
    // Each f32 as its shortest decimal.
    assert_eq!(e["confidence"].as_f64(), Some(0.95));
    // The drone's true end (the simulation's truth file, metres in the same frame) lies
    // within twice the last 95 % semi-major axis of the last point: a track that lost the
    // drone would be kilometres off (the coverage itself is tests/tests/moving.rs's).
    let truth = std::fs::read_to_string(dir.join("drone.truth.csv")).expect("truth");
    let end: Vec<f64> = truth
        .lines()
        .last()
        .expect("a row")
        .split(',')
        .skip(3)
        .take(2)
        .map(|x| x.parse().expect("metres"))
        .collect();
    let num = |v: &serde_json::Value| v.as_f64().expect("number");
    let d = (end[0] - num(&last["east_m"])).hypot(end[1] - num(&last["north_m"]));
    println!("the last point {d:.0} m from the drone, ellipse {e}");
    assert!(d < 2.0 * num(&e["major_m"]), "{d:.0} m off: {last}");
    // Times rise.
    let t: Vec<i64> = points
        .iter()
        .map(|p| p["t_ms"].as_i64().expect("t"))
        .collect();
    assert!(t.windows(2).all(|w| w[0] <= w[1]), "{t:?}");
}

#[test]
fn a_channel_heard_by_one_station_is_not_tracked_and_says_why() {
    // The bundled drive: one vehicle's DF unit. Recorded, with or without --json: no track,
    // status 1, one line naming the station and what to do.
    let path = capture("aoa-drive.nmea");
    for args in [vec!["track", &path], vec!["track", &path, "--json"]] {
        let out = foxhunt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("no track on 433.920 MHz: heard by one DF station only (pfoxb)")
                && err.contains("not observable")
                && err.contains("foxhunt locate")
                && err.trim().lines().count() == 1,
            "{err}"
        );
        assert!(out.stdout.is_empty());
    }
    // Live: no point while only that station is heard, and the reason once it ends.
    let bytes = std::fs::read(&path).expect("capture");
    let out = fed(&["track", "-", "--json"], &bytes);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty());
    assert!(
        err.contains("no track on 433.920 MHz yet: heard by one DF station only (pfoxb)"),
        "{err}"
    );
    // Beside a channel four masts hear, the lone station's channel is named in the JSON, the
    // other tracked.
    let dir = scratch("lone");
    let (xml, stations) = drone(&dir);
    let mut both = std::fs::read(&xml).expect("drone");
    both.extend(retuned(&bytes, "145.500"));
    let mixed = dir.join("both.cap");
    std::fs::write(&mixed, &both).expect("write");
    let out = foxhunt(&[
        "track",
        mixed.to_str().expect("path"),
        "--stations",
        stations.to_str().expect("path"),
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let v = json(&out);
    let tracks = v["tracks"].as_array().expect("tracks");
    assert_eq!(tracks.len(), 2, "{v}");
    let lone: Vec<&serde_json::Value> = tracks.iter().filter(|t| t["freq_mhz"] == 145.5).collect();
    assert_eq!(lone.len(), 1, "{v}");
    assert!(lone[0]["points"].as_array().is_some_and(|p| p.is_empty()));
    assert!(
        lone[0]["untracked"]
            .as_str()
            .is_some_and(|w| w.contains("one DF station only (pfoxb)")),
        "{v}"
    );
    assert!(err.contains("no track on 145.500 MHz"), "{err}");
    let drone = tracks
        .iter()
        .find(|t| t["freq_mhz"] != 145.5)
        .expect("the drone");
    assert!(drone.get("untracked").is_none());
    assert!(drone["points"].as_array().is_some_and(|p| p.len() > 500));
}

/// `bytes` with every `$PFOXB` on frequency `mhz` (its checksum made anew).
fn retuned(bytes: &[u8], mhz: &str) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let mut out = String::new();
    for line in text.lines() {
        let Some(body) = line
            .strip_prefix("$PFOXB,")
            .and_then(|b| b.split('*').next())
        else {
            out.push_str(line);
            out.push_str("\r\n");
            continue;
        };
        let fields: Vec<&str> = body
            .split(',')
            .enumerate()
            .map(|(i, f)| if i == 4 { mhz } else { f })
            .collect();
        write_sentence(&mut out, &format!("PFOXB,{}", fields.join(","))).expect("written");
    }
    out.into_bytes()
}

/// Seed 003's rooms tracked as `track` tracks them, through the bytes `simulate` writes, 20
/// runs each against the node's true positions: no worse than the tracker before this one
/// (`sir-wide` on the anchors file's constant-velocity model: rssi-sim 0.61 m, rssi-lab
/// 1.03 m rmse over the same 20 runs; docs/src/tracking.md), the 95 % ellipses holding the
/// truth 90-99 % of the time. The runs are seeded, so the figures move only with the code;
/// today's are 16 % and 9 % under those bounds.
#[test]
fn the_rssi_rooms_track_no_worse_than_before_with_honest_ellipses() {
    let dir = scratch("rooms");
    for (name, before) in [("rssi-sim", 0.61), ("rssi-lab", 1.03)] {
        let (mut squares, mut inside, mut n) = (0.0f64, 0usize, 0usize);
        for run in 0..20 {
            let (_, _, truth) =
                foxhunt_sim::runs::simulate::indoor_capture(name, run).expect("a run");
            let znp = dir.join(format!("{name}-{run}.znp"));
            let made = foxhunt(&[
                "simulate",
                "--scenario",
                name,
                "--run",
                &run.to_string(),
                "--out",
                znp.to_str().expect("path"),
            ]);
            assert!(made.status.success(), "{made:?}");
            let anchors = znp.with_extension("anchors.toml");
            let v = json(&foxhunt(&[
                "track",
                znp.to_str().expect("path"),
                "--anchors",
                anchors.to_str().expect("path"),
                "--json",
            ]));
            let points = v["tracks"][0]["points"].as_array().expect("points");
            assert_eq!(
                points.len(),
                truth.len(),
                "{name} run {run}: a point an epoch"
            );
            for (p, t) in points.iter().zip(&truth) {
                let (error, held) = common::error_and_held(p, [f64::from(t[0]), f64::from(t[1])]);
                squares += error * error;
                inside += usize::from(held);
                n += 1;
            }
        }
        let (rmse, coverage) = (
            (squares / n as f64).sqrt(),
            100.0 * inside as f64 / n as f64,
        );
        println!(
            "{name}: rmse {rmse:.3} m (before {before} m), coverage {coverage:.1} % over {n} points"
        );
        assert!(rmse <= before, "{name}: {rmse:.3} m");
        assert!((90.0..=99.0).contains(&coverage), "{name}: {coverage:.1} %");
    }
}

#[test]
fn rssi_of_anchors_without_an_origin_is_in_metres_only() {
    let v = json(&foxhunt(&[
        "track",
        &capture("rssi-sim.znp"),
        "--anchors",
        &capture("rssi-sim.anchors.toml"),
        "--json",
    ]));
    let points = v["tracks"][0]["points"].as_array().expect("points");
    assert_eq!(points.len(), 60);
    assert!(v["tracks"][0]["freq_mhz"].is_null());
    for p in points {
        for k in POINT_KEYS {
            assert!(p.get(k).is_some(), "a point lacks `{k}`: {p}");
        }
        assert!(p.get("lat").is_none() && p.get("lon").is_none(), "{p}");
        // Inside the 10 m room (a margin for the mean of a cloud at a wall).
        for k in ["east_m", "north_m"] {
            let x = p[k].as_f64().expect("number");
            assert!((-0.5..=10.5).contains(&x), "{k} {x}");
        }
    }
    // No origin: no GeoJSON, one line, exit 1.
    let dir = scratch("geo");
    let g = dir.join("t.geojson");
    let out = foxhunt(&[
        "track",
        &capture("rssi-sim.znp"),
        "--anchors",
        &capture("rssi-sim.anchors.toml"),
        "--geojson",
        g.to_str().expect("path"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("origin") && err.trim().lines().count() == 1,
        "{err}"
    );
}

#[test]
fn csv_geojson_and_kml_of_a_drone() {
    let dir = scratch("files");
    let g = dir.join("t.geojson");
    let k = dir.join("t.kml");
    let c = dir.join("t.csv");
    let (xml, stations) = drone(&dir);
    let out = foxhunt(&[
        "track",
        xml.to_str().expect("path"),
        "--stations",
        stations.to_str().expect("path"),
        "--geojson",
        g.to_str().expect("path"),
        "--csv",
        c.to_str().expect("path"),
        "--kml",
        k.to_str().expect("path"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert_eq!(std::fs::read_to_string(&c).expect("csv"), stdout);
    let mut lines = stdout.lines();
    assert_eq!(
        lines.next(),
        Some(
            "freq_mhz,t_ms,lat,lon,east_m,north_m,vel_e_mps,vel_n_mps,major_m,minor_m,\
             orientation_deg,p_moving"
        )
    );
    let rows: Vec<&str> = lines.collect();
    assert!(rows.iter().all(|r| r.split(',').count() == 12), "{rows:?}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).expect("geojson")).expect("JSON");
    assert_eq!(v["type"], "FeatureCollection");
    let features = v["features"].as_array().expect("features");
    let kinds = |k: &str| {
        features
            .iter()
            .filter(|f| f["properties"]["kind"] == k)
            .count()
    };
    assert_eq!(kinds("track"), 1);
    assert_eq!(kinds("ellipse"), rows.len());
    for f in features
        .iter()
        .filter(|f| f["properties"]["kind"] == "ellipse")
    {
        let ring = f["geometry"]["coordinates"][0].as_array().expect("ring");
        assert_eq!(ring.first(), ring.last(), "an open ring");
    }
    // The KML holds the same: one track line, a point and an ellipse per CSV row, at the
    // rows' positions.
    let kml = std::fs::read_to_string(&k).expect("kml");
    assert_eq!(kml.matches("<LineString>").count(), 1);
    assert_eq!(kml.matches("<Polygon>").count(), rows.len());
    let points: Vec<&str> = kml
        .split("<Point><coordinates>")
        .skip(1)
        .map(|p| &p[..p.find('<').expect("end of coordinates")])
        .collect();
    assert_eq!(points.len(), rows.len());
    for (p, r) in points.iter().zip(&rows) {
        let f: Vec<f64> = p.split(',').map(|x| x.parse().expect("number")).collect();
        let c: Vec<&str> = r.split(',').collect();
        let (lat, lon): (f64, f64) = (c[2].parse().expect("lat"), c[3].parse().expect("lon"));
        // The CSV's six decimals against the KML's eight.
        assert!(
            (f[0] - lon).abs() < 1e-6 && (f[1] - lat).abs() < 1e-6,
            "{p} against {r}"
        );
    }
}

#[test]
fn bad_options_are_one_line_refusals() {
    for (args, words) in [
        (vec!["--method", "ml-robust"], "not a tracking method"),
        (vec!["--particles", "300"], "--particles 300"),
        (vec!["--sigma=-1"], "--sigma"),
        (vec!["--svg", "x.svg"], "--anchors"),
    ] {
        let mut all = vec!["track", "AOA"];
        all.extend(args);
        let path = capture("aoa-drive.nmea");
        let all: Vec<&str> = all
            .into_iter()
            .map(|a| if a == "AOA" { path.as_str() } else { a })
            .collect();
        let out = foxhunt(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        // A value the program refuses is a usage error, as --help says.
        assert_eq!(out.status.code(), Some(2), "{all:?}: {err}");
        assert!(
            err.contains(words) && err.trim().lines().count() == 1,
            "{err}"
        );
        assert!(out.stdout.is_empty());
    }
    // A live line is printed as it comes: nothing to smooth it with.
    let out = foxhunt(&["track", "-", "--smooth"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--smooth smooths a recording") && err.trim().lines().count() == 1,
        "{err}"
    );
    // An empty capture has nothing to track.
    let dir = scratch("empty");
    let f = dir.join("empty.nmea");
    std::fs::write(&f, b"").expect("write");
    let out = foxhunt(&["track", f.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to track"));
}

/// A drone seen by four masts (`move-fixed-turning`, run 1) as its stations log it, and the
/// stations file: (capture, stations file).
fn drone(dir: &std::path::Path) -> (PathBuf, PathBuf) {
    let xml = dir.join("drone.xml");
    common::simulate("move-fixed-turning", Some(1), &xml);
    (xml, dir.join("drone.stations.toml"))
}

/// `foxhunt ARGS` fed `bytes` on standard input in two halves: it must print an update
/// before the second half is written (the line is tracked as it arrives), and end well; its
/// lines, one JSON object each.
fn live_in_halves(args: &[&str], bytes: &[u8]) -> Vec<serde_json::Value> {
    let mut child = common::piped(args);
    let rx = common::line_reader(&mut child);
    let mut stdin = child.stdin.take().expect("stdin");
    let half = bytes.len() / 2;
    stdin.write_all(&bytes[..half]).expect("first half");
    stdin.flush().expect("flush");
    let first = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("an update before the line closed");
    let mut lines = vec![first];
    stdin.write_all(&bytes[half..]).expect("second half");
    drop(stdin);
    lines.extend(rx.iter());
    assert!(child.wait().expect("wait").success());
    lines
        .iter()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect()
}

#[test]
fn a_live_line_is_tracked_as_it_arrives_and_ends_where_the_recording_does() {
    let dir = scratch("live");
    let (xml, stations) = drone(&dir);
    let (xml, stations) = (
        xml.to_str().expect("path"),
        stations.to_str().expect("path"),
    );
    let recorded = json(&foxhunt(&["track", xml, "--stations", stations, "--json"]));
    let points = recorded["tracks"][0]["points"].as_array().expect("points");
    let bytes = std::fs::read(xml).expect("capture");
    let live = live_in_halves(&["track", "-", "--stations", stations, "--json"], &bytes);
    println!(
        "live {} updates, recorded {}; last live {}, last recorded {}",
        live.len(),
        points.len(),
        live.last().expect("a point"),
        points.last().expect("a point")
    );
    // The same bearings in the same windows, except that the pause between the halves may
    // close one update early (the line went quiet): at most one update more.
    assert!(
        (points.len()..=points.len() + 1).contains(&live.len()),
        "{} live updates against {} recorded",
        live.len(),
        points.len()
    );
    for p in &live {
        for key in POINT_KEYS.iter().chain(&["lat", "lon", "freq_mhz"]) {
            assert!(p.get(*key).is_some(), "{key} missing from {p}");
        }
    }
    // Where the track ends: the live tracker saw the same bearings, so it ends within the
    // recorded track's last 95 % semi-major axis of the recorded end (one split update moves
    // a particle filter's draws, not what the bearings say).
    let (a, b) = (
        live.last().expect("a point"),
        points.last().expect("a point"),
    );
    let d = (a["east_m"].as_f64().expect("east") - b["east_m"].as_f64().expect("east"))
        .hypot(a["north_m"].as_f64().expect("north") - b["north_m"].as_f64().expect("north"));
    let major = b["ellipse"]["major_m"].as_f64().expect("major");
    assert!(
        d < major,
        "live end {d:.0} m from the recorded end (major {major:.0} m)"
    );
}

#[test]
fn a_live_line_of_anchors_rssi_is_tracked_as_the_recording_is() {
    let (znp, anchors) = (capture("rssi-sim.znp"), capture("rssi-sim.anchors.toml"));
    let recorded = json(&foxhunt(&["track", &znp, "--anchors", &anchors, "--json"]));
    let points = recorded["tracks"][0]["points"].as_array().expect("points");
    let bytes = std::fs::read(&znp).expect("capture");
    let live = live_in_halves(&["track", "-", "--anchors", &anchors, "--json"], &bytes);
    println!(
        "live {} epochs, recorded {}; first live {}, first recorded {}",
        live.len(),
        points.len(),
        live[0],
        points[0]
    );
    // The pause between the halves closes the open epoch early (the line went quiet): one
    // epoch more at most. Up to it the points are the recording's to the last digit.
    assert!(
        (points.len()..=points.len() + 1).contains(&live.len()),
        "{} live epochs against {} recorded",
        live.len(),
        points.len()
    );
    let same = live
        .iter()
        .zip(points)
        .take_while(|(a, b)| POINT_KEYS.iter().all(|k| a[k] == b[k]))
        .count();
    println!("the first {same} points are the recording's");
    // Frames are of one size, so the half of the bytes is about the half of the epochs: an
    // early close there (two epochs of slack for where in an epoch the cut falls) is the only
    // place the points may part.
    assert!(
        same == points.len() || same >= points.len() / 2 - 2,
        "only the first {same} points agree"
    );
    for p in &live {
        assert!(p.get("lat").is_none() && p["freq_mhz"].is_null(), "{p}");
        let (x, y) = (
            p["east_m"].as_f64().expect("east"),
            p["north_m"].as_f64().expect("north"),
        );
        assert!(
            (-0.5..=10.5).contains(&x) && (-0.5..=10.5).contains(&y),
            "{p}"
        );
    }
}

#[test]
fn a_live_line_without_bearings_and_live_files_are_refused() {
    let run = fed;
    // Nothing on the line: no track, exit status 1, one line saying why.
    let out = run(&["track", "-"], b"$GPGGA,garbage\r\n");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nothing to track") && err.trim().lines().count() == 1,
        "{err}"
    );
    assert!(out.stdout.is_empty());
    // A line of MT frames from no listed anchor: nothing to track, exit 1.
    let anchors = capture("rssi-sim.anchors.toml");
    let out = run(
        &["track", "-", "--anchors", &anchors],
        b"\xfe\x00\x00\x00\x00",
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no RSSI reading") && err.trim().lines().count() == 1,
        "{err}"
    );
    // Files are written from recordings, RSSI comes on a byte line; no CAPTURE at all is a
    // usage error.
    for args in [
        vec!["track", "-", "--geojson", "x.geojson"],
        vec!["track", "-", "--anchors", &anchors, "--svg", "x.svg"],
        vec![
            "track",
            "--kraken",
            "http://127.0.0.1:9",
            "--anchors",
            &anchors,
        ],
        vec!["track"],
        vec!["track", "-", "--kraken", "http://127.0.0.1:9"],
    ] {
        let out = run(&args, b"");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.trim().lines().count() == 1, "{err}");
    }
}

/// One DF vehicle (a GGA each second, a PFOXB half a second later from halfway along, 3 deg
/// of noise) driving a 400 m square at 8 m/s around a tag walking at 1.1 m/s, and three
/// anchors' RSSI of the tag (MT frames after each fix; -30 dBm at 1 m, exponent 2, 4 dB of
/// noise), in `dir`: the capture and its anchors file (the tag: [`walker`]).
fn vehicle_and_anchors(dir: &std::path::Path) -> (String, String) {
    vehicle_and_anchors_with(dir, [0.0; 4])
}

/// [`vehicle_and_anchors`] with the unit's direction-dependent error `table` (a1, b1, a2, b2,
/// degrees, of the true bearing relative to the vehicle's course, both counter-clockwise)
/// added to every bearing.
fn vehicle_and_anchors_with(dir: &std::path::Path, table: [f64; 4]) -> (String, String) {
    use foxhunt_bridge::geo::LocalFrame;
    use foxhunt_bridge::mt::{AfIncomingMsg, LinkQualityMap};
    use foxhunt_bridge::nmea::{LatLon, Pfoxb, Reference, UtcTime};
    use foxhunt_sim::runs::writer::CaptureWriter;
    let origin = LatLon {
        lat: 52.5,
        lon: 13.4,
    };
    let frame = LocalFrame::new(origin, 0.0).expect("frame");
    let anchors = [
        (0x0201u16, [0.0, 200.0]),
        (0x0202, [400.0, 0.0]),
        (0x0203, [400.0, 400.0]),
    ];
    // A small generator of its own: the fixture is the same on every machine.
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut normal = move || {
        let mut u = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    };
    let vehicle = |t: f64| {
        let s = (8.0 * t) % 1600.0;
        match (s / 400.0) as u32 {
            0 => [s, 0.0],
            1 => [400.0, s - 400.0],
            2 => [1200.0 - s, 400.0],
            _ => [0.0, 1600.0 - s],
        }
    };
    let geo = |p: [f64; 2]| frame.to_geodetic(p).expect("in range");
    let mut w = CaptureWriter::new();
    let map = LinkQualityMap::default();
    for k in 0..240u32 {
        let t = f64::from(k);
        let time = |t: f64| UtcTime {
            ms_of_day: 36_000_000 + (t * 1000.0) as u32,
        };
        w.gga(time(t), geo(vehicle(t))).expect("gga");
        let (v, e) = (vehicle(t + 0.5), walker(t + 0.5));
        // The unit's error at the true bearing relative to its course (counter-clockwise
        // from east, as the table's harmonics take it), taken off the azimuth (clockwise).
        let ahead = vehicle(t + 0.6);
        let course = (ahead[1] - v[1]).atan2(ahead[0] - v[0]);
        let phi = (e[1] - v[1]).atan2(e[0] - v[0]) - course;
        let error = table[0] * phi.cos()
            + table[1] * phi.sin()
            + table[2] * (2.0 * phi).cos()
            + table[3] * (2.0 * phi).sin();
        let azimuth = (e[0] - v[0]).atan2(e[1] - v[1]).to_degrees() - error + 3.0 * normal();
        w.pfoxb(&Pfoxb {
            time: time(t + 0.5),
            azimuth_deg: azimuth.rem_euclid(360.0),
            reference: Reference::True,
            quality: 80.0,
            freq_mhz: 433.92,
            position: None,
        })
        .expect("pfoxb");
        let here = walker(t);
        for (i, (addr, at)) in anchors.iter().enumerate() {
            let d = (here[0] - at[0]).hypot(here[1] - at[1]).max(1.0);
            let dbm = -30.0 - 20.0 * d.log10() + 4.0 * normal();
            w.af_incoming_msg(&AfIncomingMsg {
                group_id: 0,
                cluster_id: 0x0402,
                src_addr: *addr,
                src_endpoint: 1,
                dst_endpoint: 1,
                was_broadcast: false,
                link_quality: map.link_quality(dbm as f32),
                security_use: false,
                timestamp: k * 1000,
                trans_seq: (k as usize * 3 + i) as u8,
                data: &[0x18, 0, 0x0a],
            })
            .expect("frame");
        }
    }
    let capture = dir.join("vehicle-anchors.nmea");
    std::fs::write(&capture, w.into_bytes()).expect("write capture");
    let mut file = format!(
        "origin = [{}, {}]\nsigma_db = 4.0\n\n[path_loss]\np0_dbm = -30.0\nd0_m = 1.0\neta = 2.0\n",
        origin.lat, origin.lon
    );
    for (addr, [x, y]) in anchors {
        file.push_str(&format!("\n[[anchor]]\naddr = {addr}\nx = {x}\ny = {y}\n"));
    }
    let anchors_file = dir.join("vehicle-anchors.anchors.toml");
    std::fs::write(&anchors_file, file).expect("write anchors");
    let path = |p: PathBuf| p.to_str().expect("a UTF-8 path").to_string();
    (path(capture), path(anchors_file))
}

/// Where the tag of [`vehicle_and_anchors`] is `t` seconds into it (east, north), metres.
fn walker(t: f64) -> [f64; 2] {
    [100.0 + t, 120.0 + 0.5 * t]
}

/// The rmse of a track of the walking tag of [`vehicle_and_anchors`] and the share of its
/// 95 % ellipses that hold the tag, after the first minute (the vehicle has then seen the tag
/// from two sides of the square).
fn judge_walker(points: &[serde_json::Value]) -> (f64, f64) {
    let (mut sq, mut held, mut n) = (0.0, 0usize, 0usize);
    for p in points {
        // A live line's points name their channel; a recording's tracks do.
        if let Some(freq) = p.get("freq_mhz") {
            assert!((freq.as_f64().expect("MHz") - 433.92).abs() < 1e-4, "{p}");
        }
        // The track's time counts from the first bearing, half a second into the fixture's.
        let t = p["t_ms"].as_f64().expect("t") / 1000.0 + 0.5;
        if t < 60.0 {
            continue;
        }
        let x = walker(t);
        let f = |k: &str| p[k].as_f64().expect(k);
        let d = [x[0] - f("east_m"), x[1] - f("north_m")];
        let e = &p["ellipse"];
        let (a, b) = (
            e["major_m"].as_f64().expect("a"),
            e["minor_m"].as_f64().expect("b"),
        );
        let o = e["orientation_deg"].as_f64().expect("o").to_radians();
        // The major axis clockwise from north: (east, north) = (sin, cos).
        let along = d[0] * o.sin() + d[1] * o.cos();
        let across = d[0] * o.cos() - d[1] * o.sin();
        held += usize::from((along / a).powi(2) + (across / b).powi(2) <= 1.0);
        sq += d[0] * d[0] + d[1] * d[1];
        n += 1;
    }
    let (rmse, coverage) = ((sq / n as f64).sqrt(), held as f64 / n as f64);
    println!("{n} points after a minute: rmse {rmse:.1} m, coverage {coverage:.3}");
    (rmse, coverage)
}

#[test]
fn bearings_and_anchors_rssi_on_one_live_line_are_tracked_as_the_recording_is() {
    let dir = scratch("mixed");
    let (capture, anchors) = vehicle_and_anchors(&dir);
    let (capture, anchors) = (capture.as_str(), anchors.as_str());
    // What the user knows: the tag is carried by someone walking, the unit's noise is 3 deg.
    let known = ["--motion", "indoor", "--sigma", "3", "--json"];
    let args = |capture| [&["track", capture, "--anchors", anchors][..], &known].concat();
    let recorded = json(&foxhunt(&args(capture)));
    let tracks = recorded["tracks"].as_array().expect("tracks");
    assert_eq!(tracks.len(), 1, "one emitter: {recorded}");
    let points = tracks[0]["points"].as_array().expect("points");
    let bytes = std::fs::read(capture).expect("capture");
    let live = live_in_halves(&args("-"), &bytes);
    let same = live
        .iter()
        .zip(points)
        .take_while(|(a, b)| POINT_KEYS.iter().all(|k| a[k] == b[k]))
        .count();
    println!(
        "live {} updates, recorded {}; the first {same} the same",
        live.len(),
        points.len()
    );
    // One update a second, each a bearing and the readings beside it (the readings of a fix
    // come half a second before its bearing: their own update).
    assert!(points.len() >= 2 * 239, "{} updates", points.len());
    // The pause between the halves may close an open update early (the line went quiet): up
    // to it the points are the recording's to the last digit.
    assert!(same >= points.len() / 2 - 4, "only the first {same} agree");
    let (rmse, coverage) = judge_walker(&live);
    // Measured 25.1 m and 85.3 %: the bar leaves this one fixture's luck a margin. The
    // ellipses are short of 95 % (docs/src/tracking.md, "Live"): between the vehicle's
    // passes the tracker's P(moving) falls toward "still" and the track lags the walker
    // (30-45 m late in the last minute); the outdoor motion model lags more (39.9 m, 48 %).
    assert!(rmse < 35.0, "rmse {rmse:.1} m");
    assert!(coverage > 0.75, "coverage {coverage:.3}");
}

#[test]
fn bearings_noisier_than_their_records_say_are_tracked_with_the_noise_they_show() {
    let dir = scratch("noisy");
    let (capture, anchors) = vehicle_and_anchors(&dir);
    let (capture, anchors) = (capture.as_str(), anchors.as_str());
    // The unit's 3 deg of noise where its PFOXB records state the bridge's 1 deg.
    let run = |input: &str, extra: &[&str]| {
        let args = [
            &[
                "track",
                input,
                "--anchors",
                anchors,
                "--motion",
                "indoor",
                "--json",
            ][..],
            extra,
        ]
        .concat();
        let (lines, err) = common::json_lines_from(&args, Some(Path::new(capture)));
        println!("{args:?}: {err}");
        (lines, err)
    };
    // Recorded, nothing stated: estimated, said once, and in the JSON.
    let (out, err) = run(capture, &[]);
    assert!(
        err.contains("pfoxb's bearings scatter")
            && err.contains("(1.0 deg)")
            && err.contains("estimated")
            && !err.contains("indoor-aoa")
            && err.trim().lines().count() == 1,
        "{err}"
    );
    let station = &out[0]["tracks"][0]["stations"][0];
    let noise = station["noise_deg"].as_f64().expect("noise_deg");
    println!("estimated {noise:.2} deg");
    // 3 deg from about 240 bearings about a track that has seen them: 2.4-3.6 leaves the
    // estimate's spread (about 5 %) and the track's pull room.
    assert!((2.4..3.6).contains(&noise), "{station}");
    assert_eq!(station["estimated"], true);
    let points = out[0]["tracks"][0]["points"].as_array().expect("points");
    let (rmse, coverage) = judge_walker(points);
    // As tracked with the unit's noise stated (`--sigma 3`: 25.1 m and 85.3 %, the same bars
    // as there); with the records' 1 deg taken as it is, 39.9 m and 48 %.
    assert!(rmse < 35.0 && coverage > 0.75, "{rmse:.1} m, {coverage:.3}");
    // Stated right: nothing said, not estimated.
    let (out, err) = run(capture, &["--sigma", "3"]);
    assert!(!err.contains("scatter"), "{err}");
    assert_eq!(out[0]["tracks"][0]["stations"][0]["estimated"], false);
    // Stated too small: said, and kept as stated.
    let (_, err) = run(capture, &["--sigma", "1"]);
    assert!(
        err.contains("times the noise stated for them (1.0 deg)"),
        "{err}"
    );
    // Live: widened once enough bearings show it, said once.
    let (live, err) = run("-", &[]);
    assert!(
        err.contains("pfoxb's bearings scatter")
            && err.contains("from here they take")
            && !err.contains("indoor-aoa"),
        "{err}"
    );
    let (rmse, coverage) = judge_walker(&live);
    assert!(rmse < 35.0 && coverage > 0.75, "{rmse:.1} m, {coverage:.3}");
}

#[test]
fn a_stated_direction_dependent_error_is_taken_out_of_a_track() {
    // The walking tag's fixture, the vehicle's unit with harmonics of 3.6 and 3.2 deg in the
    // bearing relative to its course; its calibration stated (the table, sd 0.2 deg) in a
    // stations file. What the user knows beside: a walking tag, 3 deg of noise. Measured:
    // ignored, 33.3 m and 41.7 % after the first minute; taken out, 26.3 m and 82.5 % (the
    // same fixture with no such error: 25.1 m, 85.3 %), live the same as the recording to the
    // last digit in all 480 updates. Bars: rmse below 0.8 of the ignored one, coverage above
    // the ignored one and 0.75 (the fixture's own bar), live as the recording to the pause.
    let dir = scratch("direction");
    let table = [3.0, -2.0, 2.0, 2.5];
    let (capture, anchors) = vehicle_and_anchors_with(&dir, table);
    let (capture, anchors) = (capture.as_str(), anchors.as_str());
    let stations = dir.join("unit.stations.toml");
    std::fs::write(
        &stations,
        "[[station]]\nid = \"pfoxb\"\ndirection_deg = [3.0, -2.0, 2.0, 2.5]\ndirection_error_deg = 0.2\n",
    )
    .expect("stations file");
    let stations = stations.to_str().expect("path");
    let known = ["--motion", "indoor", "--sigma", "3", "--json"];
    let args = |capture| [&["track", capture, "--anchors", anchors][..], &known].concat();
    let stated = |capture| [args(capture), vec!["--stations", stations]].concat();
    let points =
        |v: &serde_json::Value| v["tracks"][0]["points"].as_array().expect("points").clone();
    let ignored = points(&json(&foxhunt(&args(capture))));
    let (rmse_ignored, coverage_ignored) = judge_walker(&ignored);
    let recorded = points(&json(&foxhunt(&stated(capture))));
    let (rmse, coverage) = judge_walker(&recorded);
    let bytes = std::fs::read(capture).expect("capture");
    let live = live_in_halves(&stated("-"), &bytes);
    let same = live
        .iter()
        .zip(&recorded)
        .take_while(|(a, b)| POINT_KEYS.iter().all(|k| a[k] == b[k]))
        .count();
    println!(
        "stated: live the same as the recording for the first {same} of {}",
        recorded.len()
    );
    assert!(
        same >= recorded.len() / 2 - 4,
        "only the first {same} agree"
    );
    assert!(
        rmse < 0.8 * rmse_ignored,
        "rmse {rmse:.1} m against {rmse_ignored:.1} m ignored"
    );
    assert!(
        coverage > 0.75 && coverage > coverage_ignored,
        "coverage {coverage:.3} against {coverage_ignored:.3}"
    );
}
