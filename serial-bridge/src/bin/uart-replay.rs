//! Feed a capture to the firmware image's emulated USARTs and print what its user port sent.
//!
//! `uart-replay [options] CAPTURE` starts QEMU's netduinoplus2 with the image and one unix
//! socket per USART (`-serial` order: USART1 GPS, USART2 DF, USART3 user, UART4 ZigBee), waits
//! for the image's ready banner (`$PFOXR`: QEMU drops bytes sent before a receiver is on),
//! (QEMU waits for the four connections before it starts the image, so the banner is never
//! sent to a socket nobody holds), splits the capture into its ports' streams and sends each record at its own time (GPS and
//! PFOXB sentence times, KrakenSDR epochs; a record without a time goes with the one before
//! it), divided by `--speed`. QEMU moves a port's bytes only as fast as its main loop runs
//! (about 10 kB/s, 5 kB/s under `-icount`, less on a loaded machine): a speed that asks more of
//! a line lets it lag the others. It then waits until a `$PFOXL` sentence says every byte sent was
//! parsed, and one more status after that, stops QEMU (SIGTERM, so a plugin prints its count)
//! and writes the user port's bytes, exactly, on stdout.
//!
//! Records: `$PFOXC` commands go to the user port; `$PFOXB`, Agrelo `%`, KrakenSDR CSV (a
//! digit) and XML (`<`) to the DF port; other sentences to the GPS port; MT frames (`0xFE`) to
//! the ZigBee port; anything else stays with the record before it.
//!
//! Options: `--elf PATH` (default: the firmware profile's image under `target/`), `--speed X`
//! (default 1), `--icount` (QEMU's `-icount shift=0`: one instruction, one nanosecond), `--plugin
//! SO` (a TCG plugin), `--out DIR` (where the sockets and these go: the bytes sent per port,
//! `gps.bin` `df.bin` `user.bin` `zigbee.bin`, the defmt log `defmt.bin`, QEMU's stderr
//! `qemu.err`; default a fresh directory under the system's temporary one), `--timeout S`
//! (default 600).
#![cfg_attr(target_os = "none", no_std, no_main)]

/// A host tool: built for the MCU (every binary of the crate is, with the image) it only sleeps.
#[cfg(target_os = "none")]
mod image {
    use stm32f4 as _;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
        loop {
            core::hint::spin_loop();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    match host::run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("uart-replay: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(not(target_os = "none"))]
mod host {
    use foxhunt_bridge::nmea::{Pfoxb, Sentence};
    use foxhunt_bridge::record::{Framing, RecordKind};
    use foxhunt_bridge::stream::{Demux, Frame};
    use foxhunt_bridge::telemetry::UnitSentence;
    use foxhunt_bridge::unit::Port;
    use std::io::{Read, Write};
    use std::os::unix::net::UnixStream;
    use std::path::{Path, PathBuf};
    use std::process::{Child, Command, Stdio};
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, Instant};

    const DAY_MS: i64 = 86_400_000;
    /// Socket names in `-serial` order, and the port index of each in the unit.
    const SOCKETS: [(&str, usize); 4] = [("gps", 0), ("df", 1), ("user", 3), ("zigbee", 2)];

    struct Options {
        elf: PathBuf,
        speed: f64,
        icount: bool,
        plugin: Option<String>,
        out: PathBuf,
        timeout: Duration,
        capture: PathBuf,
    }

    fn options() -> Result<Options, String> {
        let mut args = std::env::args().skip(1);
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut o = Options {
            elf: root.join("target/thumbv7em-none-eabihf/firmware/foxhunt-firmware"),
            speed: 1.0,
            icount: false,
            plugin: None,
            out: std::env::temp_dir().join(format!("uart-replay-{}", std::process::id())),
            timeout: Duration::from_secs(600),
            capture: PathBuf::new(),
        };
        let mut capture = None;
        while let Some(a) = args.next() {
            let mut value = || args.next().ok_or(format!("{a} needs a value"));
            match a.as_str() {
                "--elf" => o.elf = value()?.into(),
                "--speed" => o.speed = value()?.parse().map_err(|e| format!("--speed: {e}"))?,
                "--icount" => o.icount = true,
                "--plugin" => o.plugin = Some(value()?),
                "--out" => o.out = value()?.into(),
                "--timeout" => {
                    let s: u64 = value()?.parse().map_err(|e| format!("--timeout: {e}"))?;
                    o.timeout = Duration::from_secs(s);
                }
                _ if a.starts_with("--") => return Err(format!("unknown option {a}")),
                _ => capture = Some(PathBuf::from(a)),
            }
        }
        o.capture = capture.ok_or("usage: uart-replay [options] CAPTURE")?;
        if !(o.speed > 0.0) {
            return Err("--speed must be positive".into());
        }
        Ok(o)
    }

    /// One record of the capture, its port and its time (ms, unwrapped).
    struct Record {
        port: usize,
        time_ms: i64,
        bytes: Vec<u8>,
    }

    fn body(line: &[u8]) -> Option<&str> {
        let s = std::str::from_utf8(line).ok()?;
        let s = s.strip_prefix('$')?;
        Some(&s[..s.find('*')?])
    }

    /// Port and time (ms of day, or a Kraken epoch) of a record, if it names them.
    fn classify(r: &[u8]) -> (Option<usize>, Option<i64>) {
        let port = Port::of_record(r);
        let kind = RecordKind::of_record(r);
        let time = match kind {
            Some(RecordKind::Pfoxb) => body(r)
                .and_then(|b| Pfoxb::parse(b).ok())
                .map(|p| i64::from(p.time.ms_of_day)),
            Some(k) if k.framing() == Framing::Sentence && port == Some(Port::Gps) => body(r)
                .and_then(Sentence::time_of)
                .map(|t| i64::from(t.ms_of_day)),
            Some(RecordKind::KrakenCsv) => std::str::from_utf8(r)
                .ok()
                .and_then(|s| s.split(',').next())
                .and_then(|s| s.trim().parse::<i64>().ok())
                .map(|e| e.rem_euclid(DAY_MS)),
            _ => None,
        };
        (port.map(|p| p as usize), time)
    }

    fn records(capture: &[u8]) -> Vec<Record> {
        let mut out: Vec<Record> = Vec::new();
        let mut rest = capture;
        let (mut port, mut time) = (0usize, None::<i64>);
        while !rest.is_empty() {
            let n = if rest.first() == Some(&0xFE) && rest.len() >= 2 {
                (usize::from(rest[1]) + 5).min(rest.len())
            } else {
                rest.iter()
                    .position(|b| *b == b'\n')
                    .map_or(rest.len(), |i| i + 1)
            };
            let (r, tail) = rest.split_at(n);
            rest = tail;
            let (p, t) = classify(r);
            port = p.unwrap_or(port);
            if let Some(t) = t {
                // Unwrap across midnight: the representative nearest the last time.
                let t = match time {
                    Some(last) => {
                        let day = last.div_euclid(DAY_MS);
                        [day - 1, day, day + 1]
                            .map(|d| d * DAY_MS + t)
                            .into_iter()
                            .min_by_key(|c| (c - last).abs())
                            .unwrap_or(t)
                    }
                    None => t,
                };
                time = Some(time.map_or(t, |last| last.max(t)));
            }
            out.push(Record {
                port,
                time_ms: time.unwrap_or(0),
                bytes: r.to_vec(),
            });
        }
        // Records before the first time take it.
        let first = out.iter().map(|r| r.time_ms).find(|t| *t != 0).unwrap_or(0);
        for r in out.iter_mut().take_while(|r| r.time_ms == 0) {
            r.time_ms = first;
        }
        out
    }

    fn connect(path: &Path, deadline: Instant) -> Result<UnixStream, String> {
        loop {
            match UnixStream::connect(path) {
                Ok(s) => return Ok(s),
                Err(e) if Instant::now() > deadline => {
                    return Err(format!("{}: {e}", path.display()));
                }
                Err(_) => std::thread::sleep(Duration::from_millis(20)),
            }
        }
    }

    fn terminate(child: &mut Child) {
        let _ = Command::new("kill")
            .arg("-TERM")
            .arg(child.id().to_string())
            .status();
        let until = Instant::now() + Duration::from_secs(10);
        while Instant::now() < until {
            if let Ok(Some(_)) = child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = child.kill();
        let _ = child.wait();
    }

    /// What the user port has said so far: its bytes, the banners and the latest link counts.
    #[derive(Default)]
    struct Heard {
        bytes: Vec<u8>,
        ready: u32,
        statuses: u32,
        parsed: Option<[u32; 3]>,
    }

    fn listen(mut s: UnixStream, heard: Arc<Mutex<Heard>>) {
        let mut demux = Demux::<{ foxhunt_bridge::stream::DEFAULT_CAPACITY }>::new();
        let mut buf = [0u8; 4096];
        while let Ok(n) = s.read(&mut buf) {
            if n == 0 {
                break;
            }
            let Ok(mut h) = heard.lock() else { break };
            h.bytes.extend_from_slice(&buf[..n]);
            demux.feed(&buf[..n], &mut |f| {
                if let Frame::Nmea(b) = f {
                    match UnitSentence::parse(b) {
                        Ok(UnitSentence::Ready(_)) => h.ready += 1,
                        Ok(UnitSentence::Status(_)) => h.statuses += 1,
                        Ok(UnitSentence::Link(l)) => h.parsed = Some(l.bytes),
                        _ => {}
                    }
                }
            });
        }
    }

    pub fn run() -> Result<(), String> {
        let o = options()?;
        let capture =
            std::fs::read(&o.capture).map_err(|e| format!("{}: {e}", o.capture.display()))?;
        let records = records(&capture);
        std::fs::create_dir_all(&o.out).map_err(|e| format!("{}: {e}", o.out.display()))?;
        let file = |name: &str| o.out.join(name);
        for (name, _) in SOCKETS {
            let _ = std::fs::remove_file(file(&format!("{name}.sock")));
        }
        let mut qemu = Command::new("qemu-system-arm");
        qemu.args([
            "-machine",
            "netduinoplus2",
            "-display",
            "none",
            "-monitor",
            "none",
        ])
        .args(["-semihosting-config", "enable=on,target=native"]);
        for (name, _) in SOCKETS {
            let path = file(&format!("{name}.sock"));
            qemu.arg("-serial")
                .arg(format!("unix:{},server=on,wait=on", path.display()));
        }
        if o.icount {
            qemu.args(["-icount", "shift=0"]);
        }
        if let Some(p) = &o.plugin {
            qemu.args(["-plugin", p]);
        }
        qemu.arg("-kernel").arg(&o.elf);
        let log = std::fs::File::create(file("defmt.bin")).map_err(|e| e.to_string())?;
        let err = std::fs::File::create(file("qemu.err")).map_err(|e| e.to_string())?;
        let mut child = qemu
            .stdin(Stdio::null())
            .stdout(log)
            .stderr(err)
            .spawn()
            .map_err(|e| format!("qemu-system-arm: {e}"))?;
        let result = drive(&o, &records, &mut child);
        terminate(&mut child);
        let heard = result?;
        std::io::stdout()
            .write_all(&heard)
            .map_err(|e| e.to_string())
    }

    fn drive(o: &Options, records: &[Record], child: &mut Child) -> Result<Vec<u8>, String> {
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut sockets: Vec<(UnixStream, usize)> = Vec::new();
        for (name, port) in SOCKETS {
            sockets.push((
                connect(&o.out.join(format!("{name}.sock")), deadline)?,
                port,
            ));
        }
        let heard = Arc::new(Mutex::new(Heard::default()));
        let user = sockets
            .iter()
            .find(|(_, p)| *p == 3)
            .and_then(|(s, _)| s.try_clone().ok())
            .ok_or("no user socket")?;
        let h = Arc::clone(&heard);
        let reader = std::thread::spawn(move || listen(user, h));
        let alive = |child: &mut Child| match child.try_wait() {
            Ok(None) => Ok(()),
            Ok(Some(s)) => Err(format!("QEMU exited early: {s}")),
            Err(e) => Err(e.to_string()),
        };
        let until = Instant::now() + o.timeout;
        let deadline = Instant::now() + Duration::from_secs(30);
        let ready = |h: &Arc<Mutex<Heard>>| h.lock().map(|h| h.ready).unwrap_or(0);
        while ready(&heard) == 0 {
            alive(child)?;
            if Instant::now() > deadline {
                return Err("no ready banner from the image".into());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let mut sent: [Vec<u8>; 4] = Default::default();
        let start = Instant::now();
        let t0 = records.first().map_or(0, |r| r.time_ms);
        for r in records {
            let due =
                start + Duration::from_secs_f64((r.time_ms - t0).max(0) as f64 / 1000.0 / o.speed);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            alive(child)?;
            let (s, _) = sockets
                .iter_mut()
                .find(|(_, p)| *p == r.port)
                .ok_or("no socket for a port")?;
            s.write_all(&r.bytes).map_err(|e| e.to_string())?;
            sent[r.port].extend_from_slice(&r.bytes);
        }
        for (name, i) in [("gps", 0), ("df", 1), ("zigbee", 2), ("user", 3)] {
            std::fs::write(o.out.join(format!("{name}.bin")), &sent[i])
                .map_err(|e| e.to_string())?;
        }
        // Done when a link sentence counts every byte parsed, and one more status has gone.
        let want = [
            sent[0].len() as u32,
            sent[1].len() as u32,
            sent[2].len() as u32,
        ];
        let mut statuses_then = None;
        loop {
            alive(child)?;
            if Instant::now() > until {
                let h = heard.lock().map_err(|e| e.to_string())?;
                let _ = std::fs::write(o.out.join("user.out"), &h.bytes);
                return Err(format!(
                    "timed out waiting for the image to parse every byte: sent {want:?}, parsed {:?} (its output so far in user.out)",
                    h.parsed
                ));
            }
            let (parsed, statuses) = {
                let h = heard.lock().map_err(|e| e.to_string())?;
                (h.parsed, h.statuses)
            };
            let done = parsed.is_some_and(|p| {
                p[0] == want[0] && p[1] == want[1] && (p[2] == want[2] || want[2] == 0)
            });
            match statuses_then {
                None if done => statuses_then = Some(statuses),
                Some(s) if statuses > s => break,
                _ => {}
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        for (s, _) in &sockets {
            let _ = s.shutdown(std::net::Shutdown::Both);
        }
        let _ = reader.join();
        let h = heard.lock().map_err(|e| e.to_string())?;
        Ok(h.bytes.clone())
    }
}
