//! The `foxhunt` command as a user runs it.

use std::process::Command;

fn foxhunt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_foxhunt"))
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
    let dir = std::env::temp_dir().join(format!("foxhunt-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let f = dir.join("drive.toml");
    std::fs::write(
        &f,
        "name = \"mine\"\nemitter = [800.0, 600.0]\npoints = [[0.0, 0.0], [100.0, 0.0], [200.0, 50.0], [250.0, 150.0]]\nruns = 3\n",
    )
    .expect("write");
    let out = foxhunt(&[
        "bench",
        "--scenario-file",
        f.to_str().expect("path"),
        "--markdown",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("| mine | ml |"), "{text}");

    std::fs::write(&f, "emitter = [1.0, 2.0]\nroute = \"loop300\"\nspeed = 3\n").expect("write");
    let out = foxhunt(&["bench", "--scenario-file", f.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed"));
}

#[test]
fn unknown_scenario_is_a_one_line_error() {
    let out = foxhunt(&["bench", "--scenario", "nowhere"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown scenario `nowhere`") && err.contains("aoa-afsa"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1);
}
