use super::*;
use crate::geo::LocalFrame;
use crate::nmea::LatLon;
use crate::telemetry::UnitSentence;

const CAPTURE: &[u8] = include_bytes!("../../captures/aoa-drive.nmea");

fn bodies(out: &[u8]) -> std::vec::Vec<String> {
    let mut d = Demux::<DEFAULT_CAPACITY>::new();
    let mut v = std::vec::Vec::new();
    d.feed(out, &mut |f| {
        if let Frame::Nmea(t) = f {
            v.push(t.to_string());
        }
    });
    v
}

fn command(c: &str) -> std::vec::Vec<u8> {
    let sum = crate::nmea::checksum(c);
    format!("${c}*{sum:02X}\r\n").into_bytes()
}

/// The bundled drive split by sentence kind into the GPS and DF ports, in its own order.
fn run(unit: &mut Unit, out: &mut std::vec::Vec<u8>) {
    for line in CAPTURE.split_inclusive(|b| *b == b'\n') {
        let port = Port::of_record(line).unwrap_or(Port::Gps);
        unit.feed(port, line, &mut |s| {
            out.extend_from_slice(s);
            true
        });
    }
}

#[test]
fn the_drive_gives_a_fix_per_bearing_and_ends_inside_its_ellipse() {
    let mut unit = Unit::default();
    let mut out = std::vec::Vec::new();
    run(&mut unit, &mut out);
    let fixes: std::vec::Vec<_> = bodies(&out)
        .iter()
        .filter_map(|b| match UnitSentence::parse(b) {
            Ok(UnitSentence::Fix(f)) => Some(f),
            _ => None,
        })
        .collect();
    assert_eq!(fixes.len(), 60);
    assert_eq!(unit.link().fixes, 60);
    let last = unit.last_fix().copied().unwrap();
    assert_eq!(
        last.status,
        foxhunt_core::fix::window::Status::Valid,
        "{last:?}"
    );
    // aoa-drive's emitter is at (1200, 800) from the first fix: inside the 95 % ellipse
    // (its semi-major axis bounds the distance).
    let err = libm::hypotf(last.position[0] - 1200.0, last.position[1] - 800.0);
    assert!(err < last.major, "{err} m from the emitter: {last:?}");
}

#[test]
fn the_projection_follows_the_exact_inverse() {
    let frame = LocalFrame::new(
        LatLon {
            lat: 47.0,
            lon: 8.0,
        },
        0.0,
    )
    .unwrap();
    let p = Projection::new(&frame).unwrap();
    let worst = |r: f64| {
        let mut w = 0.0f64;
        for k in 0..72 {
            let a = (k as f64 * 5.0).to_radians();
            let (e, n) = (r * a.cos(), r * a.sin());
            let exact = frame.to_geodetic([e, n]).unwrap();
            let q = p.at(e, n);
            let dn = (q.lat - exact.lat) * 111_200.0;
            let de = (q.lon - exact.lon) * 111_200.0 * 47f64.to_radians().cos();
            w = w.max(dn.hypot(de));
        }
        w
    };
    // Third order in the distance: centimetres at 10 km, metres at 50 km.
    let (w10, w50) = (worst(10_000.0), worst(50_000.0));
    assert!(w10 < 0.1, "{w10} m at 10 km");
    assert!(w50 < 5.0, "{w50} m at 50 km");
    eprintln!("projection error: {w10:.4} m at 10 km, {w50:.3} m at 50 km");
}

#[test]
fn commands_are_acknowledged_and_kept() {
    let mut unit = Unit::default();
    let mut out = std::vec::Vec::new();
    let mut send = |unit: &mut Unit, c: &str| {
        unit.feed(Port::User, &command(c), &mut |s| {
            out.extend_from_slice(s);
            true
        });
    };
    send(&mut unit, "PFOXC,SIGMA,1.5");
    send(&mut unit, "PFOXC,WINDOW,30,60");
    send(&mut unit, "PFOXC,MOUNT,-2.5");
    send(&mut unit, "PFOXC,GATE,101");
    send(&mut unit, "PFOXC,REF,4700.0000,N,00800.0000,E");
    send(&mut unit, "PFOXC,SHOW");
    let acks = bodies(&out);
    assert_eq!(
        acks,
        [
            "PFOXA,SIGMA,OK,1.50",
            "PFOXA,WINDOW,OK,30,60",
            "PFOXA,MOUNT,OK,-2.5",
            "PFOXA,GATE,ERR,ARGUMENT",
            "PFOXA,REF,OK,4700.000000,N,00800.000000,E",
            "PFOXA,SHOW,OK,1.50,40.0,-2.5,30,60,OFF,4700.000000,N,00800.000000,E",
        ]
    );
    assert_eq!(unit.config().window.window, 30);
    let mut out = std::vec::Vec::new();
    run(&mut unit, &mut out);
    let last = unit.last_fix().copied().unwrap();
    assert_eq!(last.window, 30);
    assert!((last.sigma - 1.5f32.to_radians()).abs() < 1e-6);
}
