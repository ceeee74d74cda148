//! A run's history (`foxhunt locate --db FILE`, docs/src/history.md): stored and replayed to
//! the same fix, exported, windowed, resumed by a worker started again, and the files that are
//! not a foxhunt history refused untouched. The restart through a real broker is in mqtt.rs.

use foxhunt_bridge::nmea::LatLon;
use foxhunt_sim::runs::network::{NetworkCondition, capture};
use serde_json::Value;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const FOXHUNT: &str = env!("CARGO_BIN_EXE_foxhunt");

/// The bundled sample drive.
fn sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures/aoa-drive.nmea")
}

/// A fresh directory of this test's own.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("foxhunt-history-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn foxhunt(args: &[&str]) -> Output {
    Command::new(FOXHUNT).args(args).output().expect("run")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The JSON report of a run that must give a fix.
fn fix(args: &[&str]) -> Value {
    let out = foxhunt(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.lines().last().expect("a line")).expect("JSON")
}

/// Two fixes of the same bearings agree: the same bearings used, and the emitter within 1 %
/// of the ellipse's semi-minor axis, the axes within 1 %. A replay's local frame starts at
/// its first bearing's station, not at the drive's first GPS fix, so the solver starts from
/// another point and stops at another point of its tolerance (measured: the same position to
/// the printed 1e-6 degrees on the sample drive).
fn assert_same_fix(a: &Value, b: &Value) {
    assert_eq!(a["used"], b["used"], "bearings used");
    let (l, f) = (&a["emitters"][0], &b["emitters"][0]);
    let num = |v: &Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let apart = ((num(l, "lat") - num(f, "lat")) * 111_200.0)
        .hypot((num(l, "lon") - num(f, "lon")) * 75_800.0);
    eprintln!(
        "{:.7}, {:.7} and {:.7}, {:.7}: {apart:.3} m apart",
        num(l, "lat"),
        num(l, "lon"),
        num(f, "lat"),
        num(f, "lon")
    );
    assert!(
        apart < 0.01 * num(&f["ellipse"], "minor_m"),
        "{apart} m apart"
    );
    for k in ["major_m", "minor_m"] {
        let (x, y) = (num(&l["ellipse"], k), num(&f["ellipse"], k));
        assert!((x / y - 1.0).abs() < 0.01, "{k}: {x} {y}");
    }
}

/// `foxhunt history FILE ARGS`: its summary line.
fn summary(db: &Path, args: &[&str]) -> String {
    let mut all = vec!["history", s(db)];
    all.extend_from_slice(args);
    let out = foxhunt(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

#[test]
fn a_capture_stored_replays_to_its_fix_and_exports() {
    let d = dir("round");
    let db = d.join("run.db");
    let drive = sample();
    let stored = fix(&["locate", s(&drive), "--db", s(&db), "--json"]);
    assert_eq!(stored["used"], 60);
    let replayed = fix(&["locate", "--db", s(&db), "--json"]);
    assert_same_fix(&replayed, &stored);
    assert_eq!(
        summary(&db, &[]),
        "bearings 60 (stations 1, channels 1), from 2026-06-01T10:00:00.5Z to \
         2026-06-01T10:00:59.5Z; fixes 1 in 1 updates"
    );
    // The same capture again: its bearings are there already (stored once), its fix is a
    // second update.
    fix(&["locate", s(&drive), "--db", s(&db), "--json"]);
    assert!(
        summary(&db, &[]).starts_with("bearings 60 ")
            && summary(&db, &[]).ends_with("fixes 2 in 2 updates"),
        "{}",
        summary(&db, &[])
    );

    // CSV: a line per bearing in the order taken, a line per fix row.
    let prefix = d.join("out");
    let geojson = d.join("out.geojson");
    summary(&db, &["--csv", s(&prefix), "--geojson", s(&geojson)]);
    let bearings = std::fs::read_to_string(d.join("out.bearings.csv")).expect("bearings.csv");
    let lines: Vec<&str> = bearings.lines().collect();
    assert_eq!(lines.len(), 61, "header and 60 bearings");
    assert!(lines[0].starts_with("time_ms,time,channel,station,lat,lon,bearing_deg"));
    let times: Vec<i64> = lines[1..]
        .iter()
        .map(|l| {
            l.split(',')
                .next()
                .and_then(|t| t.parse().ok())
                .expect("time_ms")
        })
        .collect();
    assert!(times.windows(2).all(|w| w[1] - w[0] == 1000), "{times:?}");
    assert!(lines[1].contains(",433.920,pfoxb,"), "{}", lines[1]);
    let fixes = std::fs::read_to_string(d.join("out.fixes.csv")).expect("fixes.csv");
    let rows: Vec<Vec<&str>> = fixes
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 2);
    let lat: f64 = rows[0][9].parse().expect("lat");
    assert!((lat - stored["emitters"][0]["lat"].as_f64().expect("lat")).abs() < 1e-7);
    assert_eq!(rows[0][5], "emitter");
    assert_eq!(
        rows[0][1], "1780308059500",
        "a fix's time is its newest bearing's"
    );

    // GeoJSON: each bearing a point, each fix a point and its ellipse.
    let g: Value =
        serde_json::from_str(&std::fs::read_to_string(&geojson).expect("geojson")).expect("JSON");
    let features = g["features"].as_array().expect("features");
    let of = |kind: &str| {
        features
            .iter()
            .filter(|f| f["properties"]["feature"] == kind)
            .count()
    };
    assert_eq!((of("bearing"), of("fix"), of("ellipse")), (60, 2, 2));
    let ring = features
        .iter()
        .find(|f| f["properties"]["feature"] == "ellipse")
        .map(|f| {
            f["geometry"]["coordinates"][0]
                .as_array()
                .expect("ring")
                .clone()
        })
        .expect("an ellipse");
    assert_eq!(ring.first(), ring.last(), "a closed ring");
    // The ring lies about the fix: its farthest point a semi-major axis away.
    let (lat0, lon0) = (
        stored["emitters"][0]["lat"].as_f64().expect("lat"),
        stored["emitters"][0]["lon"].as_f64().expect("lon"),
    );
    let far = ring
        .iter()
        .map(|p| {
            let (lon, lat) = (p[0].as_f64().expect("lon"), p[1].as_f64().expect("lat"));
            ((lat - lat0) * 111_200.0).hypot((lon - lon0) * 75_800.0)
        })
        .fold(0.0, f64::max);
    let major = stored["emitters"][0]["ellipse"]["major_m"]
        .as_f64()
        .expect("major");
    // 111.2 and 75.8 km per degree at 47 N: within 1 % of the ellipse's own figure.
    assert!(
        (far / major - 1.0).abs() < 0.01,
        "{far} m against {major} m"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_window_replays_only_its_bearings() {
    let d = dir("window");
    let db = d.join("run.db");
    fix(&["locate", s(&sample()), "--db", s(&db), "--json"]);
    // 10:00:30 (RFC 3339, another zone) to 10:00:45 (ms): the bearings of 10:00:30.5 to
    // 10:00:44.5.
    let window = [
        "--since",
        "2026-06-01T12:00:30+02:00",
        "--until",
        "1780308045000",
    ];
    let mut args = vec!["locate", "--db", s(&db), "--json"];
    args.extend_from_slice(&window);
    let part = fix(&args);
    assert_eq!(part["used"], 15, "{part}");
    let span = &part["emitters"][0]["time_span_s"];
    eprintln!("window fix: {}; span {span}", part["emitters"][0]);
    assert!(summary(&db, &window).starts_with("bearings 15 "));
    let prefix = d.join("w");
    let mut args = vec!["--csv", s(&prefix)];
    args.extend_from_slice(&window);
    summary(&db, &args);
    let text = std::fs::read_to_string(d.join("w.bearings.csv")).expect("csv");
    assert_eq!(text.lines().count(), 16);
    assert!(
        text.lines()
            .nth(1)
            .expect("first")
            .starts_with("1780308030500,")
    );
    // A period without bearings: no fix, exit status 1.
    let out = foxhunt(&["locate", "--db", s(&db), "--since", "2026-06-02T00:00:00Z"]);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    // --since applies to a replay only, and must come before --until.
    for args in [
        vec!["locate", s(&sample()), "--db", s(&db), "--since", "0"],
        vec!["locate", "--since", "0"],
        vec!["locate", "--db", s(&db), "--since", "5", "--until", "5"],
        vec!["locate", "--db", s(&db), "--since", "yesterday"],
    ] {
        let out = foxhunt(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {out:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Three KrakenSDR masts' records, interleaved as they were taken (network-fixed3, run 1).
fn network_lines() -> Vec<String> {
    let origin = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    let (bytes, _, _) = capture(NetworkCondition::Fixed3, 1, origin).expect("capture");
    String::from_utf8(bytes)
        .expect("ASCII")
        .lines()
        .map(|l| format!("{l}\n"))
        .collect()
}

/// `foxhunt locate - --db FILE --json` fed `lines` on standard input until it closes: its
/// updates.
fn live(db: &Path, lines: &[String]) -> Vec<Value> {
    let mut child = Command::new(FOXHUNT)
        .args(["locate", "-", "--json", "--db", s(db)])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("locate -");
    let mut stdin = child.stdin.take().expect("stdin");
    let text: String = lines.concat();
    let writer = std::thread::spawn(move || {
        let _ = stdin.write_all(text.as_bytes());
    });
    let out = child.wait_with_output().expect("wait");
    writer.join().expect("writer");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect()
}

#[test]
fn a_live_worker_started_again_resumes_its_channels() {
    let d = dir("resume");
    let lines = network_lines();
    assert_eq!(lines.len(), 1800);
    let whole = live(&d.join("whole.db"), &lines);
    let once = whole.last().expect("an update");
    assert_eq!(once["used"], 1800);
    // The same line stopped half way and started again on the same history.
    let db = d.join("restart.db");
    let first = live(&db, &lines[..900]);
    assert_eq!(first.last().expect("an update")["used"], 900);
    let second = live(&db, &lines[900..]);
    let again = second.last().expect("an update");
    assert_same_fix(again, once);
    // Every bearing stored once, in both.
    for f in ["whole.db", "restart.db"] {
        assert!(
            summary(&d.join(f), &[]).starts_with("bearings 1800 (stations 3, channels 1)"),
            "{f}: {}",
            summary(&d.join(f), &[])
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The exit status and standard error of `args`, and whether `file` is unchanged.
fn refused(args: &[&str], file: &Path) -> (Option<i32>, String, bool) {
    let before = std::fs::read(file).expect("read");
    let out = foxhunt(args);
    let after = std::fs::read(file).expect("read");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).trim().to_string(),
        before == after,
    )
}

#[test]
fn files_that_are_no_foxhunt_history_are_refused_untouched() {
    let d = dir("refuse");
    let drive = sample();
    let text = d.join("notes.txt");
    std::fs::write(&text, "not a database\n").expect("write");
    let other = d.join("other.db");
    {
        let c = rusqlite::Connection::open(&other).expect("sqlite");
        c.execute_batch("CREATE TABLE t (x); INSERT INTO t VALUES (1);")
            .expect("table");
    }
    let newer = d.join("newer.db");
    fix(&["locate", s(&drive), "--db", s(&newer), "--json"]);
    {
        let c = rusqlite::Connection::open(&newer).expect("sqlite");
        c.execute_batch("PRAGMA user_version = 2;")
            .expect("version");
    }
    for (file, why) in [
        (&text, "is not a foxhunt history: not an SQLite database"),
        (&other, "is an SQLite database of another program"),
        (
            &newer,
            "is a foxhunt history of schema version 2; this foxhunt reads version 1",
        ),
    ] {
        for args in [
            vec!["locate", s(&drive), "--db", s(file)],
            vec!["locate", "--db", s(file)],
            vec!["history", s(file)],
        ] {
            let (code, err, same) = refused(&args, file);
            assert_eq!(code, Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "one line: {err}");
            assert!(err.contains(why), "{args:?}: {err}");
            assert!(same, "{args:?} changed {}", file.display());
        }
    }
    // A directory, and a history that is not there to replay.
    let (code, err, _) = refused(&["locate", s(&drive), "--db", s(&d)], &text);
    assert_eq!(code, Some(2), "{err}");
    let out = foxhunt(&["locate", "--db", s(&d.join("absent.db"))]);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_history_in_use_is_refused_with_status_1() {
    let d = dir("locked");
    let drive = sample();
    let db = d.join("run.db");
    fix(&["locate", s(&drive), "--db", s(&db), "--json"]);
    // Another worker writing it: a second one is refused at once.
    {
        let _writer = foxhunt_sim::outputs::history::History::open(&db).expect("the first worker");
        let (code, err, _) = refused(&["locate", s(&drive), "--db", s(&db)], &db);
        assert_eq!(code, Some(1), "{err}");
        assert!(err.contains("in use by another foxhunt worker"), "{err}");
        // Readers go on while the worker writes.
        assert!(summary(&db, &[]).starts_with("bearings 60 "));
    }
    // Another program holding SQLite's exclusive lock: readers and writers give up after
    // their wait, one line each.
    {
        let c = rusqlite::Connection::open(&db).expect("sqlite");
        // In write-ahead-log mode the exclusive lock is taken by a write, and kept.
        c.execute_batch(
            "PRAGMA locking_mode = EXCLUSIVE; BEGIN EXCLUSIVE; \
             UPDATE fixes SET method = method WHERE id = 1; COMMIT;",
        )
        .expect("lock");
        // (Not read here: closing any descriptor of the file would drop this process's
        // POSIX locks on it, SQLite's among them.)
        for args in [
            vec!["history", s(&db)],
            vec!["locate", "--db", s(&db)],
            vec!["locate", s(&drive), "--db", s(&db)],
        ] {
            let out = foxhunt(&args);
            let (code, err) = (
                out.status.code(),
                String::from_utf8_lossy(&out.stderr).trim().to_string(),
            );
            assert_eq!(code, Some(1), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "one line: {err}");
            assert!(
                err.contains("is locked by another program"),
                "{args:?}: {err}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
