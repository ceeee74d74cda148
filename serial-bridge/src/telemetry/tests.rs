use super::*;
use crate::stream::{Demux, Frame};

fn body(s: &[u8]) -> String {
    let mut d = Demux::<{ crate::stream::DEFAULT_CAPACITY }>::new();
    let mut out = Vec::new();
    d.feed(s, &mut |f| {
        if let Frame::Nmea(t) = f {
            out.push(t.to_string());
        }
    });
    assert_eq!(out.len(), 1, "{}", String::from_utf8_lossy(s));
    out.remove(0)
}

#[test]
fn a_fix_round_trips_through_the_demultiplexer() {
    let fix = FixSentence {
        time: UtcTime {
            ms_of_day: 36_061_250,
        },
        position: Some(LatLon {
            lat: 47.010_123_4,
            lon: -8.005_432_1,
        }),
        major_m: 123.45,
        minor_m: 6.04,
        orientation_deg: 179.96,
        cep50_m: 40.0,
        used: 117,
        window: 120,
        sigma_deg: 1.234,
        status: Status::Valid,
    };
    let mut w = fix.write();
    let line = w.finish().unwrap().to_vec();
    assert_eq!(
        String::from_utf8_lossy(&line),
        "$PFOXF,100101.25,4700.607404,N,00800.325926,W,123.5,6.0,180.0,40.0,117,120,1.23,A*0C\r\n"
    );
    let text = body(&line);
    let Ok(UnitSentence::Fix(back)) = UnitSentence::parse(&text) else {
        panic!("{text}")
    };
    let p = back.position.unwrap();
    assert!((p.lat - 47.010_123_4).abs() < 1e-7 && (p.lon + 8.005_432_1).abs() < 1e-7);
    assert_eq!(
        (back.used, back.window, back.status),
        (117, 120, Status::Valid)
    );
    assert!((back.major_m - 123.5).abs() < 1e-4 && (back.sigma_deg - 1.23).abs() < 1e-6);
}

#[test]
fn a_fix_without_position_has_empty_fields() {
    let fix = FixSentence {
        time: UtcTime { ms_of_day: 0 },
        position: None,
        major_m: 0.0,
        minor_m: 0.0,
        orientation_deg: 0.0,
        cep50_m: 0.0,
        used: 0,
        window: 2,
        sigma_deg: 2.0,
        status: Status::TooFew,
    };
    let mut w = fix.write();
    let line = w.finish().unwrap().to_vec();
    let text = body(&line);
    assert_eq!(text, "PFOXF,000000.00,,,,,,,,,0,2,2.00,N");
    assert_eq!(UnitSentence::parse(&text), Ok(UnitSentence::Fix(fix)));
    // A status with a position needs one.
    assert!(UnitSentence::parse("PFOXF,000000.00,,,,,,,,,0,2,2.00,A").is_err());
}

#[test]
fn status_link_ready_and_ack_round_trip_at_their_widest() {
    let s = StatusSentence {
        uptime_s: u32::MAX,
        stack_bytes: 4096,
        queue_high: [u32::MAX; 4],
        latency_ticks: u32::MAX,
        fix_ticks: u32::MAX,
        reset: Some(ResetCause::Watchdog),
    };
    let l = LinkSentence {
        bytes: [u32::MAX; 3],
        overruns: u32::MAX,
        full: u32::MAX,
        dropped: u32::MAX,
        rejected: u32::MAX,
        bearings: u32::MAX,
        fixes: u32::MAX,
    };
    let (mut sw, mut lw) = (s.write(), l.write());
    let (st, lt) = (body(sw.finish().unwrap()), body(lw.finish().unwrap()));
    assert_eq!(UnitSentence::parse(&st), Ok(UnitSentence::Status(s)));
    assert_eq!(UnitSentence::parse(&lt), Ok(UnitSentence::Link(l)));
    let r = ReadySentence {
        version: 1,
        reset: ResetCause::Panic,
    };
    let rt = body(r.write().finish().unwrap());
    assert_eq!(rt, "PFOXR,1,P");
    assert_eq!(UnitSentence::parse(&rt), Ok(UnitSentence::Ready(r)));
    assert_eq!(
        UnitSentence::parse("PFOXA,WINDOW,OK,60,300"),
        Ok(UnitSentence::Ack(AckSentence {
            command: "WINDOW",
            ok: true,
            detail: "60,300"
        }))
    );
    assert_eq!(
        UnitSentence::parse("GPGGA,1"),
        Err(TelemetryError::Unsupported)
    );
}

#[test]
fn an_overflowing_sentence_is_never_cut() {
    let mut s = SentenceBuf::new("PFOXA");
    for _ in 0..20 {
        s.field(b"ABCDEFGH");
    }
    assert!(s.finish().is_none());
}

#[test]
fn a_fix_no_unit_could_have_made_is_refused() {
    let ok = "PFOXF,100101.25,4700.607404,N,00800.325926,W,123.5,6.0,180.0,40.0,117,120,1.23,A";
    assert!(UnitSentence::parse(ok).is_ok());
    for (bad, field) in [
        // The major axis turned past 180 degrees.
        (ok.replace(",180.0,", ",400.0,"), 8),
        // The semi-minor axis longer than the semi-major.
        (ok.replace("123.5,6.0", "123.5,600.0"), 7),
        // More bearings used than the window holds.
        (ok.replace(",117,120,", ",600,60,"), 10),
    ] {
        assert_eq!(
            UnitSentence::parse(&bad),
            Err(TelemetryError::BadField(field)),
            "{bad}"
        );
    }
}
