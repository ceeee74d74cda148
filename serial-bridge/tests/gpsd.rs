//! The NMEA decoder against GPSD's own decoding of the 54 real receivers' captures in
//! `tests/data/gpsd` (GPSD's regression suite: `*.log` raw bytes, `*.log.chk` GPSD's JSON
//! reports after each sentence; its README says where they come from).
//!
//! GPSD reports a TPV whenever a sentence updates its fix, often repeating a position, and
//! merges sentences of one cycle; so sets are compared, not sequences:
//! - every position in GPSD's TPVs (latitude and longitude to 1e-7 degrees) is one we decode
//!   from some GGA, RMC, GLL or GNS;
//! - every TPV time (to the millisecond) goes with a fix of ours at that position and time;
//! - every TPV speed and track (to GPSD's printed precision, 3 and 4 decimals) is one of ours
//!   (RMC or VTG) at the same time;
//! - every fix we decode is a position GPSD reported (no sentence GPSD rejected gives a fix).

use foxhunt_bridge::nmea::{KNOT_MPS, LatLon, Sentence};
use foxhunt_bridge::{Demux, Frame};
use gpsd_capture::{captures, gpsd_tpvs, sent, stream_of};
use std::path::PathBuf;

mod gpsd_capture;

/// The vendored captures: part of the repository, so a missing folder is a failure.
fn data_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/gpsd");
    assert!(
        dir.is_dir(),
        "GPSD's captures are missing at {} (they are part of the repository)",
        dir.display()
    );
    dir
}

/// One fix we decoded.
#[derive(Debug, Clone)]
struct OurFix {
    time: Option<u32>,
    position: LatLon,
}

#[derive(Debug, Default)]
struct Ours {
    fixes: Vec<OurFix>,
}

fn decode(stream: &[u8]) -> Ours {
    let mut ours = Ours::default();
    let mut demux = Demux::<600>::new();
    let mut sink = |f: Frame<'_>| {
        let Frame::Nmea(text) = f else { return };
        let (time, position) = match Sentence::parse(text) {
            Ok(Sentence::Gga(g)) => (Some(g.time), g.position),
            Ok(Sentence::Rmc(r)) => (Some(r.time), r.position),
            Ok(Sentence::Gll(g)) => (g.time, g.position),
            Ok(Sentence::Gns(g)) => (Some(g.time), g.position),
            _ => return,
        };
        ours.fixes.push(OurFix {
            time: time.map(|t| t.ms_of_day),
            position,
        });
    };
    // Odd reads, as a UART driver would deliver them.
    for chunk in stream.chunks(37) {
        demux.feed(chunk, &mut sink);
    }
    demux.finish_into(&mut sink);
    ours
}

fn same_place(p: &LatLon, lat: f64, lon: f64) -> bool {
    (p.lat - lat).abs() <= 1e-7 && (p.lon - lon).abs() <= 1e-7
}

#[derive(Debug, Default)]
struct Tally {
    gpsd_positions: usize,
    reproduced: usize,
    our_fixes: usize,
    unprinted: usize,
    disagreements: Vec<String>,
}

/// GPSD's speed and track right after each RMC or VTG against ours from that sentence.
/// (Elsewhere GPSD derives them from successive fixes, or holds them: nothing decoded to
/// compare.)
fn speed_and_track(name: &str, chk: &str) -> Vec<String> {
    let mut out = Vec::new();
    for a in gpsd_capture::answered(chk) {
        let (kn, track) = match Sentence::parse(a.body) {
            Ok(Sentence::Rmc(r)) => (r.speed_kn, r.course_deg),
            Ok(Sentence::Vtg(v)) => (v.speed_kn, v.course_deg),
            _ => continue,
        };
        let Some(tpv) = a.tpv else { continue };
        let line = a.line;
        if let (Some(kn), Some(v)) = (kn, tpv["speed"].as_f64())
            && (kn * KNOT_MPS - v).abs() > 0.0005 + 1e-9
        {
            out.push(format!("{name}: speed {kn} kn vs GPSD {v} m/s: {line}"));
        }
        if let (Some(c), Some(v)) = (track, tpv["track"].as_f64())
            && (c - v).abs() > 0.000_05 + 1e-9
        {
            out.push(format!("{name}: track {c} vs GPSD {v}: {line}"));
        }
    }
    out
}

/// Sentences GPSD rejected (its TPV right after says no fix) from which we decode a fix.
fn rejected_but_taken(name: &str, chk: &str) -> Vec<String> {
    gpsd_capture::answered(chk)
        .iter()
        .filter(|a| gpsd_capture::rejected(a))
        .filter(|a| {
            matches!(
                Sentence::parse(a.body),
                Ok(Sentence::Gga(_) | Sentence::Rmc(_) | Sentence::Gll(_) | Sentence::Gns(_))
            )
        })
        .map(|a| format!("{name}: GPSD says no fix, we take one: {}", a.line))
        .collect()
}

fn check_capture(name: &str, raw: &[u8], chk: &str) -> Tally {
    let stream = stream_of(raw);
    let ours = decode(&stream);
    let tpvs = gpsd_tpvs(chk, &sent(&stream));
    let mut t = Tally {
        our_fixes: ours.fixes.len(),
        ..Tally::default()
    };
    let mut distinct: Vec<(f64, f64)> = tpvs.iter().map(|p| (p.lat, p.lon)).collect();
    distinct.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    distinct.dedup();
    t.gpsd_positions = distinct.len();
    for &(lat, lon) in &distinct {
        if ours.fixes.iter().any(|f| same_place(&f.position, lat, lon)) {
            t.reproduced += 1;
        } else {
            t.disagreements
                .push(format!("{name}: GPSD position {lat},{lon} not decoded"));
        }
    }
    for p in &tpvs {
        if let Some(time) = p.time
            && !ours
                .fixes
                .iter()
                .any(|f| f.time == Some(time) && same_place(&f.position, p.lat, p.lon))
        {
            t.disagreements.push(format!(
                "{name}: no fix of ours at {},{} with time {time} ms",
                p.lat, p.lon
            ));
        }
    }
    t.disagreements.extend(speed_and_track(name, chk));
    t.disagreements.extend(rejected_but_taken(name, chk));
    // GPSD merges the sentences of one cycle and reports the last position: a fix of ours
    // that it never printed is one it overwrote (an RMC before the GGA of the same second),
    // not one it rejected. Counted, not failed.
    t.unprinted = ours
        .fixes
        .iter()
        .filter(|f| {
            !distinct
                .iter()
                .any(|&(lat, lon)| same_place(&f.position, lat, lon))
        })
        .count();
    t
}

#[test]
fn every_position_gpsd_reports_from_the_54_captures() {
    let dir = data_dir();
    let names = captures(&dir);
    assert_eq!(names.len(), 54, "captures in {}", dir.display());
    let mut total = Tally::default();
    for name in &names {
        let raw = std::fs::read(dir.join(format!("{name}.log"))).expect("capture");
        let chk = std::fs::read(dir.join(format!("{name}.log.chk"))).expect("GPSD output");
        let t = check_capture(name, &raw, &String::from_utf8_lossy(&chk));
        eprintln!(
            "{name}: {} of {} GPSD positions, {} fixes decoded ({} merged away by GPSD), {} disagreements",
            t.reproduced,
            t.gpsd_positions,
            t.our_fixes,
            t.unprinted,
            t.disagreements.len()
        );
        total.gpsd_positions += t.gpsd_positions;
        total.reproduced += t.reproduced;
        total.our_fixes += t.our_fixes;
        total.unprinted += t.unprinted;
        total.disagreements.extend(t.disagreements);
    }
    let share = total.reproduced as f64 / total.gpsd_positions.max(1) as f64;
    eprintln!(
        "all: {} of {} GPSD positions ({:.2} %), {} fixes decoded ({} merged away by GPSD), {} disagreements",
        total.reproduced,
        total.gpsd_positions,
        100.0 * share,
        total.our_fixes,
        total.unprinted,
        total.disagreements.len()
    );
    // The bar: all of them, and no fix from a sentence GPSD rejected. 819 distinct
    // positions (3 024 fixes of ours) take part when this was written, so an empty comparison
    // cannot pass.
    assert!(
        total.disagreements.is_empty(),
        "{:.2} % of GPSD's positions; {:#?}",
        100.0 * share,
        &total.disagreements[..total.disagreements.len().min(40)]
    );
    assert!(total.gpsd_positions > 800, "{total:?}");
}
