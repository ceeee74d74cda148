//! `foxhunt locate` on a serial device: the fix is updated as the bytes arrive.
//!
//! Reads with a short timeout; a timeout tells the demultiplexer the line is idle (so a frame
//! waiting on look-ahead is delivered) and counts towards `--quiet-exit`. Every new bearing,
//! from the second on, recomputes the fix and prints one line (a JSON object with `--json`).

use crate::locate::{Decoded, LocateMethod, LocateReport, Solution, locate};
use foxhunt_bridge::bridge::{BridgeConfig, Receiver};
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// How to read a live line.
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// Serial device path.
    pub path: String,
    /// Baud rate.
    pub baud: u32,
    /// Stop after this long without a byte (`None`: read until the device closes).
    pub quiet_exit: Option<Duration>,
    /// Fix method.
    pub method: LocateMethod,
    /// Bearing noise, degrees, or estimated.
    pub sigma_deg: Option<f32>,
    /// Print updates as JSON lines.
    pub json: bool,
    /// Seed of particle methods.
    pub seed: u64,
}

fn snapshot(rx: &Receiver<0>, d: &mut Decoded) {
    d.frame = rx.bridge.local_frame().copied();
    let (s, b) = rx.counters();
    d.stream = *s;
    d.bridge = *b;
}

/// Read the line until it closes or stays quiet; print each updated fix to `out`; return the
/// last fix (or why there is none).
pub fn run(
    o: &LiveOptions,
    out: &mut impl Write,
) -> Result<(LocateReport, Solution, Decoded), String> {
    let mut port = serialport::new(&o.path, o.baud)
        .timeout(Duration::from_millis(100))
        .open()
        .map_err(|e| format!("cannot open {} at {} baud: {e}", o.path, o.baud))?;
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let mut d = Decoded::default();
    let mut buf = [0u8; 512];
    let mut last_byte = Instant::now();
    let emit = |d: &mut Decoded, rx: &Receiver<0>, out: &mut dyn Write| {
        snapshot(rx, d);
        if d.bearings.len() < 2 {
            return;
        }
        if let Ok((r, _)) = locate(d, o.method, o.sigma_deg, o.seed) {
            let line = if o.json {
                serde_json::to_string(&r).unwrap_or_default()
            } else {
                format!(
                    "{} bearings: {:.6}, {:.6}  CEP50 {:.1} m, CRLB {:.1} m",
                    r.used, r.lat, r.lon, r.cep50_m, r.crlb_m
                )
            };
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }
    };
    loop {
        let before = d.bearings.len();
        match port.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => {
                last_byte = Instant::now();
                rx.feed(&buf[..n], &mut |e| d.absorb(e));
            }
            Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::WouldBlock => {
                rx.idle(&mut |e| d.absorb(e));
                if o.quiet_exit.is_some_and(|q| last_byte.elapsed() >= q) {
                    break;
                }
            }
            // A hung-up pseudo-terminal or unplugged adapter ends the stream.
            Err(e) if e.kind() == ErrorKind::BrokenPipe || e.raw_os_error() == Some(5) => break,
            Err(e) => return Err(format!("reading {}: {e}", o.path)),
        }
        if d.bearings.len() > before {
            emit(&mut d, &rx, out);
        }
    }
    rx.finish(&mut |e| d.absorb(e));
    snapshot(&rx, &mut d);
    let (r, s) = locate(&d, o.method, o.sigma_deg, o.seed)?;
    Ok((r, s, d))
}
