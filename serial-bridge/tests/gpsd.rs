//! The NMEA decoder against GPSD's own decoding of four real receivers' captures.
//!
//! `../shared/data/gpsd` holds raw captures (`*.log`) and, beside each, GPSD's regression
//! output (`*.log.chk`): every sentence followed by the JSON reports GPSD made after it. GPSD
//! reports a TPV at the end of each receiver cycle, not after every sentence, so the comparison
//! is: for each GGA or RMC we decode to a fix, the first TPV with a position after it has the
//! same time of day (else the sentence was superseded by a newer epoch before GPSD reported,
//! and is counted as such), and then the same latitude and longitude (1e-7 degrees), date
//! (RMC), speed and track (RMC, to GPSD's printed precision). For each GGA or RMC we reject as
//! no fix, GPSD's next TPV before the following GGA/RMC has no position.

use foxhunt_bridge::nmea::{NmeaError, Sentence};
use foxhunt_bridge::{Demux, Frame};
use serde_json::Value;
use std::path::PathBuf;

fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("FOXHUNT_GPSD_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/gpsd")
        });
    dir.is_dir().then_some(dir)
}

/// GGA/RMC sentences as the demultiplexer delivers them from the raw capture.
fn decoded(raw: &[u8]) -> Vec<(String, Result<Sentence, NmeaError>)> {
    // Lines starting with '#' are GPSD's comments, not serial bytes.
    let mut stream = Vec::new();
    for line in raw.split_inclusive(|&b| b == b'\n') {
        if !line.starts_with(b"#") {
            stream.extend_from_slice(line);
        }
    }
    let mut out = Vec::new();
    let mut demux = Demux::<600>::new();
    let mut sink = |f: Frame<'_>| {
        if let Frame::Nmea(text) = f
            && matches!(text.get(2..5), Some("GGA" | "RMC"))
        {
            out.push((text.to_string(), Sentence::parse(text)));
        }
    };
    // Odd reads, as a UART driver would deliver them.
    for chunk in stream.chunks(37) {
        demux.feed(chunk, &mut sink);
    }
    demux.finish_into(&mut sink);
    out
}

/// "2014-12-31T03:07:19.000Z" to (date, ms of day).
fn tpv_time(t: &str) -> ((u16, u8, u8), u32) {
    let n = |a: usize, b: usize| t[a..b].parse::<u32>().expect("digits");
    let ms = ((n(11, 13) * 60 + n(14, 16)) * 60 + n(17, 19)) * 1000 + n(20, 23);
    ((n(0, 4) as u16, n(5, 7) as u8, n(8, 10) as u8), ms)
}

#[derive(Default, Debug)]
struct Tally {
    compared: usize,
    no_fix: usize,
    superseded: usize,
    unreported_at_end: usize,
    disagreements: Vec<String>,
}

fn check_capture(name: &str, raw: &[u8], chk: &str) -> Tally {
    let ours = decoded(raw);
    let lines: Vec<&str> = chk.lines().filter(|l| !l.starts_with('#')).collect();
    let mut t = Tally::default();
    let mut k = 0; // index into ours
    for (i, line) in lines.iter().enumerate() {
        let Some(body) = line
            .strip_prefix('$')
            .and_then(|l| l.rsplit_once('*'))
            .map(|x| x.0)
        else {
            continue;
        };
        if !matches!(body.get(2..5), Some("GGA" | "RMC")) {
            continue;
        }
        let Some((text, result)) = ours.get(k) else {
            t.disagreements
                .push(format!("{name}: sentence not delivered: {line}"));
            continue;
        };
        k += 1;
        if text != body {
            t.disagreements
                .push(format!("{name}: order differs at {line} (we have {text})"));
            continue;
        }
        let reports = lines[i + 1..].iter().filter(|l| l.starts_with('{'));
        let tpvs = reports
            .map(|l| serde_json::from_str::<Value>(l).expect("GPSD JSON"))
            .filter(|v| v["class"] == "TPV");
        match result {
            Ok(s) => {
                let (time, pos) = match s {
                    Sentence::Gga(g) => (g.time, g.position),
                    Sentence::Rmc(r) => (r.time, r.position),
                    Sentence::Pfoxb(_) => unreachable!(),
                };
                let mut tpvs = tpvs.filter(|v| v.get("lat").is_some());
                let Some(tpv) = tpvs.next() else {
                    t.unreported_at_end += 1;
                    continue;
                };
                if let Some(tt) = tpv["time"].as_str() {
                    let (date, ms) = tpv_time(tt);
                    if ms != time.ms_of_day {
                        t.superseded += 1;
                        continue;
                    }
                    if let Sentence::Rmc(r) = s {
                        let d = r.date.map(|d| (d.year, d.month, d.day));
                        if d != Some(date) {
                            t.disagreements
                                .push(format!("{name}: date {d:?} vs {tt}: {line}"));
                        }
                    }
                }
                let (lat, lon) = (
                    tpv["lat"].as_f64().expect("lat"),
                    tpv["lon"].as_f64().expect("lon"),
                );
                if (lat - pos.lat).abs() > 1e-7 || (lon - pos.lon).abs() > 1e-7 {
                    t.disagreements
                        .push(format!("{name}: {pos:?} vs {lat},{lon}: {line}"));
                }
                if let Sentence::Rmc(r) = s {
                    // GPSD prints speed in m/s to 3 decimals and track to 4.
                    if let (Some(kn), Some(v)) = (r.speed_kn, tpv["speed"].as_f64())
                        && (kn * 1852.0 / 3600.0 - v).abs() > 0.0005 + 1e-9
                    {
                        t.disagreements
                            .push(format!("{name}: speed {kn} kn vs {v}: {line}"));
                    }
                    if let (Some(c), Some(v)) = (r.course_deg, tpv["track"].as_f64())
                        && (c - v).abs() > 0.000_05 + 1e-9
                    {
                        t.disagreements
                            .push(format!("{name}: course {c} vs {v}: {line}"));
                    }
                }
                t.compared += 1;
            }
            Err(NmeaError::NoFix) => {
                // GPSD's report for this epoch (if any before the next fix sentence) has no
                // position either.
                let next_fix = lines[i + 1..]
                    .iter()
                    .position(|l| matches!(l.get(3..6), Some("GGA" | "RMC")))
                    .map_or(lines.len(), |p| i + 1 + p);
                let positioned = lines[i + 1..next_fix]
                    .iter()
                    .filter(|l| l.starts_with('{'))
                    .map(|l| serde_json::from_str::<Value>(l).expect("GPSD JSON"))
                    .any(|v| v["class"] == "TPV" && v.get("lat").is_some());
                if positioned {
                    t.disagreements
                        .push(format!("{name}: we say no fix, GPSD has one: {line}"));
                }
                t.no_fix += 1;
            }
            Err(e) => t.disagreements.push(format!("{name}: {e:?}: {line}")),
        }
    }
    if k != ours.len() {
        t.disagreements.push(format!(
            "{name}: {} sentences GPSD never saw",
            ours.len() - k
        ));
    }
    t
}

#[test]
fn gga_and_rmc_agree_with_gpsd_on_four_real_receivers() {
    let Some(dir) = data_dir() else {
        eprintln!("SKIPPED: ../shared/data/gpsd is absent (set FOXHUNT_GPSD_DATA to its path)");
        return;
    };
    let mut total = Tally::default();
    for name in ["bu353s4", "haicom-305N", "quectel-l76k-nmea", "ublox-8"] {
        let raw = std::fs::read(dir.join(format!("{name}.log"))).expect("capture");
        let chk = std::fs::read(dir.join(format!("{name}.log.chk"))).expect("GPSD output");
        let t = check_capture(name, &raw, &String::from_utf8_lossy(&chk));
        eprintln!(
            "{name}: {} fixes agree, {} no-fix agree, {} superseded before GPSD reported, {} unreported at the end",
            t.compared, t.no_fix, t.superseded, t.unreported_at_end
        );
        total.compared += t.compared;
        total.no_fix += t.no_fix;
        total.superseded += t.superseded;
        total.disagreements.extend(t.disagreements);
    }
    assert!(total.disagreements.is_empty(), "{:#?}", total.disagreements);
    // Every capture contributes: 50 + 135 + 299 + 144 fixes and 11 no-fix sentences were
    // compared when this was written.
    assert!(total.compared > 600 && total.no_fix > 0, "{total:?}");
}
