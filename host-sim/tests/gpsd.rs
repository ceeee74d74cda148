//! `foxhunt locate - --gpsd` and `foxhunt publish - --gpsd` against the real daemon: Debian's
//! gpsd, run by gpsfake (package gpsd-clients) replaying a drive's GPS and heading sentences
//! on loopback, while the bearings, relative to the vehicle, come on standard input.
//! Positions reach foxhunt only through gpsd's TPV reports and headings only through its ATT
//! reports.
//!
//! Needs gpsd and gpsfake (and mosquitto for the broker's test): without them the tests fail
//! saying what to install (.ci/run installs them).

use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::{LatLon, write_sentence};
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::runs::simulate::{CaptureFormat, CaptureOptions, drive_capture};
use std::io::Write;
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

mod common;

use common::broker::{Broker, Worker};

/// A deadline for waits that guard against a hang (not timing assertions).
const PATIENCE: Duration = Duration::from_secs(60);

/// Fails the test, saying what to install, where gpsfake is missing.
fn require_gpsfake() {
    let found = Command::new("gpsfake")
        .arg("--help")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        found,
        "gpsfake not found: apt-get install gpsd gpsd-clients (.ci/run does)"
    );
}

fn sentence(body: &str) -> String {
    let mut s = String::new();
    write_sentence(&mut s, body).expect("string");
    s
}

/// The GPS log for gpsfake and the bearings for standard input, from a straight drive
/// written in the Agrelo format: its GGA, RMC and HDT go to gpsd; each `%` record, placed
/// at its fix's time, becomes a relative `$PFOXB`.
fn drive() -> (String, Vec<String>, Scenario) {
    let scenario = Scenario::from_toml(
        "name = \"gpsd-line\"\nemitter = [300.0, 500.0]\nroute = \"line600\"\n",
    )
    .expect("scenario");
    let o = CaptureOptions {
        format: CaptureFormat::Agrelo,
        ..CaptureOptions::default()
    };
    let bytes = drive_capture(&scenario, &o).expect("capture");
    let text = String::from_utf8(bytes).expect("ASCII");
    // gpsfake feeds the log from its start, whether or not a client listens yet: 3 s of
    // satellite views first (no fix, nothing foxhunt uses) give the clients time to connect.
    let mut log = String::from("# foxhunt: a drive for the gpsd client test\n");
    let gsv = sentence("GPGSV,1,1,04,01,40,083,46,02,17,308,41,12,07,344,39,14,22,228,45");
    for _ in 0..150 {
        log.push_str(gsv.trim_end());
        log.push('\n');
    }
    let mut bearings = Vec::new();
    let mut time = String::new();
    for line in text.lines() {
        if let Some(body) = line.strip_prefix("$GPGGA,") {
            time = body.split(',').next().unwrap_or("").to_string();
        }
        if let Some(body) = line.strip_prefix("$HEHDT,") {
            // gpsd 3.22 reports HDT as ATT from GP and GN talkers.
            let body = body.split('*').next().unwrap_or("");
            log.push_str(sentence(&format!("GNHDT,{body}")).trim_end());
            log.push('\n');
        } else if line.starts_with('$') {
            log.push_str(line.trim_end());
            log.push('\n');
        } else if line.starts_with('%') {
            let a = Agrelo::parse(line.trim_end()).expect("Agrelo record");
            let relative = a.bearing().expect("a bearing");
            bearings.push(sentence(&format!(
                "PFOXB,{time},{relative:.1},R,{},433.920",
                u32::from(a.quality) * 11
            )));
        }
    }
    (log, bearings, scenario)
}

/// A free loopback port (bound, read, released).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// Ends gpsfake (which ends its gpsd) when the test does, however it ends.
struct Daemon(Child);

impl Drop for Daemon {
    fn drop(&mut self) {
        if let Ok(None) = self.0.try_wait() {
            // SIGTERM lets gpsfake stop the gpsd it started.
            let _ = Command::new("kill")
                .args(["-TERM", &self.0.id().to_string()])
                .status();
            let deadline = Instant::now() + Duration::from_secs(10);
            while Instant::now() < deadline && matches!(self.0.try_wait(), Ok(None)) {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = self.0.kill();
        }
        let _ = self.0.wait();
    }
}

/// gpsfake replaying [`drive`]'s GPS log on a port of its own, a watcher of its reports
/// (which paces the bearings: it sees what foxhunt sees), and the drive's bearings.
struct GpsDrive {
    port: u16,
    reports: mpsc::Receiver<String>,
    bearings: Vec<String>,
    scenario: Scenario,
    dir: std::path::PathBuf,
    // Dropped last: gpsd stops once the watcher and foxhunt are done with it.
    _daemon: Daemon,
}

impl GpsDrive {
    fn start(name: &str) -> Self {
        require_gpsfake();
        let (log, bearings, scenario) = drive();
        let dir = std::env::temp_dir().join(format!("foxhunt-gpsd-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch");
        let log_path = dir.join("drive.log");
        std::fs::write(&log_path, &log).expect("log");
        let port = free_port();
        let daemon = Daemon(
            Command::new("gpsfake")
                .args(["-1", "-q", "-c", "0.02", "-P", &port.to_string()])
                .arg(&log_path)
                .current_dir(&dir)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("gpsfake runs"),
        );
        let deadline = Instant::now() + PATIENCE;
        let mut watcher = loop {
            match TcpStream::connect(("127.0.0.1", port)) {
                Ok(s) => break s,
                Err(_) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(20))
                }
                Err(e) => panic!("gpsd never listened on {port}: {e}"),
            }
        };
        watcher
            .write_all(b"?WATCH={\"enable\":true,\"json\":true}\n")
            .expect("watch");
        Self {
            port,
            reports: common::lines(watcher),
            bearings,
            scenario,
            dir,
            _daemon: daemon,
        }
    }

    /// `--gpsd=` this daemon.
    fn arg(&self) -> String {
        format!("--gpsd=127.0.0.1:{}", self.port)
    }

    /// Write the bearings to `stdin`, bearing k once gpsd has reported epoch k's heading
    /// (each epoch: GGA, RMC, then HDT, so its TPV came before): foxhunt, watching the same
    /// daemon, has both by then. Closes `stdin`; the ATT reports seen.
    fn feed(&self, mut stdin: impl Write) -> usize {
        let mut headings = 0;
        for (k, b) in self.bearings.iter().enumerate() {
            while headings <= k {
                let line = self
                    .reports
                    .recv_timeout(PATIENCE)
                    .expect("gpsd reports before the deadline");
                if line.contains("\"class\":\"ATT\"") {
                    headings += 1;
                }
            }
            stdin.write_all(b.as_bytes()).expect("write");
            stdin.flush().expect("flush");
        }
        headings
    }

    /// How far the report's first emitter is from the truth, and its CRLB, metres (in the
    /// frame of the report's origin).
    fn off_and_crlb(&self, report: &serde_json::Value) -> (f64, f64) {
        let s = self.scenario.drive().expect("a drive");
        let origin = LatLon {
            lat: report["origin"]["lat"].as_f64().expect("origin"),
            lon: report["origin"]["lon"].as_f64().expect("origin"),
        };
        let start = LocalFrame::new(CaptureOptions::default().origin, 0.0).expect("frame");
        let emitter = start
            .to_geodetic([
                f64::from(s.emitter[0] - s.route[0][0]),
                f64::from(s.emitter[1] - s.route[0][1]),
            ])
            .expect("emitter");
        let truth = LocalFrame::new(origin, 0.0)
            .and_then(|f| f.to_local(emitter))
            .expect("truth");
        let e = &report["emitters"][0];
        let (east, north) = (
            e["east_m"].as_f64().expect("east"),
            e["north_m"].as_f64().expect("north"),
        );
        let crlb = e["crlb_m"].as_f64().expect("crlb");
        ((east - truth[0]).hypot(north - truth[1]), crlb)
    }
}

impl Drop for GpsDrive {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[test]
fn locate_takes_positions_and_headings_from_a_real_gpsd() {
    let g = GpsDrive::start("locate");
    let mut child = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args(["locate", "-", &g.arg(), "--json"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run foxhunt");
    let updates = common::lines(child.stdout.take().expect("stdout"));
    let headings = g.feed(child.stdin.take().expect("stdin"));
    let mut used = Vec::new();
    let mut last = serde_json::Value::Null;
    while let Ok(line) = updates.recv_timeout(PATIENCE) {
        let v: serde_json::Value = serde_json::from_str(&line).expect("JSON");
        used.push(v["used"].as_u64().expect("used"));
        last = v;
    }
    let out = child.wait_with_output().expect("foxhunt ends");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(headings == g.bearings.len(), "{headings} ATT reports");
    // One update per new bearing (or per batch of them), never fewer bearings than before.
    assert!(used.windows(2).all(|w| w[0] < w[1]), "{used:?}");
    let n = last["used"].as_u64().expect("a fix at the end");
    // Every bearing placed by gpsd's positions and turned by its headings; the first may
    // come before foxhunt's first heading when the two watchers differ by a report.
    assert!(
        n + 1 >= g.bearings.len() as u64,
        "{n} of {}: {last}",
        g.bearings.len()
    );
    // The fix within 3 CRLBs (sqrt of the bound's trace: 3 of it holds a 2-D Gaussian
    // fix at least 98.9 % of the time) of the truth.
    let (off, crlb) = g.off_and_crlb(&last);
    eprintln!(
        "gpsd: {n} of {} bearings through gpsd's TPV and ATT, fix {off:.1} m off, CRLB {crlb:.1} m",
        g.bearings.len()
    );
    assert!(off < 3.0 * crlb, "{off} m off, CRLB {crlb} m: {last}");
}

#[test]
fn a_vehicle_publishes_bearings_placed_by_gpsd_and_the_broker_fuses_them() {
    // A vehicle whose DF unit sends relative bearings alone: `publish --gpsd` places and
    // turns them with gpsd's reports and sends them as the car's station; a worker on the
    // broker fixes the emitter from them as `locate --gpsd` does from the line.
    let broker = Broker::start("gpsd");
    let url = broker.url("cars");
    let g = GpsDrive::start("publish");
    let worker = Worker::start_command(&["locate", "--json"], &url, "gpsd-worker", 5, &[]);
    let mut publisher = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
        .args([
            "publish",
            "-",
            &g.arg(),
            "--station",
            "car-1",
            "--mqtt",
            &url,
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run publish");
    let headings = g.feed(publisher.stdin.take().expect("stdin"));
    let out = publisher.wait_with_output().expect("publish ends");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "publish: {err}");
    assert!(headings == g.bearings.len(), "{headings} ATT reports");
    let (last, _) = worker.finish();
    // Every bearing the publisher sent was placed (one may precede its first position), and
    // the worker used them all.
    let sent = err
        .lines()
        .find_map(|l| l.strip_prefix("mqtt: bearings "))
        .and_then(|l| l.split(',').next())
        .and_then(|n| n.parse::<u64>().ok())
        .expect("publish's count");
    let n = last["used"].as_u64().expect("a fix at the end");
    assert!(
        sent + 1 >= g.bearings.len() as u64 && n == sent,
        "sent {sent}, used {n} of {}: {last}",
        g.bearings.len()
    );
    assert_eq!(last["stations"][0]["id"], "car-1", "{last}");
    // The same bound as the line's: the fix within 3 CRLBs of the truth.
    let (off, crlb) = g.off_and_crlb(&last);
    eprintln!(
        "publish --gpsd: {sent} bearings through the broker, fix {off:.1} m off, CRLB {crlb:.1} m"
    );
    assert!(off < 3.0 * crlb, "{off} m off, CRLB {crlb} m: {last}");
}
