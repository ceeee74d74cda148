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
    // Azimuth 0 (north) is the model angle pi/2, less the meridians' convergence: north at
    // the vehicle (0.005' of longitude east of the origin) is turned by dlon sin(lat) =
    // 1.06e-6 rad clockwise in the origin's frame, so the azimuth is -1.06e-6 there.
    let convergence = (0.005f32 / 60.0).to_radians() * 47f32.to_radians().sin();
    let theta = b[0].theta;
    assert!(
        (theta - (FRAC_PI_2 + convergence)).abs() < 2e-7,
        "{theta} against {}",
        FRAC_PI_2 + convergence
    );
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

fn measurements(events: &[Event]) -> Vec<foxhunt_bridge::bridge::BearingMeasurement> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Bearing(b) => Some(*b),
            _ => None,
        })
        .collect()
}

/// Azimuth in degrees (clockwise from north) of a core bearing.
fn azimuth(b: &foxhunt_core::Bearing) -> f32 {
    (FRAC_PI_2 - b.theta).to_degrees().rem_euclid(360.0)
}

fn feed_raw<const A: usize>(rx: &mut Receiver<A>, parts: &[&[u8]]) -> Vec<Event> {
    let mut events = Vec::new();
    let mut sink = |e| events.push(e);
    for p in parts {
        rx.feed(p, &mut sink);
    }
    rx.finish(&mut sink);
    events
}

#[test]
fn the_heading_rule_in_order_with_the_mounting_offset() {
    use foxhunt_bridge::bridge::HeadingSource::*;
    let config = BridgeConfig {
        declination_deg: Some(2.0),
        mount_offset_deg: 1.0,
        ..BridgeConfig::default()
    };
    // A vehicle standing still (no course): heading sentences only.
    let still = "GPRMC,120000.000,A,4700.0000,N,00800.0000,E,0.0,,010626,,,A";
    let cases: [(&[&str], Option<(f32, _)>); 5] = [
        // A fresh HDT wins over an HDG.
        (
            &["HCHDG,100.0,,,5.0,E", "HEHDT,30.0,T"],
            Some((30.0 + 10.0 + 1.0, TrueHeading)),
        ),
        // HDG with its own variation: 100 - 2 (W deviation) + 5 (E variation) = 103.
        (&["HCHDG,100.0,2.0,W,5.0,E"], Some((103.0 + 11.0, Magnetic))),
        // HDM with the configured declination: 200 + 2.
        (&["HCHDM,200.0,M"], Some((202.0 + 11.0, Magnetic))),
        // THS with mode V is no heading at all.
        (&["GNTHS,10.0,V"], None),
        (&[], None),
    ];
    for (sentences, want) in cases {
        let mut rx = Receiver::<0>::new(config, []);
        let mut bodies = vec![still];
        bodies.extend_from_slice(sentences);
        bodies.push("PFOXB,120000.00,10.0,R,80,433.92");
        let events = run(&mut rx, &bodies);
        let m = measurements(&events);
        match want {
            Some((az, source)) => {
                assert_eq!(m.len(), 1, "{sentences:?}");
                assert!(
                    (azimuth(&m[0].bearing) - az).abs() < 1e-3,
                    "{sentences:?}: {m:?}"
                );
                assert_eq!(m[0].heading, source);
            }
            None => {
                assert!(m.is_empty(), "{sentences:?}");
                assert_eq!(rx.bridge.counters().no_heading, 1);
            }
        }
    }
    // Without a declination an HDM turns nothing; a stale HDT neither.
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    run(
        &mut rx,
        &[
            "HEHDT,30.0,T",
            "HCHDM,200.0,M",
            still,
            "GPRMC,120005.000,A,4700.0000,N,00800.0000,E,0.0,,010626,,,A",
            "PFOXB,120005.00,10.0,R,80,433.92",
        ],
    );
    assert_eq!(rx.bridge.counters().no_heading, 1);
}

#[test]
fn agrelo_bearings_take_their_arrival_time_and_the_latest_fix() {
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let mut fix = line(FIX0);
    fix.extend_from_slice(&line("HEHDT,90.0,T"));
    let events = feed_raw(&mut rx, &[&fix, b"%45/7\r\n%0/7\r%90/0\r\n"]);
    let m = measurements(&events);
    assert_eq!(m.len(), 1, "{events:?}");
    // Relative 45 on a heading of 90: 135 true, at the fix itself.
    assert!((azimuth(&m[0].bearing) - 135.0).abs() < 1e-3);
    assert_eq!(m[0].bearing.vehicle, [0.0, 0.0]);
    assert_eq!(m[0].kind, foxhunt_bridge::bridge::BearingKind::Agrelo);
    let c = rx.bridge.counters();
    assert_eq!((c.no_bearing, c.low_quality), (1, 1));
    // The GPS loses its fix and its clock runs on: a later record has only a stale fix.
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let mut s = line(FIX0);
    s.extend_from_slice(&line("HEHDT,90.0,T"));
    s.extend_from_slice(&line("GPGGA,120005.000,,,,,0,00,,,M,,M,,"));
    s.extend_from_slice(&line("HEHDT,90.0,T"));
    s.extend_from_slice(b"%45/7\r\n");
    feed_raw(&mut rx, &[&s]);
    assert_eq!(rx.bridge.counters().stale_fix, 1);
}

#[test]
fn kraken_records_bring_their_own_position_and_heading() {
    let frame = foxhunt_bridge::geo::LocalFrame::new(
        foxhunt_bridge::nmea::LatLon {
            lat: 47.0,
            lon: 8.0,
        },
        0.0,
    )
    .expect("frame");
    let east = frame.to_geodetic([100.0, 50.0]).expect("point");
    let csv = format!(
        "1780315200000, 20.0, 0.41, -48.5, 433920000, UCA, 100, car, {:.9}, {:.9}, 30.0, 30.0, GPS, R, R, R, R{} \n",
        east.lat,
        east.lon,
        ", 0.00".repeat(360)
    );
    let config = BridgeConfig {
        reference: Some(foxhunt_bridge::nmea::LatLon {
            lat: 47.0,
            lon: 8.0,
        }),
        ..BridgeConfig::default()
    };
    let mut rx = Receiver::<0>::new(config, []);
    let events = feed_raw(&mut rx, &[csv.as_bytes()]);
    let m = measurements(&events);
    assert_eq!(m.len(), 1, "{:?}", rx.counters());
    assert!(
        (azimuth(&m[0].bearing) - 50.0).abs() < 1e-3,
        "30 + 20: {m:?}"
    );
    let v = m[0].bearing.vehicle;
    assert!(
        (v[0] - 100.0).abs() < 0.01 && (v[1] - 50.0).abs() < 0.01,
        "{v:?}"
    );
    assert_eq!(m[0].heading, foxhunt_bridge::bridge::HeadingSource::Record);
    assert!((m[0].freq_mhz - 433.92).abs() < 1e-9);
    // The 2023-05..2024-07 builds: field 2 anticlockwise, so 20 means 340 relative.
    let mut rx = Receiver::<0>::new(
        BridgeConfig {
            kraken_convention: foxhunt_bridge::kraken::CsvConvention::Anticlockwise,
            ..config
        },
        [],
    );
    let m = measurements(&feed_raw(&mut rx, &[csv.as_bytes()]));
    assert!(
        (azimuth(&m[0].bearing) - 10.0).abs() < 1e-3,
        "30 + 340: {m:?}"
    );

    // rdf-sim's KerberosSDR sample: heading 0, DOA 120, so true 240; CONF 15 passes the
    // gate of 10 and CONF 5 does not.
    let sample = "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<DATA>\n\t<STATION_ID>K3CPK-1</STATION_ID>\n\t<TIME>1568052311</TIME>\n\t<FREQUENCY>162.4</FREQUENCY>\n\t<LOCATION>\n\t\t<LATITUDE>39.124526</LATITUDE>\n\t\t<LONGITUDE>-76.519717</LONGITUDE>\n\t\t<HEADING>0</HEADING>\n\t</LOCATION>\n\t<DOA>120</DOA>\n\t<PWR>19.265165</PWR>\n\t<CONF>15</CONF>\n</DATA>\n";
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    let quiet = sample.replace("<CONF>15", "<CONF>5");
    let m = measurements(&feed_raw(&mut rx, &[sample.as_bytes(), quiet.as_bytes()]));
    assert_eq!(m.len(), 1);
    assert!((azimuth(&m[0].bearing) - 240.0).abs() < 1e-3, "{m:?}");
    assert_eq!(rx.bridge.counters().low_quality, 1);
}

#[test]
fn a_bearing_whose_time_jumped_ahead_holds_no_later_one_back() {
    // A drive of 30 one-second fixes with a $PFOXB half a second after each; the fifth
    // bearing's hour digit corrupt (checksum right): 11:00:04.5 instead of 12:00:04.5 is
    // behind, 13:00:04.5 ahead. Either costs that bearing, none of the others.
    for hour in ["11", "13"] {
        let mut bodies = Vec::new();
        for s in 0..30 {
            bodies.push(format!(
                "GPRMC,1200{s:02}.000,A,4700.0000,N,00800.{:04},E,24.5,90.0,010626,,,A",
                s * 100
            ));
            let h = if s == 4 { hour } else { "12" };
            bodies.push(format!("PFOXB,{h}00{s:02}.50,10.0,T,80,433.92"));
        }
        let bodies: Vec<&str> = bodies.iter().map(String::as_str).collect();
        let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
        let b = bearings(&run(&mut rx, &bodies));
        assert!(
            b.len() >= 29,
            "hour {hour}: {} of 30 bearings placed",
            b.len()
        );
    }
}

#[test]
fn a_broker_bearing_held_up_by_an_outage_passes_when_its_clock_was_judged() {
    // One station's KrakenSDR records a second apart; the one of 2.5 s arrives after the one
    // of 5 s, as a broker delivers a bearing held up by an outage. Judged on the station's
    // clock here it went back on its own (refused); a broker's were judged where they were
    // decoded, and all pass as they come.
    let record = |ms: u64| {
        format!(
            "<DATA><STATION_ID>mast-1</STATION_ID><TIME>{}</TIME><FREQUENCY>433.92</FREQUENCY>\
             <LOCATION><LATITUDE>47.0</LATITUDE><LONGITUDE>8.0</LONGITUDE><HEADING>0</HEADING>\
             </LOCATION><DOA>90</DOA><PWR>60</PWR><CONF>80</CONF></DATA>\n",
            1_780_308_000_000 + ms
        )
    };
    let mut times: Vec<u64> = (0..=5).map(|s| s * 1000).collect();
    times.push(2500);
    times.extend((6..10).map(|s| s * 1000));
    let records: Vec<String> = times.iter().map(|&t| record(t)).collect();
    let chunks: Vec<&[u8]> = records.iter().map(|r| r.as_bytes()).collect();
    for (judged, placed, jumped) in [(false, 10, 1), (true, 11, 0)] {
        let config = BridgeConfig {
            judged_clocks: judged,
            ..BridgeConfig::default()
        };
        let mut rx = Receiver::<0>::new(config, []);
        let m = measurements(&feed_raw(&mut rx, &chunks));
        assert_eq!(m.len(), placed, "judged {judged}: {:?}", rx.counters());
        assert_eq!(rx.bridge.counters().time_jump, jumped, "judged {judged}");
    }
}
