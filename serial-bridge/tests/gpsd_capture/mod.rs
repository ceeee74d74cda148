//! GPSD's regression captures read as GPSD's own suite means them: the serial bytes of a
//! `*.log`, and in its `*.log.chk` the TPV reports that follow each sentence. Shared by the
//! decoder test (`tests/gpsd.rs`) and the decoder comparison (`nmea-compare/suite`), so both
//! judge against the same reading of GPSD.

use serde_json::Value;
use std::collections::HashSet;
use std::path::Path;

/// The captures in `dir` by name (`NAME.log` with GPSD's `NAME.log.chk`), sorted.
pub fn captures(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("data folder")
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            e.file_name()
                .to_str()
                .and_then(|n| n.strip_suffix(".log.chk"))
                .map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

/// The serial bytes of a capture: GPSD's `#` comment lines are not part of the stream, nor is
/// the delay cookie a header may declare (`# Delay-Cookie: | 0.01`: gpsfake's write
/// boundaries).
pub fn stream_of(raw: &[u8]) -> Vec<u8> {
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

/// Every sentence the receiver itself sent (from each `$` of each line to its end): GPSD's
/// output also holds sentences it generated from binary packets, and TPVs from those.
pub fn sent(stream: &[u8]) -> HashSet<Vec<u8>> {
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

/// A TPV of GPSD's with a position.
#[derive(Debug, Clone)]
pub struct Tpv {
    /// Its time as ms of day, when it has one.
    pub time: Option<u32>,
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
}

/// "2014-12-31T03:07:19.000Z" to ms of day.
fn tpv_time(t: &str) -> Option<u32> {
    let n = |a: usize, b: usize| t.get(a..b)?.parse::<u32>().ok();
    Some(((n(11, 13)? * 60 + n(14, 16)?) * 60 + n(17, 19)?) * 1000 + n(20, 23).unwrap_or(0))
}

/// GPSD's TPVs with a position reported right after a sentence the receiver sent (not after a
/// binary packet, nor after a sentence GPSD generated from one).
pub fn gpsd_tpvs(chk: &str, sent: &HashSet<Vec<u8>>) -> Vec<Tpv> {
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
        if !from_receiver || v["class"] != "TPV" {
            continue;
        }
        if let (Some(lat), Some(lon)) = (v["lat"].as_f64(), v["lon"].as_f64()) {
            out.push(Tpv {
                time: v["time"].as_str().and_then(tpv_time),
                lat,
                lon,
            });
        }
    }
    out
}

/// One sentence of GPSD's output and the first TPV GPSD reported after it (before the next
/// sentence), if any.
pub struct Answered<'a> {
    /// The sentence as printed (`$...*hh`).
    pub line: &'a str,
    /// Its body, between `$` and `*`.
    pub body: &'a str,
    /// GPSD's TPV right after it.
    pub tpv: Option<Value>,
}

/// Every sentence in GPSD's output with the TPV that answered it.
pub fn answered(chk: &str) -> Vec<Answered<'_>> {
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
        let tpv = lines[i + 1..]
            .iter()
            .take_while(|l| !l.starts_with('$'))
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .find(|v| v["class"] == "TPV");
        out.push(Answered { line, body, tpv });
    }
    out
}

/// Whether GPSD rejected the sentence: its TPV says there is no fix.
pub fn rejected(a: &Answered<'_>) -> bool {
    a.tpv
        .as_ref()
        .is_some_and(|v| v["mode"].as_u64().unwrap_or(0) < 2 || v.get("lat").is_none())
}
