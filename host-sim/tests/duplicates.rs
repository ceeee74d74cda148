//! Evidence counted once, however an adversary duplicates it: for every drive format and
//! several runs' noise, a log given twice as two inputs, a log appended to itself, its second
//! half replayed, and a KrakenSDR's CSV and XML logs of the same records give the fix of the
//! log read once (same position and ellipse), with the copies counted as `repeated`.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn foxhunt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(args)
        .output()
        .expect("run foxhunt")
}

/// `locate --json` on `captures`: the report, which must hold a fix.
fn locate(captures: &[&Path]) -> Value {
    let mut args = vec!["locate", "--json"];
    args.extend(captures.iter().map(|p| p.to_str().expect("path")));
    let out = foxhunt(&args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{captures:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// A simulated drive of `run`'s noise in `format`.
fn drive(dir: &Path, format: &str, run: u32) -> PathBuf {
    let ext = match format {
        "kraken-csv" => "csv",
        "kraken-xml" => "xml",
        _ => "nmea",
    };
    let path = dir.join(format!("{format}-{run}.{ext}"));
    let out = foxhunt(&[
        "simulate",
        "--scenario",
        "aoa-drive",
        "--format",
        format,
        "--run",
        &run.to_string(),
        "--out",
        path.to_str().expect("path"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

/// The fix's position and ellipse, the numbers a duplicate must leave alone.
fn fix(v: &Value) -> [f64; 4] {
    let e = &v["emitters"][0];
    let n = |x: &Value| x.as_f64().unwrap_or_else(|| panic!("a number: {v}"));
    [
        n(&e["lat"]),
        n(&e["lon"]),
        n(&e["ellipse"]["major_m"]),
        n(&e["ellipse"]["minor_m"]),
    ]
}

fn repeated(v: &Value) -> u64 {
    v["rejected"]["repeated"].as_u64().expect("repeated")
}

/// The lines of `path`, and its second half appended to them.
fn replayed_half(path: &Path, to: &Path) {
    let text = std::fs::read_to_string(path).expect("read");
    let lines: Vec<&str> = text.lines().collect();
    let mut out = text.clone();
    for l in &lines[lines.len() / 2..] {
        out.push_str(l);
        out.push('\n');
    }
    std::fs::write(to, out).expect("write");
}

#[test]
fn duplicated_logs_count_once_in_every_format() {
    let dir = std::env::temp_dir().join(format!("foxhunt-dup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    let mut cases = 0;
    for run in 1..=3 {
        let mut kraken: Vec<(PathBuf, [f64; 4])> = Vec::new();
        for format in ["pfoxb", "agrelo", "kraken-csv", "kraken-xml"] {
            let once_path = drive(&dir, format, run);
            let once = locate(&[&once_path]);
            let want = fix(&once);
            let base = repeated(&once);
            let doubled = dir.join(format!("doubled-{format}-{run}"));
            let mut text = std::fs::read(&once_path).expect("read");
            text.extend(std::fs::read(&once_path).expect("read"));
            std::fs::write(&doubled, text).expect("write");
            let half = dir.join(format!("half-{format}-{run}"));
            replayed_half(&once_path, &half);
            let variants: [(&str, Vec<&Path>); 3] = [
                ("given twice", vec![&once_path, &once_path]),
                ("appended to itself", vec![&doubled]),
                ("second half replayed", vec![&half]),
            ];
            for (what, captures) in variants {
                let v = locate(&captures);
                println!(
                    "{format} run {run}, {what}: fix {:?} (once {want:?}), repeated {}",
                    fix(&v),
                    repeated(&v)
                );
                assert_eq!(fix(&v), want, "{format} run {run}: {what}");
                assert!(repeated(&v) > base, "{format} run {run}: {what}");
                cases += 1;
            }
            if format.starts_with("kraken") {
                kraken.push((once_path, want));
            }
        }
        // The CSV and the XML log of the same records: the first log's fix.
        let [(csv, want), (xml, _)] = &kraken[..] else {
            panic!("two KrakenSDR logs");
        };
        let v = locate(&[csv, xml]);
        println!(
            "kraken csv + xml run {run}: fix {:?}, repeated {}",
            fix(&v),
            repeated(&v)
        );
        assert_eq!(fix(&v), *want, "run {run}: csv + xml");
        cases += 1;
    }
    println!("{cases} duplicated inputs, each the fix of its log read once");
    std::fs::remove_dir_all(&dir).ok();
}
