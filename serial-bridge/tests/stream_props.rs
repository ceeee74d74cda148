//! Property tests of the demultiplexer and the bridge on arbitrary and damaged streams.

use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_bridge::nmea::{Sentence, write_sentence};
use foxhunt_bridge::{BridgeConfig, Demux, Frame, MtFrame, Receiver};
use proptest::prelude::*;

/// A frame as the tests describe it: its bytes on the wire and what it decodes to.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Expected {
    Nmea(String),
    Mt(u8, u8, Vec<u8>),
}

fn wire(e: &Expected) -> Vec<u8> {
    match e {
        Expected::Nmea(body) => {
            let mut s = String::new();
            write_sentence(&mut s, body).expect("string");
            s.into_bytes()
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
    ]
}

fn parse(chunks: &[&[u8]]) -> (Vec<Expected>, foxhunt_bridge::StreamCounters) {
    let mut d = Demux::<600>::new();
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
