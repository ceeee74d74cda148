//! Property tests of the demultiplexer and the bridge on arbitrary and damaged streams.

use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::kraken::{ArrayType, KrakenCsv, KrakenXml, SPECTRUM_LEN, Station};
use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_bridge::nmea::{LatLon, Sentence, write_sentence};
use foxhunt_bridge::{BridgeConfig, Demux, Frame, MtFrame, Receiver};
use proptest::prelude::*;

/// A frame as the tests describe it: its bytes on the wire and what it decodes to.
#[derive(Debug, Clone)]
enum Expected {
    Nmea(String),
    Mt(u8, u8, Vec<u8>),
    /// Record text, `%` to the quality or magnetic field.
    Agrelo(String),
    /// The line as the decoder's record re-emits it (spectrum included).
    Csv(String),
    /// The one-line XML form the record re-emits; `true`: sent in the KerberosSDR form.
    Xml(String, bool),
}

impl PartialEq for Expected {
    fn eq(&self, other: &Self) -> bool {
        use Expected::*;
        match (self, other) {
            (Nmea(a), Nmea(b)) | (Agrelo(a), Agrelo(b)) | (Csv(a), Csv(b)) => a == b,
            (Mt(a, b, c), Mt(x, y, z)) => (a, b, c) == (x, y, z),
            (Xml(a, _), Xml(b, _)) => a == b,
            _ => false,
        }
    }
}

fn csv_line(r: &KrakenCsv, spectrum: &[f32]) -> String {
    let mut s = String::new();
    r.emit(spectrum, &mut s).expect("string");
    s
}

fn xml_line(r: &KrakenXml) -> String {
    let mut s = String::new();
    r.emit(&mut s).expect("string");
    s
}

/// The description of the one frame `wire` decodes to alone.
fn canonical(wire: &[u8]) -> Expected {
    let (got, _) = parse(&[wire]);
    assert_eq!(got.len(), 1, "{}", String::from_utf8_lossy(wire));
    got.into_iter().next().expect("one")
}

fn csv_case(epoch: u64, bearing10: u16, conf: u8, lat7: i32, spectrum_seed: u32) -> Expected {
    let r = KrakenCsv {
        epoch_ms: 1_600_000_000_000 + epoch,
        bearing_deg: f32::from(bearing10 % 3600) / 10.0,
        confidence: f32::from(conf) / 100.0,
        power_db: -48.5,
        freq_hz: 151_880_000,
        array: ArrayType::Uca,
        latency_ms: 100,
        station: Station::new("dingus"),
        position: Some(LatLon {
            lat: f64::from(lat7) * 1e-7,
            lon: -66.443_805_7,
        }),
        heading_deg: 12.5,
    };
    let spectrum: Vec<f32> = (0..SPECTRUM_LEN as u32)
        .map(|i| ((i * 7 + spectrum_seed) % 3000) as f32 / 100.0)
        .collect();
    canonical(csv_line(&r, &spectrum).as_bytes())
}

fn xml_case(time: u64, doa10: u16, legacy: bool) -> Expected {
    let r = KrakenXml {
        station: Station::new("K3CPK-1"),
        time_ms: Some(1_568_052_311_000 + time * 1000),
        gps_time_ms: None,
        freq_mhz: Some(162.4),
        position: Some(LatLon {
            lat: 39.124_526,
            lon: -76.519_717,
        }),
        heading_deg: Some(0.0),
        speed_mps: None,
        doa_deg: f32::from(doa10 % 3600) / 10.0,
        pwr: Some(19.3),
        conf: Some(15.0),
    };
    let mut wire = String::new();
    if legacy {
        r.emit_legacy(&mut wire).expect("string");
    } else {
        r.emit(&mut wire).expect("string");
    }
    match canonical(wire.as_bytes()) {
        Expected::Xml(c, _) => Expected::Xml(c, legacy),
        other => panic!("{other:?}"),
    }
}

fn wire(e: &Expected) -> Vec<u8> {
    match e {
        Expected::Nmea(body) => {
            let mut s = String::new();
            write_sentence(&mut s, body).expect("string");
            s.into_bytes()
        }
        Expected::Agrelo(text) => format!("{text}\r\n").into_bytes(),
        Expected::Csv(line) => line.clone().into_bytes(),
        Expected::Xml(line, false) => line.clone().into_bytes(),
        Expected::Xml(line, true) => {
            let mut d = Demux::<600>::new();
            let mut legacy = String::new();
            d.feed(line.as_bytes(), &mut |f| {
                if let Frame::KrakenXml(r) = f {
                    r.emit_legacy(&mut legacy).expect("string");
                }
            });
            d.finish_into(&mut |_| {});
            legacy.into_bytes()
        }
        Expected::Mt(cmd0, cmd1, data) => {
            let mut out = vec![0; data.len() + 5];
            let n = MtFrame {
                cmd0: *cmd0,
                cmd1: *cmd1,
                data,
            }
            .encode(&mut out)
            .expect("fits");
            out.truncate(n);
            out
        }
    }
}

fn describe(f: Frame<'_>) -> Expected {
    match f {
        Frame::Nmea(s) => Expected::Nmea(s.to_string()),
        Frame::Mt(m) => Expected::Mt(m.cmd0, m.cmd1, m.data.to_vec()),
        Frame::Agrelo(t) => Expected::Agrelo(t.to_string()),
        Frame::KrakenCsv(k) => Expected::Csv(csv_line(&k.record, k.spectrum.unwrap_or(&[]))),
        Frame::KrakenXml(r) => Expected::Xml(xml_line(&r), false),
    }
}

fn frame() -> impl Strategy<Value = Expected> {
    prop_oneof![
        // Sentence bodies: printable ASCII without '$' or '*', up to 70 characters.
        "[A-Z]{5}(,[0-9A-Za-z. -]{0,9}){0,7}".prop_map(Expected::Nmea),
        Just(Expected::Nmea(
            "GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,".into()
        )),
        (
            any::<u8>(),
            any::<u8>(),
            prop::collection::vec(any::<u8>(), 0..40)
        )
            .prop_map(|(a, b, d)| Expected::Mt(a, b, d)),
        // Payloads full of start bytes.
        (0usize..40).prop_map(|n| Expected::Mt(0x44, 0x81, vec![0xFE; n])),
        (0usize..20).prop_map(|n| Expected::Mt(0x44, 0x81, b"$GP".repeat(n))),
        (
            0u16..=3600,
            0u8..10,
            prop::option::of(0u16..3600),
            any::<bool>()
        )
            .prop_map(|(b, q, m, dec)| {
                let a = Agrelo {
                    bearing_deg: if dec {
                        f32::from(b) / 10.0
                    } else {
                        f32::from(b / 10)
                    },
                    quality: q,
                    magnetic_deg: m.map(|m| f32::from(m / 10)),
                };
                let mut t = String::new();
                a.emit(&mut t).expect("string");
                Expected::Agrelo(t)
            }),
        (
            0u64..1_000_000,
            any::<u16>(),
            0u8..100,
            -900_000_000i32..900_000_000,
            any::<u32>()
        )
            .prop_map(|(e, b, c, lat, sp)| csv_case(e, b, c, lat, sp)),
        (0u64..1_000_000, any::<u16>(), any::<bool>()).prop_map(|(t, d, l)| xml_case(t, d, l)),
    ]
}

fn parse(chunks: &[&[u8]]) -> (Vec<Expected>, foxhunt_bridge::StreamCounters) {
    let mut d = Demux::<600, SPECTRUM_LEN>::new();
    let mut out = Vec::new();
    let mut sink = |f: Frame<'_>| out.push(describe(f));
    for c in chunks {
        d.feed(c, &mut sink);
    }
    d.finish_into(&mut sink);
    (out, *d.counters())
}

/// Whether `want` appears in `got` in order (other frames may sit between).
fn in_order(want: &[&Expected], got: &[Expected]) -> bool {
    let mut it = got.iter();
    want.iter().all(|w| it.any(|g| g == *w))
}

/// Flip byte `p` of the stream of `frames` by `mask`: do all frames not holding it come
/// through, in order?
fn survives_flip(frames: &[Expected], p: usize, mask: u8) -> bool {
    let wires: Vec<Vec<u8>> = frames.iter().map(wire).collect();
    let mut stream = wires.concat();
    stream[p] ^= mask;
    let (got, _) = parse(&[&stream]);
    let mut start = 0;
    let mut kept = Vec::new();
    for (f, w) in frames.iter().zip(&wires) {
        if !(start..start + w.len()).contains(&p) {
            kept.push(f);
        }
        start += w.len();
    }
    in_order(&kept, &got)
}

proptest! {
    // A fixed seed: the flipped-byte property can fail by a double checksum coincidence (about
    // 2 flips in 100 000, measured by `flipped_byte_loss_rate` below), and CI must not flicker.
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn any_split_parses_identically(
        frames in prop::collection::vec(frame(), 1..12),
        cuts in prop::collection::vec(any::<prop::sample::Index>(), 0..12),
    ) {
        let stream: Vec<u8> = frames.iter().flat_map(wire).collect();
        let (whole, whole_counters) = parse(&[&stream]);
        prop_assert_eq!(&whole, &frames);
        let mut points: Vec<usize> = cuts.iter().map(|c| c.index(stream.len() + 1)).collect();
        points.sort_unstable();
        let mut pieces = Vec::new();
        let mut last = 0;
        for p in points {
            pieces.push(&stream[last..p]);
            last = p;
        }
        pieces.push(&stream[last..]);
        let (split, split_counters) = parse(&pieces);
        prop_assert_eq!(split, whole);
        prop_assert_eq!(split_counters, whole_counters);
    }

    #[test]
    fn one_flipped_byte_costs_at_most_the_frame_holding_it(
        frames in prop::collection::vec(frame(), 1..10),
        at in any::<prop::sample::Index>(),
        mask in 1u8..=255,
    ) {
        let len: usize = frames.iter().map(|f| wire(f).len()).sum();
        let p = at.index(len);
        prop_assert!(survives_flip(&frames, p, mask), "lost a frame: flipped byte {} of {:?}", p, frames);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000), chunk in 1usize..64) {
        let mut rx = Receiver::<2>::new(BridgeConfig::default(), [(1, [0.0, 0.0]), (2, [5.0, 0.0])]);
        let mut events = 0usize;
        let mut sink = |_| events += 1;
        for c in bytes.chunks(chunk) {
            rx.feed(c, &mut sink);
            rx.idle(&mut sink);
        }
        rx.finish(&mut sink);
        let (s, _) = rx.counters();
        prop_assert_eq!(s.bytes, bytes.len() as u64);
    }

    #[test]
    fn sentence_and_mt_decoders_take_anything(text in "\\PC{0,90}", data in prop::collection::vec(any::<u8>(), 0..60)) {
        let _ = Sentence::parse(&text);
        let _ = AfIncomingMsg::parse(&MtFrame { cmd0: 0x44, cmd1: 0x81, data: &data });
    }

    #[test]
    fn mangled_real_sentences_never_panic(
        pick in 0usize..4,
        at in any::<prop::sample::Index>(),
        byte in any::<u8>(),
    ) {
        let bodies = [
            "GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,",
            "GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A",
            "PFOXB,092751.00,57.3,T,83,433.920",
            "PFOXB,092751.00,57.3,R,83,433.920,5321.6802,N,00630.3372,W",
        ];
        let mut b = bodies[pick].as_bytes().to_vec();
        let i = at.index(b.len());
        b[i] = byte;
        if let Ok(text) = std::str::from_utf8(&b) {
            let _ = Sentence::parse(text);
        }
    }
}

/// The rate at which one flipped byte costs a frame that does not hold it.
///
/// A flip can forge an MT frame: a corrupt LEN, or a 0xFE inside a damaged sentence. The
/// forgery must pass the 8-bit FCS, and then still loses to a valid frame starting inside it
/// unless a second coincidence backs it (its end followed by a valid frame, or the inner frame
/// reaching the end of the stream exactly). Measured: 20 in 1 000 000 random flips of random
/// streams, most on payloads full of 0xFE, whose XOR structure makes coincidences likelier.
#[test]
fn flipped_byte_loss_rate() {
    use rand_core::{Rng, SeedableRng};
    let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(7);
    let trials = 200_000;
    let mut lost = 0;
    for _ in 0..trials {
        let n = 1 + rng.next_u32() % 9;
        let frames: Vec<Expected> = (0..n)
            .map(|_| match rng.next_u32() % 4 {
                0 => Expected::Nmea(
                    "GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,".into(),
                ),
                1 => Expected::Nmea(format!("GPXXX,{}", rng.next_u32())),
                2 => Expected::Mt(0x44, 0x81, vec![0xFE; (rng.next_u32() % 40) as usize]),
                _ => {
                    let len = rng.next_u32() % 40;
                    let (a, b) = (rng.next_u32() as u8, rng.next_u32() as u8);
                    Expected::Mt(a, b, (0..len).map(|_| rng.next_u32() as u8).collect())
                }
            })
            .collect();
        let len: usize = frames.iter().map(|f| wire(f).len()).sum();
        let p = rng.next_u32() as usize % len;
        if !survives_flip(&frames, p, 1 + (rng.next_u32() % 255) as u8) {
            lost += 1;
        }
    }
    eprintln!("{lost} of {trials} flips cost a frame they did not touch");
    // Expected about 4 at the measured rate; 20 (1e-4) is far outside Poisson noise, so a
    // regression in the resync logic fails here.
    assert!(
        lost <= 20,
        "{lost} of {trials} flips cost a frame they did not touch"
    );
}

/// Every byte of every new record kind flipped by several masks, between other records: only
/// the record holding the byte may be lost (exhaustive, unlike the sampled property above).
#[test]
fn every_flip_in_agrelo_and_kraken_records_costs_only_that_record() {
    let gga =
        Expected::Nmea("GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,".into());
    let kinds = [
        Expected::Agrelo("%136.5/8/158".into()),
        Expected::Agrelo("%0/7".into()),
        csv_case(5, 1345, 41, 669_613_480, 7),
        xml_case(3, 1200, true),
        xml_case(3, 1200, false),
    ];
    let mut flips = 0;
    for k in &kinds {
        for next in [&gga, k, &Expected::Agrelo("%90/3".into())] {
            let frames = [gga.clone(), k.clone(), next.clone(), gga.clone()];
            let start = wire(&gga).len();
            for p in start..start + wire(k).len() {
                for mask in [0x01, 0x02, 0x10, 0x20, 0x40, 0x80, 0xff, 0x0f, 0x55] {
                    flips += 1;
                    assert!(
                        survives_flip(&frames, p, mask),
                        "byte {p} ^ {mask:#x} of {k:?} then {next:?}"
                    );
                }
            }
        }
    }
    assert!(flips > 50_000, "{flips}");
}
