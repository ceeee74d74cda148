//! Arbitrary sentence text through the NMEA decoder, and through the framing with a valid
//! checksum, so the fuzzer reaches the field parsers.
#![no_main]
use foxhunt_bridge::nmea::{Sentence, write_sentence};
use foxhunt_bridge::{Demux, Frame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else {
        return;
    };
    let _ = Sentence::parse(text);
    let mut line = String::new();
    if write_sentence(&mut line, text).is_ok() {
        let mut d = Demux::<600>::new();
        let mut sink = |f: Frame<'_>| {
            if let Frame::Nmea(t) = f {
                let _ = Sentence::parse(t);
            }
        };
        d.feed(line.as_bytes(), &mut sink);
        d.finish_into(&mut sink);
    }
});
