//! Share of GPSD's positions over its regression captures that each decoder reproduces (to
//! 1e-7 degrees), ours and the AeroRust `nmea` crate's, both behind our framing, and the fixes
//! each takes from sentences GPSD rejected. The captures and the comparison are those of
//! serial-bridge/tests/gpsd.rs: TPVs reported right after a sentence the receiver sent.
//!
//! Run: cargo run --release [-- DIR] (default: the vendored captures, serial-bridge/tests/data/gpsd)

use foxhunt_bridge::nmea::Sentence;
use foxhunt_bridge::{Demux, Frame};
use serde_json::Value;
use std::collections::HashSet;

fn stream_of(raw: &[u8]) -> Vec<u8> {
    let mut stream = Vec::new();
    let mut cookie = None;
    for line in raw.split_inclusive(|&b| b == b'\n') {
        if let Some(rest) = line.strip_prefix(b"# Delay-Cookie: ") {
            cookie = rest.first().copied();
        } else if !line.starts_with(b"#") {
            stream.extend(line.iter().filter(|&&b| Some(b) != cookie));
        }
    }
    stream
}

fn sent(stream: &[u8]) -> HashSet<Vec<u8>> {
    let mut out = HashSet::new();
    for line in stream.split(|&b| b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        for (i, &b) in line.iter().enumerate() {
            if b == b'$' {
                out.insert(line[i..].to_vec());
            }
        }
    }
    out
}

fn gpsd_positions(chk: &str, sent: &HashSet<Vec<u8>>) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut from_receiver = false;
    for line in chk.lines() {
        if line.starts_with('$') {
            from_receiver = sent.contains(line.as_bytes());
            continue;
        }
        if !line.starts_with('{') {
            from_receiver = false;
            continue;
        }
        let Ok(v) = serde_json::from_str::<Value>(line) else {
            continue;
        };
        if from_receiver
            && v["class"] == "TPV"
            && let (Some(a), Some(b)) = (v["lat"].as_f64(), v["lon"].as_f64())
        {
            out.push((a, b));
        }
    }
    out.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    out.dedup();
    out
}

fn ours(body: &str) -> Option<(f64, f64)> {
    match Sentence::parse(body) {
        Ok(Sentence::Gga(g)) => Some((g.position.lat, g.position.lon)),
        Ok(Sentence::Rmc(r)) => Some((r.position.lat, r.position.lon)),
        Ok(Sentence::Gll(g)) => Some((g.position.lat, g.position.lon)),
        Ok(Sentence::Gns(g)) => Some((g.position.lat, g.position.lon)),
        _ => None,
    }
}

/// The crate's fix, by its own validity fields.
fn theirs(body: &str) -> Option<(f64, f64)> {
    use nmea::ParseResult as P;
    let line = format!("${body}*{:02X}", foxhunt_bridge::nmea::checksum(body));
    match nmea::parse_str(&line).ok()? {
        P::GGA(g) if !matches!(g.fix_type, None | Some(nmea::sentences::FixType::Invalid)) => {
            Some((g.latitude?, g.longitude?))
        }
        P::RMC(r) if r.status_of_fix != nmea::sentences::rmc::RmcStatusOfFix::Invalid => {
            Some((r.lat?, r.lon?))
        }
        P::GLL(g) if g.valid => Some((g.latitude?, g.longitude?)),
        P::GNS(g) => Some((g.lat?, g.lon?)),
        _ => None,
    }
}

fn bodies(stream: &[u8]) -> Vec<String> {
    let mut out = Vec::new();
    let mut d = Demux::<600>::new();
    let mut sink = |f: Frame<'_>| {
        if let Frame::Nmea(t) = f {
            out.push(t.to_string());
        }
    };
    d.feed(stream, &mut sink);
    d.finish_into(&mut sink);
    out
}

/// Sentence bodies GPSD answered with a no-fix TPV.
fn rejected(chk: &str) -> Vec<String> {
    let lines: Vec<&str> = chk.lines().filter(|l| !l.starts_with('#')).collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(body) = line
            .strip_prefix('$')
            .and_then(|l| l.rsplit_once('*'))
            .map(|x| x.0)
        else {
            continue;
        };
        let no_fix = lines[i + 1..]
            .iter()
            .take_while(|l| !l.starts_with('$'))
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .find(|v| v["class"] == "TPV")
            .is_some_and(|v| v["mode"].as_u64().unwrap_or(0) < 2 || v.get("lat").is_none());
        if no_fix {
            out.push(body.to_string());
        }
    }
    out
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/gpsd").into());
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("data folder")
        .filter_map(|e| {
            e.ok()?
                .file_name()
                .to_str()?
                .strip_suffix(".log.chk")
                .map(String::from)
        })
        .collect();
    names.sort();
    let (mut total, mut hit_ours, mut hit_theirs, mut bad_ours, mut bad_theirs) = (0, 0, 0, 0, 0);
    for name in &names {
        let raw = std::fs::read(format!("{dir}/{name}.log")).expect("log");
        let chk =
            String::from_utf8_lossy(&std::fs::read(format!("{dir}/{name}.log.chk")).expect("chk"))
                .into_owned();
        let stream = stream_of(&raw);
        let gpsd = gpsd_positions(&chk, &sent(&stream));
        let b = bodies(&stream);
        let o: Vec<_> = b.iter().filter_map(|s| ours(s)).collect();
        let t: Vec<_> = b.iter().filter_map(|s| theirs(s)).collect();
        let near = |list: &[(f64, f64)], p: &(f64, f64)| {
            list.iter()
                .any(|q| (q.0 - p.0).abs() <= 1e-7 && (q.1 - p.1).abs() <= 1e-7)
        };
        let (ho, ht) = (
            gpsd.iter().filter(|p| near(&o, p)).count(),
            gpsd.iter().filter(|p| near(&t, p)).count(),
        );
        let rej = rejected(&chk);
        let (ro, rt) = (
            rej.iter().filter(|s| ours(s).is_some()).count(),
            rej.iter().filter(|s| theirs(s).is_some()).count(),
        );
        println!(
            "{name:32} GPSD {:4}  ours {ho:4}  nmea {ht:4}  fixes from rejected: ours {ro} nmea {rt}",
            gpsd.len()
        );
        total += gpsd.len();
        hit_ours += ho;
        hit_theirs += ht;
        bad_ours += ro;
        bad_theirs += rt;
    }
    let pct = |n: usize| 100.0 * n as f64 / total.max(1) as f64;
    println!(
        "all {} captures: {total} GPSD positions; ours {hit_ours} ({:.2} %), nmea 0.8 {hit_theirs} ({:.2} %); fixes from sentences GPSD rejected: ours {bad_ours}, nmea {bad_theirs}",
        names.len(),
        pct(hit_ours),
        pct(hit_theirs)
    );
}
