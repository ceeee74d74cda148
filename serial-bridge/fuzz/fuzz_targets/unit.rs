//! Arbitrary bytes on the DF unit's four ports (commands on the user port included), in
//! arbitrary reads and interleavings, through the whole unit: demultiplexers, bridge, tracker,
//! commands and the sentences it writes; and every line of them read back as a unit sentence.
#![no_main]
use foxhunt_bridge::telemetry::UnitSentence;
use foxhunt_bridge::unit::{Port, Unit, UnitConfig};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, bytes)) = data.split_first() else {
        return;
    };
    let mut unit = Unit::new(UnitConfig::default());
    let mut said = Vec::new();
    let mut out = |s: &[u8]| {
        said.extend_from_slice(s);
        true
    };
    for (i, c) in bytes.chunks(usize::from(chunk % 48) + 2).enumerate() {
        let (&which, c) = c.split_first().unwrap_or((&0, &[]));
        let port = Port::from_index(which % 4).unwrap_or(Port::Gps);
        unit.feed(port, c, &mut out);
        if i % 5 == 4 {
            unit.idle(port, &mut out);
        }
    }
    for line in said.split(|b| *b == b'\n') {
        if let Ok(text) = std::str::from_utf8(line) {
            let body = text.trim_end().trim_start_matches('$');
            let body = body.split('*').next().unwrap_or("");
            let _ = UnitSentence::parse(body);
        }
    }
    if let Ok(text) = std::str::from_utf8(bytes) {
        let _ = UnitSentence::parse(text);
    }
});
