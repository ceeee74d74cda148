//! Arbitrary text through the Agrelo decoder; what decodes re-encodes and frames to itself.
#![no_main]
use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::{Demux, Frame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else {
        return;
    };
    if let Ok(a) = Agrelo::parse(text) {
        let mut out = String::new();
        a.emit(&mut out).expect("string");
        let again = Agrelo::parse(&out).expect("an emitted record parses");
        assert!((again.bearing_deg - a.bearing_deg).abs() <= 0.05 + 1e-3);
        assert_eq!(again.quality, a.quality);
    }
    let mut d = Demux::<600>::new();
    let mut seen = 0;
    let mut line = String::from(text);
    line.push_str("\r\n");
    d.feed(line.as_bytes(), &mut |f| {
        if let Frame::Agrelo(t) = f {
            assert!(Agrelo::parse(t).is_ok(), "framed records parse");
            seen += 1;
        }
    });
    d.finish_into(&mut |_| {});
    let _ = seen;
});
