//! Arbitrary bytes after a valid KrakenSDR CSV prefix, in arbitrary reads, through the
//! demultiplexer (spectrum kept) and the bridge; decoded lines re-encode to lines that decode
//! to the same record.
#![no_main]
use foxhunt_bridge::kraken::SPECTRUM_LEN;
use foxhunt_bridge::{Bridge, BridgeConfig, Demux, Frame};
use libfuzzer_sys::fuzz_target;

const PREFIX: &[u8] = b"1679512414650, 134, 0.41, -48.5, 151880000, UCA, 100, dingus, 66.961348, -66.4438057, 0, 0, GPS, R, R, R, R";

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, rest)) = data.split_first() else {
        return;
    };
    let mut stream = PREFIX.to_vec();
    stream.extend_from_slice(rest);
    let mut d = Demux::<600, SPECTRUM_LEN>::new();
    let mut bridge = Bridge::<0>::new(BridgeConfig::default(), []);
    let mut sink = |f: Frame<'_>| {
        if let Frame::KrakenCsv(k) = f {
            let mut line = String::new();
            k.record
                .emit(k.spectrum.unwrap_or(&[]), &mut line)
                .expect("string");
            let mut again = Demux::<600, SPECTRUM_LEN>::new();
            let mut n = 0;
            again.feed(line.as_bytes(), &mut |g| {
                if let Frame::KrakenCsv(r) = g {
                    assert_eq!(r.record.epoch_ms, k.record.epoch_ms);
                    n += 1;
                }
            });
            again.finish_into(&mut |_| {});
            assert_eq!(n, 1, "{line}");
        }
        bridge.push(&f, &mut |_| {});
    };
    for c in stream.chunks(usize::from(chunk % 97) + 1) {
        d.feed(c, &mut sink);
    }
    d.finish_into(&mut sink);
    assert_eq!(d.counters().bytes, stream.len() as u64);
});
