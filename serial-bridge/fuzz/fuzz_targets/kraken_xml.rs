//! Arbitrary bytes after `<DATA>`, in arbitrary reads, through the demultiplexer and the
//! bridge; decoded records re-encode (both forms) to records that decode the same.
#![no_main]
use foxhunt_bridge::{Bridge, BridgeConfig, Demux, Frame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, rest)) = data.split_first() else {
        return;
    };
    let mut stream = b"<DATA>".to_vec();
    stream.extend_from_slice(rest);
    let mut d = Demux::<600>::new();
    let mut bridge = Bridge::<0>::new(BridgeConfig::default(), []);
    let mut sink = |f: Frame<'_>| {
        if let Frame::KrakenXml(r) = f {
            for legacy in [false, true] {
                let mut text = String::new();
                if legacy {
                    r.emit_legacy(&mut text).expect("string");
                } else {
                    r.emit(&mut text).expect("string");
                }
                let mut again = Demux::<600>::new();
                let mut n = 0;
                again.feed(text.as_bytes(), &mut |g| {
                    if let Frame::KrakenXml(b) = g {
                        assert_eq!(b.station, r.station);
                        n += 1;
                    }
                });
                again.finish_into(&mut |_| {});
                assert_eq!(n, 1, "{text}");
            }
        }
        bridge.push(&f, &mut |_| {});
    };
    for c in stream.chunks(usize::from(chunk % 61) + 1) {
        d.feed(c, &mut sink);
    }
    d.finish_into(&mut sink);
    assert_eq!(d.counters().bytes, stream.len() as u64);
});
