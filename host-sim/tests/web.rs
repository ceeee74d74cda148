//! The live map in a real headless browser (Debian's chromium, installed by .ci/run): a capture
//! replayed through `foxhunt serve`, the page loaded, and its DOM checked for the fix and the
//! suggested move; a screenshot is saved to target/tmp/web/live-map.png.

use std::path::{Path, PathBuf};
use std::process::{Child, Command};

mod common;
use common::{grid_osm, simulate};

fn chromium() -> PathBuf {
    for c in ["chromium", "chromium-browser"] {
        if let Ok(out) = Command::new("which").arg(c).output()
            && out.status.success()
        {
            return PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        }
    }
    panic!("no chromium on PATH: .ci/run installs Debian's chromium (apt-get install chromium)");
}

/// `foxhunt serve` on `capture` (roads from `osm`), once its input has ended: the child and its
/// address.
fn serve(capture: &Path, osm: &Path) -> (Child, String) {
    // The page's event stream ends with `end` (the input has ended), which lets the browser
    // finish loading; the server stays until the test stops it.
    let linger = std::ffi::OsStr::new("300");
    let (child, addr) = common::serve_ended(&[
        std::ffi::OsStr::new("--linger"),
        linger,
        std::ffi::OsStr::new("--roads"),
        osm.as_os_str(),
        capture.as_os_str(),
    ]);
    (child, format!("http://{addr}"))
}

fn browser(dir: &Path, what: &[&str], url: &str) -> std::process::Output {
    let profile = dir.join(format!("profile-{}", what[0].trim_start_matches("--")));
    let _ = std::fs::remove_dir_all(&profile);
    Command::new("timeout")
        .arg("120")
        .arg(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--window-size=1200,800",
            "--virtual-time-budget=3000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(what)
        .arg(url)
        .output()
        .expect("run chromium")
}

/// The page's DOM once `capture` (with the streets of `osm`) has been served to the end.
fn page_dom(dir: &Path, capture: &Path, osm: &Path) -> String {
    let (mut child, url) = serve(capture, osm);
    let out = browser(dir, &["--dump-dom"], &url);
    let _ = child.kill();
    let _ = child.wait();
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn the_live_map_shows_the_fix_and_the_suggested_move() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web");
    std::fs::create_dir_all(&dir).unwrap();
    // The first half of the sample drive: a fix, but not yet good enough, so a move is shown.
    let sample =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures/aoa-drive.nmea");
    let text = std::fs::read_to_string(sample).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let half = lines[..lines.len() * 11 / 20].join("\n") + "\n";
    let capture = dir.join("half-drive.nmea");
    std::fs::write(&capture, half).unwrap();
    let osm = dir.join("grid.osm");
    grid_osm(&osm);

    let dom = page_dom(&dir, &capture, &osm);
    assert!(
        dom.contains("data-ended=\"1\""),
        "the page did not hear that the input ended:\n{dom}"
    );
    assert!(
        dom.contains("data-emitters=\"1\""),
        "no emitter on the page:\n{dom}"
    );
    assert!(dom.contains("Emitter 1") && dom.contains("CEP50"), "{dom}");
    let reason = dom
        .split("data-reason=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .unwrap_or("");
    assert!(
        [
            "widen-angle",
            "get-closer",
            "calibration-leg",
            "more-bearings"
        ]
        .contains(&reason),
        "suggested move's reason `{reason}`:\n{dom}"
    );
    // The move is a road turn (the extract was given).
    assert!(
        dom.contains("at the next junction"),
        "no road turn in the advice:\n{dom}"
    );

    let (mut child, url) = serve(&capture, &osm);
    let png = dir.join("live-map.png");
    let _ = std::fs::remove_file(&png);
    let shot = format!("--screenshot={}", png.display());
    let out = browser(&dir, &[shot.as_str()], &url);
    let _ = child.kill();
    let _ = child.wait();
    let size = std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0);
    assert!(
        size > 20_000,
        "screenshot {} is {size} bytes: {}",
        png.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("screenshot: {}", png.display());
}

#[test]
fn the_live_map_shows_every_emitters_verdict_and_whom_the_move_is_for() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web-two");
    std::fs::create_dir_all(&dir).unwrap();
    let whole = dir.join("two.nmea");
    let made = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "simulate",
            "--condition",
            "two-emitters",
            "--force",
            "--out",
        ])
        .arg(&whole)
        .output()
        .expect("run foxhunt simulate");
    assert!(made.status.success(), "{made:?}");
    // 100 bearings: emitter 1 (CEP50 77 m) is good enough, emitter 2 (137 m) is not.
    let text = std::fs::read_to_string(&whole).unwrap();
    let part: String = text.lines().take(200).map(|l| format!("{l}\n")).collect();
    let capture = dir.join("two-part.nmea");
    std::fs::write(&capture, part).unwrap();
    let osm = dir.join("grid.osm");
    grid_osm(&osm);
    let dom = page_dom(&dir, &capture, &osm);
    assert!(dom.contains("data-ended=\"1\""), "{dom}");
    assert!(dom.contains("data-emitters=\"2\""), "two emitters:\n{dom}");
    assert!(
        dom.contains("data-emitter=\"1\" data-good=\"true\"")
            && dom.contains("data-emitter=\"2\" data-good=\"false\""),
        "each emitter's verdict:\n{dom}"
    );
    assert!(
        dom.contains("data-for=\"2\"") && dom.contains("for emitter 2<"),
        "the move is for emitter 2:\n{dom}"
    );
}

/// `$BODY*CS\r\n`: a sentence whose checksum holds, whatever its fields say.
fn sentence(body: &str) -> String {
    let cs = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("${body}*{cs:02X}\r\n")
}

#[test]
fn the_live_map_shows_the_df_units_own_fix_beside_the_hosts() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web-unit");
    std::fs::create_dir_all(&dir).unwrap();
    let sample =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures/aoa-drive.nmea");
    let text = std::fs::read_to_string(sample).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let half = lines[..lines.len() * 11 / 20].join("\n") + "\n";
    // The drive's first half, then what the DF unit said about the same bearings, with unit
    // sentences that pass their checksum but not their fields (each must be counted and
    // ignored), and one that fails its checksum (the stream's loss, not the unit's).
    let said = String::from_utf8(common::unit_output(half.as_bytes())).expect("ASCII");
    let last = said
        .lines()
        .rev()
        .find(|l| l.starts_with("$PFOXF") && l.contains(",A*"))
        .expect("the unit sent a valid fix");
    let cep50 = last.split(',').nth(9).expect("the CEP50 field").to_string();
    let broken = [
        "PFOXF,broken",
        "PFOXF,100059.50,9999.000000,N,00800.979846,E,146.2,8.5,54.2,36.5,60,60,1.20,A",
        "PFOXF,100059.50,4700.446054,N,00800.979846,E,-1.0,8.5,54.2,36.5,60,60,1.20,A",
        "PFOXS,12,x,0,0,0,0,0,0,P",
        "PFOXL,1,2",
    ];
    let mut capture = half;
    let (first, rest) = said.split_at(said.len() / 2);
    capture += first;
    for b in &broken {
        capture += &sentence(b);
    }
    capture += "$PFOXF,100100.50,,,,,,,,,2,60,1.20,S*00\r\n";
    capture += rest;
    let path = dir.join("drive-and-unit.nmea");
    std::fs::write(&path, capture).unwrap();
    let osm = dir.join("grid.osm");
    grid_osm(&osm);

    let dom = page_dom(&dir, &path, &osm);
    assert!(dom.contains("data-ended=\"1\""), "{dom}");
    // The host's own fix is still there.
    assert!(dom.contains("data-emitters=\"1\""), "{dom}");
    // The unit's latest valid fix, with the CEP50 it sent, and the malformed ones counted.
    assert!(
        dom.contains(&format!("data-cep50=\"{cep50}\"")),
        "the unit's CEP50 {cep50} m (from {last}) not on the page:\n{dom}"
    );
    assert!(
        dom.contains("data-status=\"A\"") && dom.contains(&format!("CEP50 <b>{cep50} m</b>")),
        "{dom}"
    );
    assert!(
        dom.contains(&format!("data-malformed=\"{}\"", broken.len())),
        "{} malformed unit sentences:\n{dom}",
        broken.len()
    );
    // Its marker (a diamond, not the emitters' discs) is on the map.
    assert!(dom.contains("unit-fix"), "no unit marker:\n{dom}");
}

#[test]
fn the_live_map_draws_fixed_stations_as_squares() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web-stations");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("network.xml");
    simulate("network-mobile", None, &path);
    let osm = dir.join("grid.osm");
    grid_osm(&osm);
    let dom = page_dom(&dir, &path, &osm);
    assert!(dom.contains("data-ended=\"1\""), "{dom}");
    // Two masts as squares (each titled with its id); the car is drawn as a dot, not a square.
    assert_eq!(
        dom.matches("leaflet-marker-icon station-fixed").count(),
        2,
        "{dom}"
    );
    for id in ["mast-1", "mast-2"] {
        assert!(
            dom.contains(&format!("title=\"{id}\"")),
            "{id} not on the page:\n{dom}"
        );
    }
}

#[test]
fn the_live_map_tracks_an_emitter_that_moves_with_its_ellipse_and_velocity() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web-moving");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("drone.xml");
    // A drone flying east at 12 m/s over its last minutes, seen by four masts.
    simulate("move-fixed-turning", Some(1), &path);
    let osm = dir.join("grid.osm");
    grid_osm(&osm);
    let dom = page_dom(&dir, &path, &osm);
    assert!(dom.contains("data-ended=\"1\""), "{dom}");
    // No fix for a moving emitter: its track instead, one per channel.
    assert!(dom.contains("data-emitters=\"0\""), "{dom}");
    assert!(dom.contains("data-tracks=\"1\""), "{dom}");
    let speed: f64 = dom
        .split("data-speed=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .expect("the track's speed on the page");
    println!("speed on the map {speed} m/s (truth 12 m/s)");
    // The tracker's velocity at the end, from 1 Hz bearings of 2 degrees at 3-6 km: within
    // a factor of two of the truth (a still emitter would show about 0).
    assert!((6.0..24.0).contains(&speed), "speed {speed} m/s");
    let points: usize = dom
        .split("data-points=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .expect("the track's points");
    assert!(points > 100, "{points} points on the track line");
}
