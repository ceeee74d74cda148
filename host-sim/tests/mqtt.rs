//! Three stations through a real MQTT broker: `foxhunt publish` per station, `foxhunt locate
//! --mqtt` fusing them, against `foxhunt locate` on the same recorded files. Each test starts
//! its own mosquitto on a free loopback port with a temporary configuration (persistence on,
//! so a restart keeps the QoS 1 sessions); it fails when mosquitto is missing (CI installs
//! it, .ci/run).

use foxhunt_bridge::nmea::LatLon;
use foxhunt_sim::runs::network::{NetworkCondition, capture};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::broker::{Broker, Worker, serial};

const FOXHUNT: &str = env!("CARGO_BIN_EXE_foxhunt");

/// The network-fixed3 run 1 (the KrakenSDR network test's): each mast's records in a file of
/// its own, in `dir`.
fn station_files(dir: &Path) -> Vec<PathBuf> {
    let origin = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    let (bytes, _, _) = capture(NetworkCondition::Fixed3, 1, origin).expect("capture");
    let text = String::from_utf8(bytes).expect("ASCII");
    ["mast-1", "mast-2", "mast-3"]
        .iter()
        .map(|id| {
            let tag = format!("<STATION_ID>{id}</STATION_ID>");
            let mine: String = text
                .lines()
                .filter(|l| l.contains(&tag))
                .map(|l| format!("{l}\n"))
                .collect();
            assert_eq!(mine.lines().count(), 600, "{id}");
            let p = dir.join(format!("{id}.xml"));
            std::fs::write(&p, mine).expect("write");
            p
        })
        .collect()
}

/// `foxhunt publish FILE` started (paced: `pace` times real time).
fn publish(file: &Path, url: &str, pace: Option<u32>) -> Child {
    let mut c = Command::new(FOXHUNT);
    c.arg("publish").arg(file).args(["--mqtt", url]);
    let id = file.file_stem().expect("stem").to_string_lossy();
    c.args(["--client-id", &format!("test-{id}")]);
    if let Some(p) = pace {
        c.args(["--pace", &p.to_string()]);
    }
    c.stderr(Stdio::piped()).spawn().expect("run publish")
}

/// A publisher's end: it must succeed (every bearing acknowledged); its standard error.
fn published(c: Child) -> String {
    let out = c.wait_with_output().expect("wait");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "publish: {err}");
    err
}

/// Every file of `files` published at once (each its own station's publisher, `pace` as
/// [`publish`]'s), each to success.
fn publish_all(files: &[PathBuf], url: &str, pace: Option<u32>) {
    let pubs: Vec<Child> = files.iter().map(|f| publish(f, url, pace)).collect();
    for p in pubs {
        published(p);
    }
}

/// `foxhunt locate FILES --json`: the recorded files' report.
fn recorded(files: &[PathBuf]) -> Value {
    let out = Command::new(FOXHUNT)
        .arg("locate")
        .args(files)
        .arg("--json")
        .output()
        .expect("locate");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// The live fix is the recorded files' fix. The bearings arrive interleaved in another order
/// than the files', and the local frame's origin is whichever station's bearing came first,
/// so the solver stops at another point of its tolerance, measured 0.4-3 m apart on ellipses
/// 1 400-2 200 m across (the KrakenSDR network test's bar): within 1 % of the ellipse's
/// semi-minor axis, and the ellipse itself within 1 %. Every bearing is used.
fn assert_same_fix(live: &Value, file: &Value) {
    assert_eq!(live["used"], file["used"], "bearings used");
    let (l, f) = (&live["emitters"][0], &file["emitters"][0]);
    let num = |v: &Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let apart = ((num(l, "lat") - num(f, "lat")) * 111_200.0)
        .hypot((num(l, "lon") - num(f, "lon")) * 75_800.0);
    let (lm, fm) = (&l["ellipse"], &f["ellipse"]);
    eprintln!(
        "live {:.7}, {:.7}; file {:.7}, {:.7}: {apart:.3} m apart; ellipses {:.1} x {:.1} and \
         {:.1} x {:.1} m",
        num(l, "lat"),
        num(l, "lon"),
        num(f, "lat"),
        num(f, "lon"),
        num(lm, "major_m"),
        num(lm, "minor_m"),
        num(fm, "major_m"),
        num(fm, "minor_m")
    );
    assert!(apart < 0.01 * num(fm, "minor_m"), "{apart} m apart");
    for k in ["major_m", "minor_m"] {
        assert!(
            (num(lm, k) / num(fm, k) - 1.0).abs() < 0.01,
            "{k}: {lm} {fm}"
        );
    }
}

/// The retained fix of a channel, read back as a new subscriber would.
fn retained_fix(port: u16, topic: &str) -> Value {
    let mut o = rumqttc::MqttOptions::new("test-reader", "127.0.0.1", port);
    o.set_clean_session(true);
    let (client, mut conn) = rumqttc::Client::new(o, 10);
    client
        .subscribe(topic, rumqttc::QoS::AtLeastOnce)
        .expect("subscribe");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        if let Ok(Ok(rumqttc::Event::Incoming(rumqttc::Packet::Publish(p)))) =
            conn.recv_timeout(Duration::from_millis(200))
        {
            assert!(p.retain, "a retained message");
            return serde_json::from_slice(&p.payload).expect("JSON fix");
        }
    }
    panic!("no retained fix on {topic}");
}

#[test]
fn three_stations_through_the_broker_give_the_recorded_files_fix() {
    let _one_broker = serial();
    let broker = Broker::start("fix");
    let files = station_files(&broker.dir);
    let url = broker.url("net");
    let worker = Worker::start(&url, "fix-worker", 3);
    publish_all(&files, &url, None);
    let (live, err) = worker.finish();
    eprintln!("{}", err.join("\n"));
    let file = recorded(&files);
    assert_eq!(file["used"].as_u64(), Some(1800));
    assert_same_fix(&live, &file);
    assert!(
        err.iter()
            .any(|l| l.contains("mqtt: bearings 1800, duplicates 0")),
        "{err:?}"
    );
    // The channel's fix, retained: the worker's last one.
    let fix = retained_fix(broker.port, "net/fixes/433.920");
    assert_eq!(
        fix, live["emitters"][0],
        "the retained fix is the last update's"
    );
}

#[test]
fn a_broker_restarted_mid_stream_loses_no_bearing_and_counts_none_twice() {
    let _one_broker = serial();
    let mut broker = Broker::start("restart");
    let files = station_files(&broker.dir);
    let url = broker.url("net");
    // Quiet for 8 s before it ends: longer than the broker's outage.
    let worker = Worker::start(&url, "restart-worker", 8);
    // 600 s of bearings at 150 times real time: 4 s of stream, the restart in the middle.
    let pubs: Vec<Child> = files.iter().map(|f| publish(f, &url, Some(150))).collect();
    std::thread::sleep(Duration::from_millis(1500));
    broker.stop();
    std::thread::sleep(Duration::from_millis(700));
    broker.run();
    let notes: Vec<String> = pubs.into_iter().map(published).collect();
    let (live, err) = worker.finish();
    eprintln!("{}\n{}", notes.join(""), err.join("\n"));
    // The restart happened while the stations were sending.
    assert!(
        notes.iter().all(|n| n.contains("outages 1")),
        "every publisher lost the broker once: {notes:?}"
    );
    assert!(
        err.iter().any(|l| l.contains("connected again")),
        "the worker reconnected: {err:?}"
    );
    // Every bearing once: the report's count is the files'.
    let file = recorded(&files);
    assert_eq!(live["used"], file["used"], "bearings used");
    assert!(
        err.iter().any(|l| l.contains("stats: bearings 1800,")),
        "{err:?}"
    );
    assert_same_fix(&live, &file);
}

#[test]
fn a_station_that_sends_its_capture_twice_counts_once() {
    let _one_broker = serial();
    let broker = Broker::start("twice");
    let files = station_files(&broker.dir);
    let url = broker.url("net");
    let worker = Worker::start(&url, "twice-worker", 3);
    // mast-1 sends its capture, then again under another session (a station that restarted
    // and resent its log); the others once.
    for f in files.iter().chain(std::iter::once(&files[0])) {
        let mut c = Command::new(FOXHUNT);
        c.arg("publish").arg(f).args(["--mqtt", &url]);
        let out = c.output().expect("publish");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let (live, err) = worker.finish();
    assert!(
        err.iter()
            .any(|l| l.contains("mqtt: bearings 1800, duplicates 600")),
        "{err:?}"
    );
    assert_same_fix(&live, &recorded(&files));
}

#[test]
fn an_unreachable_broker_is_one_line_and_status_1() {
    let _one_broker = serial();
    // A port nothing listens on: bound, then closed.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let url = format!("mqtt://127.0.0.1:{port}/net");
    let dir = std::env::temp_dir().join(format!("foxhunt-mqtt-none-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = &station_files(&dir)[0];
    for args in [
        vec!["locate".to_string(), "--mqtt".into(), url.clone()],
        vec![
            "publish".to_string(),
            file.display().to_string(),
            "--mqtt".into(),
            url.clone(),
        ],
    ] {
        let out = Command::new(FOXHUNT).args(&args).output().expect("run");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.lines()
                .any(|l| l.starts_with("foxhunt: cannot reach the MQTT broker at 127.0.0.1:")),
            "{err}"
        );
    }
    // Usage errors: exit 2 before any connection.
    for args in [
        vec!["locate", "--mqtt", "http://x"],
        vec!["locate", "x.xml", "--mqtt", "mqtt://127.0.0.1/net"],
        vec!["publish", "--mqtt", "mqtt://127.0.0.1/net"],
        vec![
            "publish",
            "x.xml",
            "--station",
            "a/b",
            "--mqtt",
            "mqtt://127.0.0.1/net",
        ],
    ] {
        let out = Command::new(FOXHUNT).args(&args).output().expect("run");
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // gpsd places a live line's bearings, not a recorded capture's.
    let capture = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let out = Command::new(FOXHUNT)
        .args([
            "publish",
            capture,
            "--gpsd",
            "--mqtt",
            "mqtt://127.0.0.1/net",
        ])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--gpsd gives positions beside a live line"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each station's file cut in two at its 300th record: `[first halves, second halves]`.
fn halves(files: &[PathBuf]) -> [Vec<PathBuf>; 2] {
    let mut out = [Vec::new(), Vec::new()];
    for f in files {
        let text = std::fs::read_to_string(f).expect("read");
        let lines: Vec<&str> = text.lines().collect();
        for (k, part) in lines.chunks(300).enumerate() {
            let p = f.with_extension(format!("{k}.xml"));
            std::fs::write(&p, part.join("\n") + "\n").expect("write");
            out[k].push(p);
        }
    }
    out
}

/// Publish `files` one after the other, each acknowledged before the next: the broker hands
/// the worker their bearings in this order.
fn publish_in_turn(files: &[PathBuf], url: &str) {
    for f in files {
        published(publish(f, url, None));
    }
}

#[test]
fn a_worker_killed_and_started_again_on_its_history_gives_the_uninterrupted_fix() {
    let _one_broker = serial();
    let broker = Broker::start("history");
    let files = station_files(&broker.dir);
    let [first, second] = halves(&files);
    let url = broker.url("net");
    let db = |name: &str| broker.dir.join(name).display().to_string();

    // One worker throughout.
    let whole_db = db("whole.db");
    let worker = Worker::start_with(&url, "whole-worker", 3, &["--db", &whole_db]);
    publish_in_turn(&first, &url);
    publish_in_turn(&second, &url);
    let (whole, _) = worker.finish();
    assert_eq!(whole["used"], 1800);

    // A worker killed once it has fused the first halves; the second halves sent while it is
    // away (the broker keeps them on its session); then started again on its history.
    let restart_db = db("restart.db");
    let mut killed = Worker::start_with(&url, "restart-worker", 30, &["--db", &restart_db]);
    publish_in_turn(&first, &url);
    // Killed once its history holds every bearing sent.
    let start = Instant::now();
    loop {
        let out = Command::new(FOXHUNT)
            .args(["history", &restart_db])
            .output()
            .expect("history");
        if String::from_utf8_lossy(&out.stdout).starts_with("bearings 900 ") {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "never stored 900: {out:?}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let before: Value = killed
        .stdout
        .try_iter()
        .last()
        .map(|l| serde_json::from_str(&l).expect("JSON"))
        .expect("an update before the kill");
    killed.child.kill().expect("kill");
    let _ = killed.child.wait();
    publish_in_turn(&second, &url);
    let again = Worker::start_with(&url, "restart-worker", 3, &["--db", &restart_db]);
    let first_line = again
        .stdout
        .recv_timeout(Duration::from_secs(20))
        .expect("an update");
    let (resumed, err) = again.finish();
    eprintln!("{}", err.join("\n"));
    assert!(
        err.iter()
            .any(|l| l.starts_with("history: 900 bearings resumed")),
        "{err:?}"
    );
    // Its first update holds the bearings it had before (and perhaps some new ones).
    let first_update: Value = serde_json::from_str(&first_line).expect("JSON");
    assert!(first_update["used"].as_u64() >= before["used"].as_u64());
    // The same bearings in the same order through the same path: the very fix.
    assert_eq!(resumed["used"], 1800);
    assert_eq!(
        resumed["emitters"], whole["emitters"],
        "the fix after the restart is the uninterrupted run's"
    );
    assert_same_fix(&resumed, &recorded(&files));
}

/// The stations' captures again on a second channel, 433.000 MHz (shard 1 of 2, where
/// 433.920 is shard 0): files of their own in `dir`.
fn second_channel(files: &[PathBuf]) -> Vec<PathBuf> {
    files
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(f).expect("read");
            assert!(text.contains("<FREQUENCY>433.92"), "a 433.92 MHz capture");
            let p = f.with_file_name(format!(
                "{}-b.xml",
                f.file_stem().expect("stem").to_string_lossy()
            ));
            std::fs::write(&p, text.replace("<FREQUENCY>433.92", "<FREQUENCY>433.00"))
                .expect("write");
            p
        })
        .collect()
}

/// Publish `files` one after the other for `shards` workers, each acknowledged before the
/// next.
fn publish_sharded(files: &[PathBuf], url: &str, shards: u32) {
    for f in files {
        let id = f.file_stem().expect("stem").to_string_lossy();
        let out = Command::new(FOXHUNT)
            .arg("publish")
            .arg(f)
            .args(["--mqtt", url, "--shards", &shards.to_string()])
            .args(["--client-id", &format!("test-{id}")])
            .output()
            .expect("publish");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The number after `key` in a worker's notes.
fn noted(err: &[String], key: &str) -> Option<u64> {
    err.iter().find_map(|l| {
        let rest = l.split(key).nth(1)?;
        rest.split(',').next()?.trim().parse().ok()
    })
}

#[test]
fn two_sharded_workers_fuse_each_channel_once_and_one_restarted_resumes() {
    let _one_broker = serial();
    let broker = Broker::start("shards");
    let x = station_files(&broker.dir);
    let y = second_channel(&x);
    let [x1, x2] = halves(&x);
    let [y1, y2] = halves(&y);
    let url = broker.url("net");
    let db = broker.dir.join("shard-0.db").display().to_string();
    // Shard 0 (433.920) keeps a history and is killed half way; shard 1 (433.000) runs
    // throughout, quiet long enough to outlast the restart.
    let mut zero = Worker::start_with(&url, "shard-0", 30, &["--mqtt-shard", "0/2", "--db", &db]);
    let one = Worker::start_with(&url, "shard-1", 10, &["--mqtt-shard", "1/2"]);
    publish_sharded(&[x1.clone(), y1.clone()].concat(), &url, 2);
    let start = Instant::now();
    loop {
        let out = Command::new(FOXHUNT)
            .args(["history", &db])
            .output()
            .expect("history");
        if String::from_utf8_lossy(&out.stdout).starts_with("bearings 900 ") {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "never stored 900: {out:?}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    zero.child.kill().expect("kill");
    let _ = zero.child.wait();
    publish_sharded(&[x2, y2].concat(), &url, 2);
    let again = Worker::start_with(&url, "shard-0", 3, &["--mqtt-shard", "0/2", "--db", &db]);
    let (zero_fix, zero_err) = again.finish();
    let (one_fix, one_err) = one.finish();
    eprintln!("{}\n--\n{}", zero_err.join("\n"), one_err.join("\n"));
    // Each worker took its own channel's bearings, every one once, and none of the other's
    // (its topics are not subscribed to, so not even a misrouted one arrives).
    assert!(
        zero_err
            .iter()
            .any(|l| l.starts_with("history: 900 bearings resumed")),
        "{zero_err:?}"
    );
    assert_eq!(noted(&zero_err, "mqtt: bearings "), Some(900));
    assert_eq!(noted(&one_err, "mqtt: bearings "), Some(1800));
    for err in [&zero_err, &one_err] {
        assert_eq!(noted(err, "other shard "), Some(0), "{err:?}");
        assert_eq!(noted(err, "duplicates "), Some(0), "{err:?}");
    }
    let freqs = |v: &Value| -> Vec<String> {
        v["emitters"]
            .as_array()
            .expect("emitters")
            .iter()
            .map(|e| format!("{:.3}", e["freq_mhz"].as_f64().unwrap_or(0.0)))
            .collect()
    };
    assert_eq!(freqs(&zero_fix), vec!["433.920"]);
    assert_eq!(freqs(&one_fix), vec!["433.000"]);
    // The restarted shard's fix is its channel's recorded fix (nothing lost or doubled:
    // 1 800 bearings), and so is the other's.
    assert_eq!(zero_fix["used"], 1800);
    assert_eq!(one_fix["used"], 1800);
    assert_same_fix(&zero_fix, &recorded(&x));
    assert_same_fix(&one_fix, &recorded(&y));
}

#[test]
fn a_drone_s_stations_through_the_broker_track_as_the_recording_does() {
    let _one_broker = serial();
    let broker = Broker::start("track");
    let xml = broker.dir.join("drone.xml");
    common::simulate("move-fixed-turning", Some(1), &xml);
    let stations = broker.dir.join("drone.stations.toml");
    let stations = stations.to_str().expect("path");
    let url = broker.url("drone");
    let tracker = Worker::start_command(
        &["track", "--json", "--stations", stations],
        &url,
        "track-worker",
        3,
        &[],
    );
    published(publish(&xml, &url, None));
    let (live, err) = tracker.finish_all();
    eprintln!("{}", err.join("\n"));
    let out = Command::new(FOXHUNT)
        .args(["track", "--json", "--stations", stations])
        .arg(&xml)
        .output()
        .expect("track");
    assert!(out.status.success());
    let recorded: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let recorded = recorded["tracks"][0]["points"].as_array().expect("points");
    // The drone's true track, every second of the run.
    let truth: Vec<[f64; 2]> = std::fs::read_to_string(xml.with_extension("truth.csv"))
        .expect("truth")
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
            [c[3], c[4]]
        })
        .collect();
    // Rmse against the truth after the first minute (the tracker's warm-up).
    let rmse = |points: &[Value]| {
        let e: Vec<f64> = points
            .iter()
            .filter_map(|p| {
                let t = (p["t_ms"].as_f64()? / 1000.0).round() as usize;
                let x = truth.get(t).filter(|_| t >= 60)?;
                Some((p["east_m"].as_f64()? - x[0]).hypot(p["north_m"].as_f64()? - x[1]))
            })
            .collect();
        (
            (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt(),
            e.len(),
        )
    };
    let ((live_rmse, n_live), (file_rmse, n_file)) = (rmse(&live), rmse(recorded));
    println!(
        "through the broker: {} updates, rmse {live_rmse:.0} m over {n_live}; the recording: \
         {} updates, rmse {file_rmse:.0} m over {n_file}",
        live.len(),
        recorded.len()
    );
    // The broker delivers the four stations' records in its own batches and a live line
    // closes an update when nothing new comes, so updates may split where the recording's
    // did not and the particles' draws differ: the same bearings, tracked as well within the
    // run-to-run spread of this tracker's rmse (about a fifth, docs/src/tracking.md), 1.3x.
    assert!(n_live >= n_file, "{n_live} points against {n_file}");
    assert!(
        live_rmse <= 1.3 * file_rmse,
        "{live_rmse} against {file_rmse}"
    );
}

/// `GET path` of a local HTTP server at `addr` (`http://HOST:PORT/`): the body.
fn http_get(addr: &str, path: &str) -> String {
    use std::io::{Read, Write};
    let host = addr.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).expect("connect to serve");
    write!(s, "GET {path} HTTP/1.0\r\nHost: {host}\r\n\r\n").expect("request");
    let mut text = String::new();
    s.read_to_string(&mut text).expect("response");
    text.split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .expect("a body")
}

#[test]
fn the_live_map_follows_three_stations_through_the_broker() {
    let _one_broker = serial();
    let broker = Broker::start("serve");
    let files = station_files(&broker.dir);
    let url = broker.url("map");
    let mut child = Command::new(FOXHUNT)
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--mqtt",
            &url,
            "--mqtt-client-id",
        ])
        // 10 s without a bearing: three publishers started on a loaded 2-core machine were
        // once slower than 3 s to begin, and the map stopped before their bearings came.
        .args(["serve-test", "--quiet-exit", "10", "--linger", "60"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run serve --mqtt");
    let stderr = common::lines(child.stderr.take().expect("stderr"));
    let next = || {
        stderr
            .recv_timeout(Duration::from_secs(30))
            .expect("serve's notes")
    };
    // It subscribes before it serves: every bearing published from now on reaches the map.
    let addr = loop {
        let l = next();
        if let Some(a) = l.strip_prefix("foxhunt serve: ") {
            break a.to_string();
        }
    };
    publish_all(&files, &url, None);
    loop {
        let l = next();
        if l.contains("input ended") {
            assert!(l.contains("after 1800 bearings"), "{l}");
            break;
        }
    }
    let state: Value = serde_json::from_str(&http_get(&addr, "/state")).expect("JSON state");
    let _ = child.kill();
    let _ = child.wait();
    assert_eq!(state["bearings"], 1800);
    assert_eq!(state["done"], true);
    // The three masts on the map, and the fix the recorded files give.
    assert_eq!(
        state["stations"].as_array().map(Vec::len),
        Some(3),
        "{state}"
    );
    let file = recorded(&files);
    let (at, f) = (&state["emitters"][0]["at"], &file["emitters"][0]);
    let num = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let apart = ((num(&at[0]) - num(&f["lat"])) * 111_200.0)
        .hypot((num(&at[1]) - num(&f["lon"])) * 75_800.0);
    println!("the map's fix {apart:.3} m from the recorded files'");
    // The broker's bearings pass the bridge's clock hold as the files' do (the fusion is the
    // same): the same fix, within 1 % of its ellipse's minor axis.
    assert!(
        apart < 0.01 * num(&f["ellipse"]["minor_m"]),
        "{apart} m apart"
    );
}

/// `foxhunt perf --mqtt URL LOAD RUN` run to success: its table row's cells (the cell
/// before the first `|` empty, so the first column is cell 1).
fn perf_row(url: &str, load: &[&str], run: &[&str]) -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(["perf", "--mqtt", url])
        .args(load)
        .args(run)
        .output()
        .expect("run foxhunt perf");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    text.lines()
        .last()
        .expect("a table row")
        .split('|')
        .map(|c| c.trim().to_string())
        .collect()
}

/// A cell of one figure per worker ("a + b"), its figures.
fn per_worker<T: std::str::FromStr>(cell: &str) -> Vec<T> {
    cell.split('+')
        .map(|c| c.trim().parse().ok().expect("a figure per worker"))
        .collect()
}

#[test]
fn the_load_harness_shards_to_pinned_workers_and_counts_every_bearing_once() {
    let _one_broker = serial();
    let broker = Broker::start("load");
    // 16 channels: the hash gives each of two shards some (10/6).
    let row = perf_row(
        &broker.url("load"),
        &["--stations", "8", "--channels", "16", "--rate-hz", "10"],
        &["--seconds", "3", "--workers", "2", "--pin-workers"],
    );
    // | stations | channels | rate | bearings/s | workers | sent | taken | fixes | updates |
    // worker CPU s | ...: 8 x 16 x 10 x 3 = 3 840 bearings, each taken by one worker; enough
    // solves that each worker's processor time shows in the table's tenths of a second (four
    // stations at 5 Hz, once the live search started from the last fix, left one at 0.0).
    assert_eq!(row[5], "2 (pinned)");
    assert_eq!(
        (row[6].as_str(), row[7].as_str()),
        ("3840", "3840"),
        "sent and taken"
    );
    let cpu: Vec<f64> = per_worker(&row[10]);
    assert_eq!(cpu.len(), 2, "one figure per worker: {}", row[10]);
    assert!(cpu.iter().all(|c| *c > 0.0), "{cpu:?}");
}

/// One channel, two workers: the hash gives the channel to one shard and the other worker is
/// told nothing. It ends without a fix (exit 1), and the harness counts it idle, not failed.
#[test]
fn the_load_harness_counts_a_worker_with_an_empty_shard_idle() {
    let _one_broker = serial();
    let broker = Broker::start("idle");
    let row = perf_row(
        &broker.url("idle"),
        &["--stations", "3", "--channels", "1", "--rate-hz", "2"],
        &["--seconds", "2", "--workers", "2"],
    );
    // 3 x 1 x 2 x 2 = 12 bearings, every one taken by the worker that owns the channel; the
    // other's one update is the one that said nothing came (before, the harness stopped on
    // it: "a worker failed").
    assert_eq!(
        (row[6].as_str(), row[7].as_str()),
        ("12", "12"),
        "sent and taken"
    );
    let updates: Vec<u64> = per_worker(&row[9]);
    assert_eq!(updates.len(), 2, "{}", row[9]);
    assert!(
        updates.iter().any(|u| *u <= 1) && updates.iter().any(|u| *u > 1),
        "{updates:?}"
    );
}

/// Stations sending on their own clocks (`--stagger`): each bearing has a time of its own, and
/// every one after its channel's first fix is reached by a fix (a worker counts time from its
/// first bearing: were the first tick staggered too, a station other than the first arriving
/// first would leave the last ones unreached, counted as `no fix`).
#[test]
fn the_load_harness_staggers_its_stations_and_reaches_every_bearing() {
    let _one_broker = serial();
    let broker = Broker::start("stagger");
    let row = perf_row(
        &broker.url("stagger"),
        &["--stations", "4", "--channels", "2", "--rate-hz", "5"],
        &["--seconds", "2", "--stagger"],
    );
    assert_eq!(row[3], "5 (staggered)");
    // 4 x 2 x 5 x 2 = 80 bearings.
    assert_eq!(
        (row[6].as_str(), row[7].as_str()),
        ("80", "80"),
        "sent and taken"
    );
    assert_eq!(row[15], "0", "bearings no fix reached");
    let p99: f64 = row[13].parse().expect("a p99");
    assert!(p99 > 0.0, "{p99}");
}

#[test]
fn a_worker_the_broker_gives_nothing_says_so() {
    let _one_broker = serial();
    let broker = Broker::start("empty");
    let w = Worker::start_with(
        &broker.url("quiet"),
        "empty-worker",
        1,
        &["--mqtt-shard", "1/2"],
    );
    let (status, out, err) = w.end();
    println!("{err:?} {out:?}");
    // No fix: exit 1, and the reason is the broker's silence on its shard's topics.
    assert_eq!(status.code(), Some(1), "{err:?}");
    let said = err.iter().chain(&out).any(|l| {
        l.contains("no bearing came through the broker on quiet/bearings/1/#: nothing to fuse")
    });
    assert!(said, "{err:?} {out:?}");
}

/// A window that holds fewer than two bearings a station: the worker names the channel and
/// the `--mqtt-keep` it needs (each station's offset takes about one bearing; 256 from 200
/// stations left too few to estimate the noise in 7-8 % of a network's solves).
#[test]
fn a_window_too_small_for_its_stations_is_named_with_the_keep_it_needs() {
    let _one_broker = serial();
    let broker = Broker::start("crowded");
    let files = station_files(&broker.dir);
    let url = broker.url("crowded");
    let w = Worker::start_with(&url, "crowded-worker", 3, &["--mqtt-keep", "5"]);
    // Paced, so that the stations' bearings come interleaved, as a network's do (one file
    // after another would fill the window with one station's).
    publish_all(&files, &url, Some(300));
    let (_, _, err) = w.end();
    println!("{err:?}");
    let named: Vec<&String> = err
        .iter()
        .filter(|l| l.contains("its window of 5 bearings (--mqtt-keep) filled with 3 stations'"))
        .collect();
    assert_eq!(named.len(), 1, "named once: {err:?}");
    assert!(
        named[0].starts_with("channel 433.920 MHz: ") && named[0].ends_with("keep at least 6"),
        "{}",
        named[0]
    );
}
