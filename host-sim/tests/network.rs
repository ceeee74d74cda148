//! A network condition as a user meets it: `simulate --condition network-*` writes every
//! station's KrakenSDR XML records and the stations file, and `locate --stations` on them
//! finds the emitter and each station's offset as the simulation drew it; its GeoJSON and KML
//! carry every station.

mod common;

use std::process::Command;

use foxhunt_sim::runs::network::{NetworkCondition, simulate};

fn foxhunt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(args)
        .output()
        .expect("run foxhunt")
}

/// `simulate --condition network-reference --run RUN` into a scratch directory named `name`:
/// the directory, and the records' path (the stations file beside, `net.stations.toml`).
fn simulated(name: &str, run: &str) -> (std::path::PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("foxhunt-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    let out = dir.join("net.xml").to_str().expect("path").to_string();
    let s = foxhunt(&[
        "simulate",
        "--condition",
        "network-reference",
        "--run",
        run,
        "--out",
        &out,
    ]);
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    (dir, out)
}

#[test]
fn a_simulated_network_reads_back_with_its_stations_and_offsets() {
    let (dir, out) = simulated("network", "2");
    let out = out.as_str();
    let stations = dir.join("net.stations.toml");
    let (geo, kml) = (dir.join("net.geojson"), dir.join("net.kml"));
    let l = foxhunt(&[
        "locate",
        out,
        "--stations",
        stations.to_str().expect("path"),
        "--json",
        "--geojson",
        geo.to_str().expect("path"),
        "--kml",
        kml.to_str().expect("path"),
    ]);
    assert_eq!(
        l.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&l.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&l.stdout).expect("JSON");
    // The emitter stands at the default origin, 47.0, 8.0.
    let e = &v["emitters"][0];
    let (lat, lon) = (e["lat"].as_f64().unwrap(), e["lon"].as_f64().unwrap());
    let off_m = ((lat - 47.0) * 111_200.0).hypot((lon - 8.0) * 75_800.0);
    println!("fix {lat:.6}, {lon:.6}: {off_m:.1} m off; {}", e["ellipse"]);
    // The known-offsets bound is about 15 m and the calibrated offsets add a few metres: 60 m
    // is four times the fix's own scatter.
    assert!(off_m < 60.0, "{off_m} m off");
    // Each station's offset as drawn, within four of its reported sd (at least 0.05 degrees:
    // the records' DOA has two decimals).
    let truth = simulate(NetworkCondition::Reference, 2).drive.stations;
    let reported = v["stations"].as_array().expect("stations");
    assert_eq!(reported.len(), truth.len());
    for t in &truth {
        let r = reported
            .iter()
            .find(|r| r["id"] == t.id.as_str())
            .expect("every station reported");
        let (o, sd) = (
            r["offset_deg"].as_f64().unwrap(),
            r["offset_sd_deg"].as_f64().unwrap(),
        );
        let want = f64::from(t.offset.to_degrees());
        println!("{}: offset {o:.2} +- {sd:.2} deg, drawn {want:.2}", t.id);
        assert!((o - want).abs() < 4.0 * sd.max(0.05), "{}", t.id);
        assert_eq!(r["fixed"], true);
        assert_eq!(r["prior_from"], "reference");
    }
    // The maps: each station where it stands, fixed, with its offset.
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&geo).expect("geojson")).expect("JSON");
    let features = g["features"].as_array().expect("features");
    let on_map: Vec<&serde_json::Value> = features
        .iter()
        .filter(|f| f["properties"]["kind"] == "station")
        .collect();
    assert_eq!(on_map.len(), truth.len());
    for f in &on_map {
        let r = reported
            .iter()
            .find(|r| r["id"] == f["properties"]["id"])
            .expect("a reported station");
        assert_eq!(f["properties"]["station"], "fixed");
        let close = |a: &serde_json::Value, b: &serde_json::Value| {
            (a.as_f64().expect("number") - b.as_f64().expect("number")).abs() < 1e-5
        };
        assert!(close(&f["properties"]["offset_deg"], &r["offset_deg"]));
        assert_eq!(f["geometry"]["coordinates"][0], r["lon"]);
        assert_eq!(f["geometry"]["coordinates"][1], r["lat"]);
    }
    let k = std::fs::read_to_string(&kml).expect("kml");
    let folder = k
        .split("<Folder><name>stations</name>")
        .nth(1)
        .and_then(|s| s.split("</Folder>").next())
        .expect("a stations folder");
    for t in &truth {
        assert!(
            folder.contains(&format!(
                "<name>{}</name><description>fixed station; offset",
                t.id
            )),
            "{folder}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `foxhunt serve --stations` on a network's records, the input ended: the map's `/state`.
fn served_state(capture: &str, stations: &str) -> serde_json::Value {
    use std::io::{Read, Write};
    let (mut child, addr) =
        common::serve_ended(&["--linger", "60", "--stations", stations, capture]);
    let mut conn = std::net::TcpStream::connect(&addr).expect("connect to serve");
    write!(conn, "GET /state HTTP/1.0\r\nHost: {addr}\r\n\r\n").expect("request");
    let mut reply = String::new();
    conn.read_to_string(&mut reply).expect("reply");
    let _ = child.kill();
    let _ = child.wait();
    let body = reply.split("\r\n\r\n").nth(1).expect("a body");
    serde_json::from_str(body).expect("the state as JSON")
}

#[test]
fn the_live_map_fixes_with_the_stations_file_as_locate_does() {
    let (dir, out) = simulated("network-map", "3");
    let out = out.as_str();
    let stations = dir.join("net.stations.toml");
    let stations = stations.to_str().expect("path");
    let l = foxhunt(&["locate", out, "--stations", stations, "--json"]);
    assert_eq!(l.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&l.stdout).expect("JSON");
    let st = served_state(out, stations);
    // The map's one emitter is `locate --stations`'s (the beacon's channel calibrates, it is
    // no emitter of its own), to the digit.
    let (e, m) = (&v["emitters"][0], &st["emitters"]);
    println!("locate {}, {}; map {}", e["lat"], e["lon"], m[0]["at"]);
    assert_eq!(m.as_array().map(Vec::len), Some(1), "{m}");
    assert_eq!(m[0]["at"][0], e["lat"]);
    assert_eq!(m[0]["at"][1], e["lon"]);
    // Every mast with `locate`'s offset and where it came from.
    let (mine, theirs) = (
        st["stations"].as_array().expect("stations"),
        v["stations"].as_array().expect("stations"),
    );
    assert_eq!(mine.len(), theirs.len());
    for r in theirs {
        let s = mine
            .iter()
            .find(|s| s["id"] == r["id"])
            .expect("every station on the map");
        assert_eq!(s["offset_deg"][0], r["offset_deg"], "{s}");
        assert_eq!(s["offset_from"], r["offset_from"], "{s}");
        assert_eq!(r["prior_from"], "reference");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The advice guides a vehicle: in a network of fixed masts there is none, and `locate` says
/// so instead of telling a mast where to drive; with a car among the masts the advice is the
/// car's (its heading and place, not the last mast heard).
#[test]
fn advice_is_for_a_vehicle_and_fixed_masts_get_none() {
    let dir = std::env::temp_dir().join(format!("foxhunt-network-advice-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    for (condition, vehicle) in [("network-fixed3", false), ("network-mobile", true)] {
        let out = dir.join(format!("{condition}.xml"));
        let path = out.to_str().expect("path");
        let s = foxhunt(&[
            "simulate",
            "--condition",
            condition,
            "--out",
            path,
            "--force",
        ]);
        assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
        let stations = out.with_extension("stations.toml");
        let l = foxhunt(&[
            "locate",
            path,
            "--stations",
            stations.to_str().expect("path"),
            "--json",
        ]);
        assert!(l.status.success(), "{}", String::from_utf8_lossy(&l.stderr));
        let v: serde_json::Value = serde_json::from_slice(&l.stdout).expect("one JSON object");
        if vehicle {
            assert!(v["advice"].is_object(), "{v}");
            assert!(v["advice_error"].is_null(), "{v}");
        } else {
            assert!(v["advice"].is_null(), "{v}");
            let why = v["advice_error"].as_str().expect("why no advice");
            assert!(why.contains("no vehicle to guide"), "{why}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
