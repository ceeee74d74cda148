//! The bridge's placement of bearings and its rejections, each counted by reason.

use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_bridge::nmea::write_sentence;
use foxhunt_bridge::{BridgeConfig, Event, Receiver};
use std::f32::consts::FRAC_PI_2;

fn line(body: &str) -> Vec<u8> {
    let mut s = String::new();
    write_sentence(&mut s, body).expect("string");
    s.into_bytes()
}

fn run<const A: usize>(rx: &mut Receiver<A>, bodies: &[&str]) -> Vec<Event> {
    let mut events = Vec::new();
    let mut sink = |e| events.push(e);
    for b in bodies {
        rx.feed(&line(b), &mut sink);
    }
    rx.finish(&mut sink);
    events
}

fn bearings(events: &[Event]) -> Vec<foxhunt_core::Bearing> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Bearing(b) => Some(b.bearing),
            _ => None,
        })
        .collect()
}

// Two fixes 0.01 minute of longitude apart (about 12.6 m east at 47 N), one second apart.
const FIX0: &str = "GPRMC,120000.000,A,4700.0000,N,00800.0000,E,24.5,90.0,010626,,,A";
const FIX1: &str = "GPRMC,120001.000,A,4700.0000,N,00800.0100,E,24.5,90.0,010626,,,A";

#[test]
fn bearing_between_fixes_is_interpolated_and_waits_for_the_later_fix() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let events = run(&mut rx, &[FIX0, "PFOXB,120000.50,0.0,T,80,433.92", FIX1]);
    let b = bearings(&events);
    assert_eq!(b.len(), 1);
    let east = rx.bridge.latest_fix().expect("fix").local[0];
    assert!((east - 12.65).abs() < 0.05, "{east}");
    assert!(
        (b[0].vehicle[0] - east / 2.0).abs() < 0.01,
        "{:?}",
        b[0].vehicle
    );
    // Azimuth 0 (north) is the model angle pi/2.
    assert!((b[0].theta - FRAC_PI_2).abs() < 1e-6);
}

#[test]
fn relative_bearing_turns_by_the_course_and_needs_one() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    // 12.6 m/s from 11:59:57: the speed gate (2 m/s held 3 s) opens at 12:00:00.
    let earlier: Vec<String> = (57..60)
        .map(|s| format!("GPRMC,1159{s}.000,A,4700.0000,N,00759.9{s}0,E,24.5,90.0,010626,,,A"))
        .collect();
    let events = run(
        &mut rx,
        &[
            "PFOXB,115956.00,10.0,R,80,433.92",
            &earlier[0],
            &earlier[1],
            &earlier[2],
            "PFOXB,115959.00,10.0,R,80,433.92",
            FIX0,
            "PFOXB,120000.00,10.0,R,80,433.92",
        ],
    );
    let b = bearings(&events);
    assert_eq!(rx.bridge.counters().no_heading, 2);
    assert_eq!(b.len(), 1);
    // Course 90 + relative 10 = azimuth 100 degrees.
    let expected = FRAC_PI_2 - 100f32.to_radians();
    assert!((b[0].theta - expected).abs() < 1e-5, "{}", b[0].theta);
}

#[test]
fn stale_missing_and_low_quality_bearings_are_counted() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    run(&mut rx, &["PFOXB,120000.00,10.0,T,80,433.92"]);
    assert_eq!(rx.bridge.counters().no_fix, 1);
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let events = run(
        &mut rx,
        &[
            FIX0,
            "PFOXB,120010.00,10.0,T,80,433.92",
            "PFOXB,120000.00,10.0,T,40,433.92",
        ],
    );
    assert!(bearings(&events).is_empty());
    let c = rx.bridge.counters();
    assert_eq!((c.stale_fix, c.low_quality), (1, 1));
}

#[test]
fn no_fix_sentences_and_bad_fields_are_counted_not_used() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let events = run(
        &mut rx,
        &[
            "GPGGA,120000.000,,,,,0,00,,,M,,M,,",
            "GPRMC,120000.000,V,,,,,,,010626,,,N",
            "GPGGA,120000.000,4799.0000,N,00800.0000,E,1,08,1.0,0.0,M,0.0,M,,",
            "GPGSV,1,1,00",
        ],
    );
    assert!(events.is_empty());
    let c = rx.bridge.counters();
    assert_eq!(
        (c.no_fix_sentences, c.bad_field, c.unsupported_sentences),
        (2, 1, 1)
    );
}

#[test]
fn a_drive_across_midnight_keeps_time_order() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let events = run(
        &mut rx,
        &[
            "GPGGA,235959.500,4700.0000,N,00800.0000,E,1,08,1.0,0.0,M,0.0,M,,",
            "PFOXB,000000.00,0.0,T,80,433.92",
            "GPGGA,000000.500,4700.0000,N,00800.0100,E,1,08,1.0,0.0,M,0.0,M,,",
        ],
    );
    let b = bearings(&events);
    assert_eq!(b.len(), 1);
    assert!(
        b[0].vehicle[0] > 6.0 && b[0].vehicle[0] < 6.7,
        "{:?}",
        b[0].vehicle
    );
}

#[test]
fn rssi_from_known_anchors_only() {
    let mut rx = Receiver::<1>::new(BridgeConfig::default(), [(0x1a2b, [3.0, 4.0])]);
    let mut events = Vec::new();
    let mut sink = |e| events.push(e);
    for addr in [0x1a2b, 0x0bad] {
        let msg = AfIncomingMsg {
            group_id: 0,
            cluster_id: 6,
            src_addr: addr,
            src_endpoint: 1,
            dst_endpoint: 1,
            was_broadcast: false,
            link_quality: 255,
            security_use: false,
            timestamp: 99,
            trans_seq: 1,
            data: &[1, 2, 3],
        };
        let mut buf = [0u8; 64];
        let n = msg.encode(&mut buf).expect("fits");
        rx.feed(&buf[..n], &mut sink);
    }
    rx.finish(&mut sink);
    assert_eq!(rx.bridge.counters().unknown_anchor, 1);
    match events.as_slice() {
        [Event::Rssi(r)] => {
            assert_eq!((r.anchor, r.timestamp), (0, 99));
            assert!((r.dbm - 10.0).abs() < 1e-4);
        }
        other => panic!("{other:?}"),
    }
}
