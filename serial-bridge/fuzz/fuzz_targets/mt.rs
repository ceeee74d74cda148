//! Arbitrary MT frames: decode, re-encode, and frame again; all must agree.
#![no_main]
use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_bridge::{Demux, Frame, MtFrame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&cmd, payload)) = data.split_first() else {
        return;
    };
    let payload = &payload[..payload.len().min(255)];
    let frame = MtFrame {
        cmd0: if cmd & 1 == 0 { 0x44 } else { cmd },
        cmd1: 0x81,
        data: payload,
    };
    if let Ok(msg) = AfIncomingMsg::parse(&frame) {
        let mut out = [0u8; 300];
        let n = msg.encode(&mut out).expect("a decoded message re-encodes");
        let mut d = Demux::<600>::new();
        let mut seen = None;
        let mut sink = |f: Frame<'_>| {
            if let Frame::Mt(m) = f {
                seen = AfIncomingMsg::parse(&m)
                    .ok()
                    .map(|a| (a.src_addr, a.link_quality, a.timestamp, a.data.to_vec()));
            }
        };
        d.feed(&out[..n], &mut sink);
        d.finish_into(&mut sink);
        assert_eq!(
            seen,
            Some((
                msg.src_addr,
                msg.link_quality,
                msg.timestamp,
                msg.data.to_vec()
            ))
        );
    }
    let mut wire = [0u8; 300];
    if let Ok(n) = frame.encode(&mut wire) {
        let mut d = Demux::<600>::new();
        let mut count = 0;
        d.feed(&wire[..n], &mut |_| count += 1);
        d.finish_into(&mut |_| count += 1);
        assert_eq!(count, 1);
    }
});
