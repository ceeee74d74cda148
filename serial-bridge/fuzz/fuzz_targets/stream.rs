//! Arbitrary bytes, in arbitrary reads, through the demultiplexer and the bridge.
#![no_main]
use foxhunt_bridge::{BridgeConfig, Receiver};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, bytes)) = data.split_first() else {
        return;
    };
    let mut rx = Receiver::<2>::new(
        BridgeConfig::default(),
        [(1, [0.0, 0.0]), (0x1a2b, [5.0, 0.0])],
    );
    let mut sink = |_| {};
    for (i, c) in bytes.chunks(usize::from(chunk % 64) + 1).enumerate() {
        rx.feed(c, &mut sink);
        if i % 7 == 6 {
            rx.idle(&mut sink);
        }
    }
    rx.finish(&mut sink);
    assert_eq!(rx.counters().0.bytes, bytes.len() as u64);
});
