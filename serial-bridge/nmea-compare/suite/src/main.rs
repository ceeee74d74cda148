//! Share of GPSD's positions over its regression captures that each decoder reproduces (to
//! 1e-7 degrees), ours and the AeroRust `nmea` crate's, both behind our framing, and the fixes
//! each takes from sentences GPSD rejected. The captures and the comparison are those of
//! serial-bridge/tests/gpsd.rs: TPVs reported right after a sentence the receiver sent.
//!
//! Run: cargo run --release [-- DIR] (default: the vendored captures, serial-bridge/tests/data/gpsd)

use foxhunt_bridge::nmea::Sentence;
use foxhunt_bridge::{Demux, Frame};
use gpsd_capture::{sent, stream_of};

// The captures read as the decoder test reads them.
#[path = "../../../tests/gpsd_capture/mod.rs"]
#[allow(dead_code)]
mod gpsd_capture;

/// GPSD's distinct positions from the receiver's own sentences.
fn gpsd_positions(chk: &str, sent: &std::collections::HashSet<Vec<u8>>) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = gpsd_capture::gpsd_tpvs(chk, sent)
        .iter()
        .map(|t| (t.lat, t.lon))
        .collect();
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
    gpsd_capture::answered(chk)
        .iter()
        .filter(|a| gpsd_capture::rejected(a))
        .map(|a| a.body.to_string())
        .collect()
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/gpsd").into());
    let names = gpsd_capture::captures(std::path::Path::new(&dir));
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
