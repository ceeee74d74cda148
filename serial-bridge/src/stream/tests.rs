use super::*;

fn frames(stream: &[u8]) -> (std::vec::Vec<std::string::String>, StreamCounters) {
    let mut d = Demux::<DEFAULT_CAPACITY>::new();
    let mut out = std::vec::Vec::new();
    let mut sink = |f: Frame<'_>| out.push(std::format!("{f:?}"));
    d.feed(stream, &mut sink);
    d.finish_into(&mut sink);
    (out, *d.counters())
}

#[test]
fn sentence_and_mt_frame_interleaved_with_garbage() {
    let mut s = std::vec::Vec::new();
    s.extend_from_slice(
        b"xx$GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A*43\r\n",
    );
    s.extend_from_slice(&[0x00, 0xFE, 0x02, 0x44, 0x81, 0xFE, 0xFE, 0x02 ^ 0x44 ^ 0x81]);
    s.extend_from_slice(
        b"$GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,*76\n",
    );
    let (out, c) = frames(&s);
    assert_eq!(out.len(), 3, "{out:?}");
    assert!(out[0].starts_with("Nmea(\"GPRMC,092750.000"));
    assert!(out[1].contains("data: [254, 254]"), "{}", out[1]);
    assert_eq!((c.sentences, c.mt_frames, c.garbage_bytes), (2, 1, 3));
}

fn sentence(body: &str) -> std::string::String {
    let mut s = std::string::String::new();
    crate::nmea::write_sentence(&mut s, body).expect("string");
    s
}

#[test]
fn bad_checksum_costs_one_frame() {
    let good = sentence("GPXXX,2");
    let s = std::format!("$GPGGA,1*00\r\n{good}");
    let (out, c) = frames(s.as_bytes());
    assert_eq!(c.bad_checksum, 1);
    assert_eq!(out.len(), 1, "{out:?}");
}

#[test]
fn over_long_line_is_dropped_and_counted() {
    let long = sentence(&"A".repeat(200));
    let s = std::format!("{long}{}", sentence("GPXXX,2"));
    let (out, c) = frames(s.as_bytes());
    assert_eq!(c.too_long, 1);
    assert_eq!(out.len(), 1);
}

#[test]
fn truncated_frame_at_the_end_is_counted() {
    let s = std::format!("{}$GPGGA,12", sentence("GPXXX,2"));
    let (out, c) = frames(s.as_bytes());
    assert_eq!((out.len(), c.truncated), (1, 1));
}

#[test]
fn forged_mt_frame_cannot_swallow_the_sentences_inside_it() {
    // A damaged sentence holds a 0xFE whose LEN spans the next sentence and ends inside the
    // one after, where a byte happens to match its FCS: refused, because the sentence it
    // spans is valid and followed by another.
    let (b, d) = (sentence("GPBBB,2"), sentence("GPDDD,4"));
    for k in 0..10_000 {
        let c = sentence(&std::format!("GPCCC,{k}"));
        let cmd1 = b"PpQq"[k % 4];
        for len in b.len()..b.len() + c.len() - 1 {
            let mut s = b"$GPAAA,1".to_vec();
            s.extend_from_slice(&[MT_SOF, len as u8, b'G', cmd1]);
            let o = s.len() - 4;
            s.extend_from_slice(b.as_bytes());
            s.extend_from_slice(c.as_bytes());
            s.extend_from_slice(d.as_bytes());
            if scan_mt(&s[o..]) != Scan::Valid(len + 5) {
                continue;
            }
            let (out, counters) = frames(&s);
            assert_eq!(counters.overlapping, 1);
            let want: std::vec::Vec<_> = [&b, &c, &d]
                .iter()
                .map(|x| std::format!("Nmea({:?})", &x[1..x.len() - 5]))
                .collect();
            assert_eq!(out, want);
            return;
        }
    }
    panic!("no forgery found to test with");
}

#[test]
fn a_decision_needing_more_than_the_buffer_does_not_stall() {
    // O: an MT frame of 255 data bytes whose last data byte is 0xFE, so an inner candidate
    // I starts there with O's FCS as its LEN (250), valid thanks to the filler after O,
    // and followed by the start of a 260-byte candidate: deciding I's support needs bytes
    // beyond the 528-byte buffer.
    let mut o = std::vec![MT_SOF, 255, 0x44, 0x81];
    o.extend(std::iter::repeat_n(0u8, 254));
    o.push(MT_SOF);
    let fcs_without_first = o[1..].iter().fold(0u8, |x, b| x ^ b);
    o[4] = fcs_without_first ^ 250; // makes O's FCS 250
    o.push(250);
    assert_eq!(scan_mt(&o), Scan::Valid(260));
    let i_start = o.len() - 2;
    let mut s = o;
    s.extend(std::iter::repeat_n(0u8, i_start + 255 - s.len()));
    let i_fcs = s[i_start + 1..i_start + 254].iter().fold(0u8, |x, b| x ^ b);
    s[i_start + 254] = i_fcs;
    assert_eq!(scan_mt(&s[i_start..]), Scan::Valid(255));
    s.extend_from_slice(&[MT_SOF, 0xFF]);
    s.extend(std::iter::repeat_n(0x55u8, 600));
    let mut d = Demux::<DEFAULT_CAPACITY>::new();
    let mut n = 0;
    d.feed(&s, &mut |_| n += 1);
    d.finish_into(&mut |_| n += 1);
    assert_eq!(d.counters().bytes, s.len() as u64);
    // Settled with what the buffer held: O is delivered (no valid frame follows its inner
    // candidate within the buffer), and the 260-byte candidate after it fails its FCS.
    let c = d.counters();
    assert_eq!(
        (n, c.mt_frames, c.bad_fcs, c.overlapping),
        (1, 1, 1, 0),
        "{c:?}"
    );
}

#[test]
fn gpsd_grade_line_ends_lengths_and_binary_neighbours() {
    let rtk =
        "GPGGA,132820.60,4134.49821229,N,09345.03351845,W,2,09,1.0,278.020,M,-31.442,M,7.6,0133";
    let mut s = std::vec::Vec::new();
    // u-blox UBX (0xB5 0x62) and SiRF (0xA0 0xA2 ... 0xB0 0xB3) frames, one with an MT
    // start byte and a '$' in its payload, between sentences with every line end.
    s.extend_from_slice(&[
        0xB5, 0x62, 0x01, 0x07, 0x04, 0x00, 0xFE, 0x10, b'$', 0x00, 0x3A, 0x9C,
    ]);
    s.extend_from_slice(std::format!("${rtk}*7E\r\r\n").as_bytes());
    s.extend_from_slice(&[0xA0, 0xA2, 0x00, 0x02, 0xFE, 0x05, 0x01, 0x03, 0xB0, 0xB3]);
    s.extend_from_slice(sentence("GPXXX,1").trim_end().as_bytes());
    s.extend_from_slice(b"\n");
    s.extend_from_slice(sentence("GPXXX,2").as_bytes());
    let (out, c) = frames(&s);
    let want = [
        std::format!("Nmea({rtk:?})"),
        "Nmea(\"GPXXX,1\")".into(),
        "Nmea(\"GPXXX,2\")".into(),
    ];
    assert_eq!(out, want, "{c:?}");
    // 130 bytes from '$' to LF is GPSD's limit; 131 is too long.
    for (len, ok) in [(130, true), (131, false)] {
        let body = std::format!("GPXXX,{}", "9".repeat(len - 12));
        let line = sentence(&body);
        assert_eq!(line.len(), len);
        let (out, c) = frames(line.as_bytes());
        assert_eq!((out.len() == 1, c.too_long == 1), (ok, !ok), "{len}");
    }
}

#[test]
fn a_kraken_line_in_odd_reads_keeps_its_spectrum_only_when_asked() {
    let line = crate::kraken::tests::issue_11_line();
    let mut keep = Demux::<DEFAULT_CAPACITY, SPECTRUM_LEN>::new();
    let mut drop = Demux::<DEFAULT_CAPACITY>::new();
    let mut seen = std::vec::Vec::new();
    for chunk in line.as_bytes().chunks(7) {
        keep.feed(chunk, &mut |f| {
            if let Frame::KrakenCsv(k) = f {
                // Index 0 is the front; clockwise 1 degree is anticlockwise index 359.
                seen.push((k.spectrum_clockwise(0), k.spectrum_clockwise(1)));
            }
        });
        drop.feed(chunk, &mut |f| {
            if let Frame::KrakenCsv(k) = f {
                assert_eq!(k.spectrum, None);
                assert_eq!(k.record.epoch_ms, 1_679_512_414_650);
            }
        });
    }
    assert_eq!(seen, [(Some(0.07), Some(3.59))]);
    assert_eq!(
        (keep.counters().kraken_csv, drop.counters().kraken_csv),
        (1, 1)
    );
    // Nothing of the 2.5 KB line is held once it is read.
    assert_eq!(keep.pending(), 0);
}

#[test]
fn a_form_feed_after_digits_is_garbage_not_a_stall() {
    // Found by the flipped-byte property: ',' ^ 0x20 is a form feed, ASCII whitespace
    // that no record starts with; the scan once stopped on it without moving.
    let s = std::format!("1600000000005\x0c 134.5{}", sentence("GPXXX,1"));
    let (out, c) = frames(s.as_bytes());
    assert_eq!(out, ["Nmea(\"GPXXX,1\")"]);
    // 13 digits, the form feed and "134.5"; the space is skipped silently.
    assert_eq!(c.garbage_bytes, 19, "{c:?}");
}

#[test]
fn a_payload_carrying_whole_frames_is_one_frame() {
    // Found by cargo-fuzz: this payload holds two valid MT frames back to back; the
    // outer frame comes first and in sync, so it is delivered whole.
    let data = [
        0xFE, 0xFE, 0x01, 0x01, 0xFF, 0x00, 0xFF, 0xFE, 0x01, 0x01, 0x00, 0x00, 0x00, 0xFE, 0xFC,
        0xFF,
    ];
    let mut wire = [0u8; 32];
    let n = MtFrame {
        cmd0: 0x01,
        cmd1: 0x81,
        data: &data,
    }
    .encode(&mut wire)
    .expect("fits");
    let (out, _) = frames(&wire[..n]);
    assert_eq!(out.len(), 1, "{out:?}");
}
