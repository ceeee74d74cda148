//! Stations: who took each bearing, each with its own headings and motion; a full table, a
//! surveyed position, one unit's two logs.

use foxhunt_bridge::bridge::{BearingMeasurement, StationKey};
use foxhunt_bridge::kraken::{ArrayType, KrakenCsv, KrakenXml, Station};
use foxhunt_bridge::nmea::LatLon;
use foxhunt_bridge::{BridgeConfig, Event, Receiver};

/// A KrakenXML record of station `id` at `at` with boresight `heading` and a relative bearing.
fn xml(id: &str, t_ms: u64, at: LatLon, heading: f32, relative: f32) -> Vec<u8> {
    let mut s = String::new();
    KrakenXml {
        station: Station::new(id),
        time_ms: Some(t_ms),
        gps_time_ms: None,
        freq_mhz: Some(433.92),
        position: Some(at),
        heading_deg: Some(heading),
        speed_mps: Some(0.0),
        doa_deg: (360.0 - relative).rem_euclid(360.0),
        pwr: Some(60.0),
        conf: Some(90.0),
    }
    .emit(&mut s)
    .expect("string");
    s.push('\n');
    s.into_bytes()
}

fn measurements<const S: usize>(rx: &mut Receiver<0, S>, bytes: &[u8]) -> Vec<BearingMeasurement> {
    let mut out = Vec::new();
    let mut sink = |e| {
        if let Event::Bearing(b) = e {
            out.push(b);
        }
    };
    rx.feed(bytes, &mut sink);
    rx.finish(&mut sink);
    out
}

/// Four fixed arrays around a room, boresights 0, 90, 180 and 270 degrees, their records
/// interleaved in one stream 100 ms apart: four steady headings, not one vehicle spinning at
/// 900 degrees a second, so the yaw gate keeps every bearing.
#[test]
fn four_fixed_arrays_in_one_stream_are_four_steady_stations() {
    let mut bytes = Vec::new();
    let corners = [
        (0.0, 0.0, 0.0),
        (0.0, 0.0002, 90.0),
        (0.0002, 0.0002, 180.0),
        (0.0002, 0.0, 270.0),
    ];
    for k in 0..100u64 {
        for (a, (dlat, dlon, heading)) in corners.iter().enumerate() {
            let at = LatLon {
                lat: 47.0 + dlat,
                lon: 8.0 + dlon,
            };
            let id = format!("anchor-{a}");
            let t = 1_780_000_000_000 + 400 * k + 100 * a as u64;
            bytes.extend(xml(&id, t, at, *heading, 45.0));
        }
    }
    let mut rx = Receiver::<0, 8>::new(BridgeConfig::default(), []);
    let m = measurements(&mut rx, &bytes);
    let counters = rx.bridge.counters();
    assert_eq!(counters.turning, 0, "{counters:?}");
    assert_eq!(m.len(), 400);
    let stations = rx.bridge.stations();
    assert_eq!(stations.len(), 4);
    for (i, s) in stations.iter().enumerate() {
        assert!(s.fixed() && s.bearings() == 100, "{i}: {s:?}");
        assert!(m.iter().filter(|b| usize::from(b.station) == i).count() == 100);
    }
}

/// The same four arrays as one unnamed unit (no STATION_ID): then they are one station, and
/// its heading jumps by 90 degrees every record: the gate drops what turns.
#[test]
fn the_same_records_without_ids_look_like_one_spinning_unit() {
    let mut bytes = Vec::new();
    for k in 0..50u64 {
        for (a, heading) in [0.0, 90.0, 180.0, 270.0].into_iter().enumerate() {
            let at = LatLon {
                lat: 47.0,
                lon: 8.0,
            };
            let t = 1_780_000_000_000 + 400 * k + 100 * a as u64;
            bytes.extend(xml("", t, at, heading, 45.0));
        }
    }
    let mut rx = Receiver::<0, 8>::new(BridgeConfig::default(), []);
    let m = measurements(&mut rx, &bytes);
    assert_eq!(rx.bridge.stations().len(), 1);
    assert!(
        rx.bridge.counters().turning > 100,
        "{:?}",
        rx.bridge.counters()
    );
    assert!(m.len() < 100);
}

/// A KrakenSDR's CSV line and its XML record name the same station; a moving unit is mobile.
#[test]
fn one_units_csv_and_xml_are_one_station_and_a_moving_one_is_mobile() {
    let mut bytes = Vec::new();
    for k in 0..20u32 {
        let at = LatLon {
            lat: 47.0 + 0.0001 * f64::from(k),
            lon: 8.0,
        };
        let t = 1_780_000_000_000 + 1000 * u64::from(k);
        let mut s = String::new();
        KrakenCsv {
            epoch_ms: t,
            bearing_deg: 30.0,
            confidence: 0.9,
            power_db: -40.0,
            freq_hz: 433_920_000,
            array: ArrayType::Uca,
            latency_ms: 100,
            station: Station::new("car-1"),
            position: Some(at),
            heading_deg: 0.0,
        }
        .emit(&[], &mut s)
        .expect("string");
        bytes.extend(s.into_bytes());
        bytes.extend(xml("car-1", t, at, 0.0, 30.0));
    }
    let mut rx = Receiver::<0, 4>::new(BridgeConfig::default(), []);
    let m = measurements(&mut rx, &bytes);
    assert_eq!(m.len(), 40);
    let stations = rx.bridge.stations();
    assert_eq!(stations.len(), 1);
    assert!(
        !stations[0].fixed() && stations[0].span_m() > 200.0,
        "{:?}",
        stations[0]
    );
    assert!(m.iter().all(|b| b.station == 0));
}

/// Stations past the table's capacity are counted, not mixed with the others; a surveyed one
/// is placed where it stands.
#[test]
fn a_full_table_is_counted_and_a_surveyed_station_stands_where_surveyed() {
    let at = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    // A table of two rows.
    let mut rx = Receiver::<0, 2>::new(BridgeConfig::default(), []);
    let mast = LatLon {
        lat: 47.01,
        lon: 8.02,
    };
    assert!(
        rx.bridge
            .survey(StationKey::Named(Station::new("mast")), mast)
    );
    let mut bytes = Vec::new();
    // A unit's first record waits for its second (its clock is judged on its own), so each
    // station is heard twice before the next starts.
    for (k, id) in ["mast", "b", "mast", "b", "c", "c", "c"].iter().enumerate() {
        bytes.extend(xml(id, 1_780_000_000_000 + 1000 * k as u64, at, 0.0, 10.0));
    }
    let m = measurements(&mut rx, &bytes);
    // "mast" and "b" fill the two rows; "c" is refused three times.
    assert_eq!(rx.bridge.counters().stations_full, 3);
    assert_eq!(m.len(), 4);
    let s = &rx.bridge.stations()[0];
    assert!(s.fixed() && s.surveyed() == Some(mast));
    // The records say (47, 8); the mast stands 1.1 km north and 1.5 km east of it.
    let frame = rx.bridge.local_frame().expect("a frame");
    let expected = frame.to_local(mast).expect("local");
    let b = m.iter().find(|b| b.station == 0).expect("a mast bearing");
    assert!((f64::from(b.bearing.vehicle[0]) - expected[0]).abs() < 0.5);
    assert!((f64::from(b.bearing.vehicle[1]) - expected[1]).abs() < 0.5);
}
