//! The command under an adversary's inputs: one corrupt time digit costs at most the record
//! holding it, huge and endless side files are refused in bounded memory, bad calibrations
//! are refused with nothing saved, an offset a straight road cannot measure is never a quiet
//! fix, and every exit status is the one `--help` documents (0 a fix, 1 none, 2 usage).
//!
//! Each run is measured as a child process: its exit status, its peak resident memory (GNU
//! time's `%M`), and a time limit that kills it if it hangs.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The most memory any run may take on a side file (the bar), KiB.
const PEAK_KIB: i64 = 64 * 1024;

/// How long any one run may take before it counts as a hang.
const HANG: Duration = Duration::from_secs(60);

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let k = N.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("foxhunt-adv-{name}-{}-{k}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// One finished run of the command.
#[derive(Debug)]
struct Run {
    /// Exit status (`None`: killed as a hang).
    code: Option<i32>,
    stdout: String,
    stderr: String,
    /// Peak resident memory, KiB.
    peak_kib: i64,
    /// Wall time.
    took: Duration,
}

impl Run {
    /// Exit status `code`, and on failure one line on stderr holding every one of `words`,
    /// no panic.
    fn expect(&self, code: i32, words: &[&str]) {
        let what = format!("{self:?}");
        assert_eq!(self.code, Some(code), "{what}");
        assert!(!self.stderr.contains("panicked"), "{what}");
        if code != 0 {
            // clap's usage errors add a "For more information" line; the program's own are one.
            let first = self.stderr.lines().next().unwrap_or_default();
            assert!(!first.is_empty(), "{what}");
            for w in words {
                assert!(self.stderr.contains(w), "`{w}` not in: {what}");
            }
        }
    }
}

/// Run the command with `args` in `cwd`, standard input from `stdin`, measured: under GNU
/// time (its `%M`, the peak resident memory of the command it waited for, descendants
/// included) and coreutils' `timeout`, which kills a hang (exit status 137).
fn run_in(cwd: &Path, args: &[&str], stdin: &[u8]) -> Run {
    static N: AtomicUsize = AtomicUsize::new(0);
    let peak_file = std::env::temp_dir().join(format!(
        "foxhunt-adv-peak-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let started = Instant::now();
    let mut child = Command::new("/usr/bin/time")
        .arg("-f")
        .arg("%M")
        .arg("-o")
        .arg(&peak_file)
        .args(["timeout", "-s", "KILL"])
        .arg(HANG.as_secs().to_string())
        .arg(env!("CARGO_BIN_EXE_foxhunt"))
        .current_dir(cwd)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run foxhunt under /usr/bin/time (GNU time: apt-get install time)");
    let mut input = child.stdin.take().expect("stdin");
    let bytes = stdin.to_vec();
    let feeder = std::thread::spawn(move || {
        // The command may refuse before reading: a broken pipe is no failure here.
        let _ = input.write_all(&bytes);
    });
    let out = child.wait_with_output().expect("wait for foxhunt");
    let _ = feeder.join();
    let report = std::fs::read_to_string(&peak_file).unwrap_or_default();
    let _ = std::fs::remove_file(&peak_file);
    // The last line is %M; a line before it says how a failing command ended.
    let peak_kib = report
        .lines()
        .last()
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or_else(|| panic!("no peak memory from GNU time: {report:?}"));
    let code = out.status.code().filter(|&c| c != 137);
    Run {
        code,
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        peak_kib,
        took: started.elapsed(),
    }
}

/// A bundled capture's absolute path.
fn capture(name: &str) -> String {
    format!(
        "{}/../serial-bridge/captures/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// splitmix64: a seeded stream of numbers for the trials, the same on every run.
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// NMEA's checksum of a sentence body (between `$` and `*`).
fn checksum(body: &str) -> u8 {
    body.bytes().fold(0, |x, b| x ^ b)
}

/// The digits' positions in `line[range]`, as positions in `line`.
fn digits(line: &str, from: usize, to: usize) -> Vec<usize> {
    (from..to)
        .filter(|&i| line.as_bytes()[i].is_ascii_digit())
        .collect()
}

/// `line` with one digit of its time field changed to another digit, the sentence's checksum
/// made right again (a record that decodes, with a wrong time): `None` if it has no time.
fn corrupt_time(format: &str, line: &str, mix: &mut Mix) -> Option<String> {
    let at = match format {
        "pfoxb" | "agrelo" => {
            let timed = ["$GPGGA,", "$GPRMC,", "$PFOXB,"];
            if !timed.iter().any(|t| line.starts_with(t)) {
                return None;
            }
            let from = line.find(',')? + 1;
            let to = from + line[from..].find(',')?;
            digits(line, from, to)
        }
        "kraken-csv" => digits(line, 0, line.find(',')?),
        "kraken-xml" => {
            let tag = if mix.below(2) == 0 {
                "<TIME>"
            } else {
                "<GPS_TIME>"
            };
            let from = line.find(tag)? + tag.len();
            let to = from + line[from..].find('<')?;
            digits(line, from, to)
        }
        _ => unreachable!("format {format}"),
    };
    let i = *at.get(mix.below(at.len().max(1)))?;
    let old = line.as_bytes()[i] - b'0';
    let new = (old + 1 + mix.below(9) as u8) % 10;
    let mut s = line.to_string();
    s.replace_range(i..=i, &char::from(b'0' + new).to_string());
    if let (Some(0), Some(star)) = (s.find('$'), s.find('*')) {
        let body = s[1..star].to_string();
        s.replace_range(star + 1..star + 3, &format!("{:02X}", checksum(&body)));
    }
    Some(s)
}

/// Bearings the field pipeline used on `path` (exit status 0 expected).
fn used(dir: &Path, path: &str) -> (Option<i32>, i64) {
    let r = run_in(dir, &["locate", path, "--json"], b"");
    let v: serde_json::Value = r
        .stdout
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .unwrap_or_default();
    (r.code, v["used"].as_i64().unwrap_or(-1))
}

#[test]
fn one_corrupt_time_digit_costs_at_most_one_record() {
    let dir = scratch("time");
    // Trials per format and kind of record: each a fresh record and digit (30 each: about 200
    // runs, some seconds; the finding was that one such digit lost half the drive, every
    // time).
    const TRIALS: usize = 30;
    let mut mix = Mix(22);
    for format in ["pfoxb", "agrelo", "kraken-csv", "kraken-xml"] {
        let clean = dir.join(format!("{format}.cap"));
        let c = clean.to_str().expect("path");
        let sim = run_in(
            &dir,
            &["simulate", "--out", c, "--format", format, "--force"],
            b"",
        );
        sim.expect(0, &[]);
        let (code, base) = used(&dir, c);
        assert_eq!(code, Some(0), "{format}: the clean drive has a fix");
        let text = std::fs::read_to_string(&clean).expect("capture");
        let lines: Vec<&str> = text.split_inclusive('\n').collect();
        // A bearing record's own time (held to the bar), and a GPS fix's time (GGA, RMC:
        // measured and printed; a fix whose time jumps is not yet refused on its own).
        let bearing_record = |l: &str| !l.starts_with("$GP");
        for own in [true, false] {
            let timed: Vec<usize> = (0..lines.len())
                .filter(|&i| bearing_record(lines[i]) == own)
                .filter(|&i| corrupt_time(format, lines[i], &mut Mix(0)).is_some())
                .collect();
            if timed.is_empty() {
                continue;
            }
            let (mut worst, mut over, mut no_fix) = (0, 0, 0);
            for trial in 0..TRIALS {
                let i = timed[mix.below(timed.len())];
                let bad = corrupt_time(format, lines[i], &mut mix).expect("a time");
                let mut t = lines.clone();
                t[i] = &bad;
                let path = dir.join(format!("{format}-{own}-{trial}.cap"));
                std::fs::write(&path, t.concat()).expect("write");
                let (code, n) = used(&dir, path.to_str().expect("path"));
                assert!(
                    matches!(code, Some(0 | 1)),
                    "{format}: `{}`: {code:?}",
                    bad.trim()
                );
                let lost = if code == Some(0) { base - n } else { base };
                if own {
                    assert_eq!(code, Some(0), "{format}: `{}` lost the fix", bad.trim());
                    assert!(
                        lost <= 1,
                        "{format}: line {i} `{}` cost {lost} bearings of {base}",
                        bad.trim()
                    );
                }
                worst = worst.max(lost);
                over += usize::from(lost > 1);
                no_fix += usize::from(code != Some(0));
            }
            let which = if own { "bearing records" } else { "GPS fixes" };
            println!(
                "{format}, {which}: {TRIALS} corrupt time digits, {base} bearings used clean, \
                 worst loss {worst}, {over} costing more than one, {no_fix} without a fix"
            );
        }
    }
}

/// Feed `fifo` endlessly with `chunk` from a thread until its reader goes away.
fn endless(fifo: &Path, chunk: &'static [u8]) -> std::thread::JoinHandle<()> {
    let fifo = fifo.to_path_buf();
    std::thread::spawn(move || {
        let Ok(mut w) = std::fs::OpenOptions::new().write(true).open(&fifo) else {
            return;
        };
        while w.write_all(chunk).is_ok() {}
    })
}

/// Unblock a writer still waiting for `fifo`'s reader (the command refused it unopened).
fn release(fifo: &Path) {
    use std::os::unix::fs::OpenOptionsExt;
    // O_NONBLOCK (Linux's 0o4000): opening the reading end does not wait for a writer.
    let _ = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(0o4000)
        .open(fifo);
}

#[test]
fn huge_and_endless_side_files_are_refused_in_bounded_memory() {
    let dir = scratch("side");
    let d = dir.to_str().expect("path").to_string();
    // A 3 GiB file (sparse: no disk), and one just past the side files' 1 MiB cap.
    let huge = dir.join("huge.toml");
    std::fs::File::create(&huge)
        .and_then(|f| f.set_len(3 << 30))
        .expect("sparse file");
    let over = dir.join("over.toml");
    std::fs::write(&over, "# a comment line of a TOML file\n".repeat(40_000)).expect("write");
    let znp = capture("rssi-sim.znp");
    let out = dir.join("out.nmea");
    let o = out.to_str().expect("path").to_string();
    // Each side file's flag, the command that reads it, and what endless text it might get.
    type Args = fn(&str, &str, &str) -> Vec<String>;
    let readers: [(&str, Args, &'static [u8]); 5] = [
        (
            "scenario",
            |f, _, o| {
                vec![
                    "simulate".into(),
                    "--scenario-file".into(),
                    f.into(),
                    "--out".into(),
                    o.into(),
                ]
            },
            b"route = [[0.0, 0.0], [1.0, 1.0]]\n",
        ),
        (
            "anchors",
            |f, z, _| vec!["track".into(), z.into(), "--anchors".into(), f.into()],
            b"[[anchor]]\naddr = 1\nx = 0.0\ny = 0.0\n",
        ),
        (
            "calibration",
            |f, _, _| vec!["locate".into(), "--calibration".into(), f.into()],
            b"offset_deg = 1.0\n",
        ),
        (
            "roads",
            |f, _, _| vec!["locate".into(), "--roads".into(), f.into()],
            b"<node <node <node <node ",
        ),
        (
            "roads.pbf",
            |f, _, _| vec!["locate".into(), "--roads".into(), f.into()],
            b"\0\0\0\x0d\x0a\x09OSMHeader\x18\x7f\x7f\x7f\x7f",
        ),
    ];
    let mut peak = 0;
    for (name, args, text) in readers {
        let fifo = dir.join(format!("endless-{name}"));
        let status = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
        assert!(status.success());
        let pbf = name.ends_with(".pbf");
        // A road extract is read as PBF by its name.
        let named = |p: &Path| -> String {
            if pbf {
                let link = dir.join(format!(
                    "{}.pbf",
                    p.file_name().expect("name").to_string_lossy()
                ));
                let _ = std::os::unix::fs::symlink(p, &link);
                link.to_string_lossy().into_owned()
            } else {
                p.to_string_lossy().into_owned()
            }
        };
        for (what, path, words) in [
            ("/dev/zero", named(Path::new("/dev/zero")), vec!["device"]),
            ("a 3 GiB file", named(&huge), vec!["3 GiB", "more than"]),
            ("a directory", named(&dir), vec!["directory"]),
            ("an endless pipe of zeros", named(&fifo), vec![]),
            ("an endless pipe of text", named(&fifo), vec![]),
        ] {
            let writer = match what {
                "an endless pipe of zeros" => Some(endless(&fifo, &[0; 4096])),
                "an endless pipe of text" => Some(endless(&fifo, text)),
                _ => None,
            };
            let argv = args(&path, &znp, &o);
            let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
            let r = run_in(Path::new(&d), &argv, b"");
            release(&fifo);
            if let Some(w) = writer {
                w.join().expect("writer");
            }
            println!(
                "{name} as {what}: exit {:?}, peak {} KiB, {:.2} s: {}",
                r.code,
                r.peak_kib,
                r.took.as_secs_f64(),
                r.stderr.trim()
            );
            r.expect(1, &words);
            assert_eq!(r.stderr.trim().lines().count(), 1, "{r:?}");
            assert!(r.peak_kib <= PEAK_KIB, "{name} as {what}: {r:?}");
            peak = peak.max(r.peak_kib);
        }
        // Just past the cap of the small side files (a road extract's is 512 MiB).
        if !name.starts_with("roads") {
            let argv = args(&over.to_string_lossy(), &znp, &o);
            let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
            let r = run_in(Path::new(&d), &argv, b"");
            r.expect(1, &["more than", "1 MiB"]);
        }
    }
    println!("peak memory over every huge or endless side file: {peak} KiB");
}

/// aoa-drive's transmitter: 1200 m east, 800 m north of the route's first point at 47, 8.
fn transmitter(east: f64, north: f64) -> String {
    let lat = 47.0 + north / 111_200.0;
    let lon = 8.0 + east / (111_320.0 * 47f64.to_radians().cos());
    format!("{lat:.6},{lon:.6}")
}

#[test]
fn bad_calibrations_are_refused_and_nothing_is_saved() {
    let dir = scratch("calibration");
    let d = |p: &str| dir.join(p).to_string_lossy().into_owned();
    let run = |args: &[&str]| run_in(&dir, args, b"");
    for (bias, name) in [("4", "small"), ("60", "large")] {
        run(&["simulate", "--out", &d(name), "--bias-deg", bias]).expect(0, &[]);
    }
    let tx = transmitter(1200.0, 800.0);
    let file = d("unit.toml");
    let cases: [(&str, Vec<String>, i32, &[&str]); 6] = [
        (
            "no capture",
            vec!["--calibrate".into(), tx.clone()],
            2,
            &["CAPTURE"],
        ),
        (
            "a 60 degree offset",
            vec![d("large"), "--calibrate".into(), tx.clone()],
            1,
            &["beyond", "--max-offset-deg", "nothing saved"],
        ),
        (
            "the transmitter at the drive's start",
            vec![d("small"), "--calibrate".into(), "47,8".into()],
            1,
            &["47.000000,8.000000", "nothing saved"],
        ),
        (
            "a transmitter 500 km away",
            vec![d("small"), "--calibrate".into(), "51.5,8".into()],
            1,
            &["too far"],
        ),
        (
            "the transmitter mirrored west",
            vec![
                d("small"),
                "--calibrate".into(),
                transmitter(-1200.0, 800.0),
            ],
            1,
            &["disagree", "nothing saved"],
        ),
        (
            "a transmitter beyond the poles",
            vec![d("small"), "--calibrate".into(), "95,8".into()],
            2,
            &["'95,8'"],
        ),
    ];
    for (what, args, code, words) in cases {
        let mut argv = vec!["locate".to_string()];
        argv.extend(args);
        argv.extend(["--calibration".into(), file.clone()]);
        let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
        let r = run(&argv);
        println!("{what}: exit {:?}: {}", r.code, r.stderr.trim());
        r.expect(code, words);
        assert!(
            !Path::new(&file).exists(),
            "{what}: a calibration was saved"
        );
    }
    // The 60 degrees, allowed: saved, and they are what the drive says.
    run(&[
        "locate",
        &d("large"),
        "--calibrate",
        &tx,
        "--calibration",
        &file,
        "--max-offset-deg",
        "90",
    ])
    .expect(0, &[]);
    let saved = std::fs::read_to_string(&file).expect("saved");
    assert!(
        saved.contains("offset_deg = 5") || saved.contains("offset_deg = 6"),
        "{saved}"
    );
    // Calibration files no calibration gives: refused on load, naming the key, as a usage
    // error (exit 2).
    let good = "offset_deg = 4.0\noffset_sd_deg = 0.5\nnoise_deg = 1.0\nbearings = 60\n\
                rejected = 0\ntransmitter = [47.007, 8.0176]\n";
    run(&[
        "locate",
        &d("small"),
        "--calibration",
        &write(&dir, "good.toml", good),
    ])
    .expect(0, &[]);
    for (key, from, to) in [
        ("offset_deg", "offset_deg = 4.0", "offset_deg = 400.0"),
        ("offset_deg", "offset_deg = 4.0", "offset_deg = nan"),
        (
            "offset_sd_deg",
            "offset_sd_deg = 0.5",
            "offset_sd_deg = 0.0",
        ),
        ("noise_deg", "noise_deg = 1.0", "noise_deg = 50.0"),
        ("bearings", "bearings = 60", "bearings = 3"),
        ("transmitter", "[47.007, 8.0176]", "[95.0, 8.0]"),
        ("noise_deg", "noise_deg = 1.0\n", ""),
        ("line 1", "offset_deg = 4.0", "offset_deg = \"four\""),
    ] {
        let bad = write(&dir, "bad.toml", &good.replace(from, to));
        let r = run(&["locate", &d("small"), "--calibration", &bad]);
        println!(
            "calibration with `{to}`: exit {:?}: {}",
            r.code,
            r.stderr.trim()
        );
        r.expect(2, &[key]);
        assert_eq!(r.stderr.trim().lines().count(), 1, "{r:?}");
    }
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p.to_string_lossy().into_owned()
}

/// A documented exit: what, the arguments, standard input, the status, words on stderr.
type Case<'a> = (&'a str, Vec<&'a str>, &'a [u8], i32, Vec<&'a str>);

#[test]
fn exit_statuses_are_as_documented() {
    let dir = scratch("exits");
    let d = |p: &str| dir.join(p).to_string_lossy().into_owned();
    let here = d("");
    let garbage = write(&dir, "garbage.nmea", "no sentence here\n$GPGGA,bad*00\n");
    // Only the DF unit's "searching" fix sentence: no position anywhere.
    let searching = write(
        &dir,
        "searching.nmea",
        "$PFOXF,100059.50,,,,,,,,,2,60,1.20,S*37\n",
    );
    let drive = d("drive.nmea");
    run_in(&dir, &["simulate", "--out", &drive], b"").expect(0, &[]);
    // (what, args, standard input, status, words on stderr)
    let cases: Vec<Case> = vec![
        ("a fix", vec!["locate", &drive], b"", 0, vec![]),
        ("empty standard input", vec!["locate", "-"], b"", 1, vec![]),
        (
            "standard input without a fix",
            vec!["locate", "-"],
            b"no sentence\n",
            1,
            vec![],
        ),
        (
            "a capture without a fix",
            vec!["locate", &garbage],
            b"",
            1,
            vec![],
        ),
        (
            "only the unit's searching sentence",
            vec!["locate", &searching],
            b"",
            1,
            vec!["searching"],
        ),
        (
            "a missing capture",
            vec!["locate", "missing.nmea"],
            b"",
            1,
            vec!["missing.nmea"],
        ),
        (
            "/dev/null",
            vec!["locate", "/dev/null"],
            b"",
            1,
            vec!["not a serial port"],
        ),
        (
            "a directory",
            vec!["locate", &here],
            b"",
            1,
            vec!["directory"],
        ),
        (
            "serve of a missing file",
            vec!["serve", "missing.nmea"],
            b"",
            1,
            vec!["missing.nmea"],
        ),
        (
            "serve of /dev/zero",
            vec!["serve", "/dev/zero"],
            b"",
            1,
            vec!["device"],
        ),
        (
            "frames of a missing file",
            vec!["frames", "missing.nmea"],
            b"",
            1,
            vec!["missing.nmea"],
        ),
        (
            "a value past f32",
            vec!["locate", "--sigma-deg", "1e308"],
            b"",
            2,
            vec!["'1e308'"],
        ),
        (
            "a negative share",
            vec!["simulate", "--out", &drive, "--wild", "-1"],
            b"",
            2,
            vec!["'-1'"],
        ),
        (
            "--particles for ml-robust",
            vec!["locate", "--particles", "1000"],
            b"",
            2,
            vec!["ml-robust"],
        ),
        (
            "--calibrate without a capture",
            vec!["locate", "--calibrate", "47,8", "--calibration", "x.toml"],
            b"",
            2,
            vec!["CAPTURE"],
        ),
        (
            "nothing to time",
            vec!["perf", "--no-numpy", "--no-growth"],
            b"",
            2,
            vec!["nothing to time"],
        ),
        (
            "--baud on a file",
            vec!["locate", &drive, "--baud", "4800"],
            b"",
            2,
            vec!["is a file"],
        ),
        (
            "--runs 0",
            vec!["bench", "--runs", "0"],
            b"",
            2,
            vec!["'0'"],
        ),
    ];
    for (what, args, stdin, code, words) in cases {
        let r = run_in(&dir, &args, stdin);
        println!("{what}: exit {:?}", r.code);
        r.expect(code, &words);
    }
    // Without a fix, --json still prints one object on standard output: why.
    let r = run_in(&dir, &["locate", &garbage, "--json"], b"");
    r.expect(1, &[]);
    let v: serde_json::Value = serde_json::from_str(r.stdout.trim()).expect("one JSON object");
    assert!(v["error"].is_string(), "{v}");
}

/// A straight road the unit drives with its antenna turned 165 degrees: the bearings cannot
/// tell that from an emitter elsewhere, so every answer must say the offset is in doubt. End
/// to end through `simulate` and `locate --json`: no fix ("the DF unit's offset is about ...",
/// `offset_beyond_prior`, exit 1), or a fix flagged (its offset relaxed or not measured) that
/// the stop rule never calls good enough. The offset sweep (tests/tests/offset_beyond_prior.rs,
/// the far straight road at 165 degrees) gives no fix in 25 of 40 runs, so six runs with none
/// would be a 0.4 % event; these six are seeded, so the figure is fixed.
#[test]
fn an_offset_a_straight_road_cannot_measure_is_never_a_quiet_fix() {
    let dir = scratch("straight");
    let scenario = write(
        &dir,
        "line.toml",
        "name = \"straight\"\nemitter = [1200.0, 800.0]\nroute = \"line600\"\n\
         bearing_sigma_deg = 1.0\n",
    );
    let mut refused = 0;
    for k in 1..=6 {
        let drive = dir
            .join(format!("run{k}.nmea"))
            .to_string_lossy()
            .into_owned();
        let args = [
            "simulate",
            "--scenario-file",
            &scenario,
            "--bias-deg",
            "165",
        ];
        run_in(
            &dir,
            &[&args[..], &["--run", &k.to_string(), "--out", &drive]].concat(),
            b"",
        )
        .expect(0, &[]);
        let r = run_in(&dir, &["locate", &drive, "--json"], b"");
        let v: serde_json::Value = serde_json::from_str(r.stdout.trim()).expect("one JSON object");
        println!("run {k}: exit {:?}, {}", r.code, r.stderr.trim());
        if r.code == Some(1) && v["reason"] == "offset_beyond_prior" {
            r.expect(1, &["offset is about", "beyond its prior", "calibrate"]);
            refused += 1;
            continue;
        }
        r.expect(0, &[]);
        let e = &v["emitters"][0];
        assert!(
            e["offset_measured"] == false || e["offset_check"].is_object(),
            "run {k}: a fix with no doubt about the offset: {e}"
        );
        assert_eq!(
            v["advice"]["good_enough"], false,
            "run {k}: {}",
            v["advice"]
        );
    }
    println!("no fix for the offset in {refused} of 6 runs");
    assert!(refused > 0, "no run gave the typed no-fix");
}
