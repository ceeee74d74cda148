//! One corrupt digit of one KrakenSDR record's time costs that record at most (CSV, XML and
//! the KerberosSDR XML form), wherever the record is and whatever the digit becomes, and a
//! clock that really steps loses nothing.

use foxhunt_bridge::bridge::BearingMeasurement;
use foxhunt_bridge::kraken::{ArrayType, KrakenCsv, KrakenXml, Station};
use foxhunt_bridge::nmea::LatLon;
use foxhunt_bridge::{BridgeConfig, Event, Receiver};
use proptest::prelude::*;

/// The formats a KrakenSDR writes its time in.
#[derive(Debug, Clone, Copy)]
enum Format {
    Csv,
    Xml,
    /// KerberosSDR: TIME in whole seconds.
    XmlSeconds,
}

/// `n` records of a drive east at 10 m/s, about a second apart (`jitter_ms` either way), two
/// channels when `pairs` (both at the same time, as a unit's VFOs report), as the lines a
/// unit writes, with where each one's time digits are.
fn drive(format: Format, n: usize, jitter_ms: &[i64], pairs: bool) -> Vec<(String, usize, usize)> {
    let start = 1_780_308_000_000u64;
    let mut lines = Vec::new();
    for k in 0..n {
        let step = if pairs { k / 2 } else { k };
        let t = (start as i64 + 1000 * step as i64 + jitter_ms[step % jitter_ms.len()]) as u64;
        let t = match format {
            Format::XmlSeconds => t / 1000 * 1000,
            _ => t,
        };
        let position = Some(LatLon {
            lat: 47.0,
            lon: 8.0 + 1.3e-4 * step as f64,
        });
        let freq = if pairs && k % 2 == 1 { 433.95 } else { 433.92 };
        let mut s = String::new();
        match format {
            Format::Csv => {
                let r = KrakenCsv {
                    epoch_ms: t,
                    bearing_deg: 30.0 + step as f32 * 0.1,
                    confidence: 0.9,
                    power_db: -40.0,
                    freq_hz: (freq * 1e6) as u64,
                    array: ArrayType::Uca,
                    latency_ms: 100,
                    station: Station::new("car"),
                    position,
                    heading_deg: 90.0,
                };
                r.emit(&[], &mut s).expect("string");
            }
            Format::Xml | Format::XmlSeconds => {
                let r = KrakenXml {
                    station: Station::new("car"),
                    time_ms: Some(t),
                    gps_time_ms: None,
                    freq_mhz: Some(freq),
                    position,
                    heading_deg: Some(90.0),
                    speed_mps: Some(10.0),
                    doa_deg: 330.0 - step as f32 * 0.1,
                    pwr: Some(60.0),
                    conf: Some(90.0),
                };
                if matches!(format, Format::XmlSeconds) {
                    r.emit_legacy(&mut s).expect("string");
                } else {
                    r.emit(&mut s).expect("string");
                    s.push('\n');
                }
            }
        }
        let (from, len) = match format {
            Format::Csv => (0, 13),
            Format::Xml => (s.find("<TIME>").expect("TIME") + 6, 13),
            Format::XmlSeconds => (s.find("<TIME>").expect("TIME") + 6, 10),
        };
        lines.push((s, from, len));
    }
    lines
}

/// The bearings the bridge hands on for `bytes`, and how many records it refused as jumps.
fn decode(bytes: &[u8]) -> (Vec<BearingMeasurement>, u32) {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let mut out = Vec::new();
    let mut sink = |e| {
        if let Event::Bearing(b) = e {
            out.push(b);
        }
    };
    rx.feed(bytes, &mut sink);
    rx.finish(&mut sink);
    let jumps = rx.counters().1.time_jump;
    (out, jumps)
}

/// What the drive is worth downstream: bearings handed on that are not behind an earlier one
/// of their source (the core refuses those as going backwards).
fn usable(bearings: &[BearingMeasurement]) -> usize {
    let mut latest = i64::MIN;
    let mut n = 0;
    for b in bearings {
        if b.time_ms >= latest {
            latest = b.time_ms;
            n += 1;
        }
    }
    n
}

fn bytes_of(lines: &[(String, usize, usize)]) -> Vec<u8> {
    lines.iter().flat_map(|(s, _, _)| s.bytes()).collect()
}

fn format() -> impl Strategy<Value = Format> {
    prop_oneof![
        Just(Format::Csv),
        Just(Format::Xml),
        Just(Format::XmlSeconds)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn one_corrupt_time_digit_costs_one_record_at_most(
        format in format(),
        n in 12usize..40,
        pairs in any::<bool>(),
        jitter in prop::collection::vec(-150i64..150, 1..8),
        at in any::<prop::sample::Index>(),
        digit in any::<prop::sample::Index>(),
        to in 0u8..10,
    ) {
        let mut lines = drive(format, n, &jitter, pairs);
        let clean = decode(&bytes_of(&lines));
        prop_assert_eq!((clean.0.len(), clean.1), (n, 0));
        prop_assert_eq!(usable(&clean.0), n);
        let k = at.index(n);
        let (line, from, len) = &mut lines[k];
        let d = digit.index(*len);
        let mut b = std::mem::take(line).into_bytes();
        b[*from + d] = b'0' + to;
        *line = String::from_utf8(b).expect("ascii");
        let (got, jumps) = decode(&bytes_of(&lines));
        let kept = usable(&got);
        prop_assert!(
            kept + 1 >= n,
            "record {} digit {} -> {}: {} of {} usable, {} refused as jumps",
            k, d, to, kept, n, jumps
        );
        prop_assert!(jumps <= 1);
    }

    #[test]
    fn a_clock_that_steps_and_stays_loses_nothing(
        format in prop_oneof![Just(Format::Csv), Just(Format::Xml)],
        n in 12usize..40,
        // From the fourth record on: a step back between the first two is a first record's
        // jump forward as far as anyone can tell.
        at in 3usize..12,
        step_s in prop_oneof![-7200i64..-3, 2i64..7200],
    ) {
        let lines = drive(format, n, &[0], false);
        // Every record from `at` on moved by the step (the unit's clock was set).
        let shifted: Vec<(String, usize, usize)> = lines
            .into_iter()
            .enumerate()
            .map(|(k, (s, from, len))| {
                if k < at {
                    return (s, from, len);
                }
                let old: u64 = s[from..from + len].parse().expect("time");
                let new = (old as i64 + 1000 * step_s) as u64;
                (format!("{}{new}{}", &s[..from], &s[from + len..]), from, len)
            })
            .collect();
        let (got, jumps) = decode(&bytes_of(&shifted));
        // Forward, every record passes in order; back, every one passes too (the core then
        // judges the older times), none refused as a jump.
        prop_assert_eq!((got.len(), jumps), (n, 0));
        if step_s > 0 {
            prop_assert_eq!(usable(&got), n);
        }
    }
}

/// The reproduction: record 30 of a 60-record drive pushed a minute into the future
/// lost every later record (29 of 59) as going backwards.
#[test]
fn a_time_pushed_a_minute_ahead_costs_its_record_not_the_drive() {
    for format in [Format::Csv, Format::Xml, Format::XmlSeconds] {
        let mut lines = drive(format, 60, &[0], false);
        let (line, from, len) = &mut lines[30];
        let digit = *from + *len
            - if matches!(format, Format::XmlSeconds) {
                2
            } else {
                5
            };
        let mut b = std::mem::take(line).into_bytes();
        b[digit] = b'9';
        *line = String::from_utf8(b).expect("ascii");
        let (got, jumps) = decode(&bytes_of(&lines));
        eprintln!(
            "{format:?}: {} of 60 handed on, {} usable, {jumps} refused as a jump",
            got.len(),
            usable(&got)
        );
        assert_eq!((got.len(), usable(&got), jumps), (59, 59, 1), "{format:?}");
    }
}
