//! Geometry and time in the bridge (docs/src/formats/bridge.md): bearings carried into the local frame through
//! the meridians' convergence, fixes kept by time span so late bearings are still placed,
//! and the yaw-rate gate.

use foxhunt_bridge::bridge::{BearingMeasurement, FIX_HISTORY};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::{LatLon, PositionField, TimeField, UtcTime, write_sentence};
use foxhunt_bridge::{BridgeConfig, Event, Receiver};
use foxhunt_core::estimator::batch_fix;
use foxhunt_core::{Bearing, Method};

fn sentence(out: &mut Vec<u8>, body: &str) {
    let mut s = String::new();
    write_sentence(&mut s, body).expect("string");
    out.extend_from_slice(s.as_bytes());
}

fn time(ms: u32) -> TimeField {
    TimeField(UtcTime {
        ms_of_day: 36_000_000 + ms,
    })
}

/// GGA and RMC of one epoch.
fn fix(out: &mut Vec<u8>, ms: u32, p: LatLon, speed_mps: f64, course_deg: f64) {
    let (t, pos) = (time(ms), PositionField(p));
    sentence(out, &format!("GPGGA,{t},{pos},1,09,0.9,0.0,M,0.0,M,,"));
    sentence(
        out,
        &format!(
            "GPRMC,{t},A,{pos},{:.2},{course_deg:.2},010626,,,A",
            speed_mps / 0.514_444
        ),
    );
}

fn pfoxb(out: &mut Vec<u8>, ms: u32, azimuth_deg: f64, reference: char) {
    let a = azimuth_deg.rem_euclid(360.0);
    sentence(
        out,
        &format!("PFOXB,{},{a:.4},{reference},90,433.920", time(ms)),
    );
}

fn hdt(out: &mut Vec<u8>, deg: f64) {
    sentence(out, &format!("HEHDT,{:.2},T", deg.rem_euclid(360.0)));
}

fn decode(bytes: &[u8], config: BridgeConfig) -> (Vec<BearingMeasurement>, Receiver<0>) {
    let mut rx = Receiver::<0>::new(config, []);
    let mut out = Vec::new();
    let mut sink = |e| {
        if let Event::Bearing(b) = e {
            out.push(b)
        }
    };
    rx.feed(bytes, &mut sink);
    rx.finish(&mut sink);
    (out, rx)
}

/// The azimuth at `p` of the emitter at `q`: the chord in `p`'s own tangent plane, what a DF
/// unit with a true-north reference measures.
fn azimuth_at(p: LatLon, q: LatLon) -> f64 {
    let t = LocalFrame::new(p, 0.0)
        .and_then(|f| f.to_local(q))
        .expect("local");
    t[0].atan2(t[1]).to_degrees()
}

/// ML fix error, metres.
fn fix_error(bearings: &[Bearing], truth: [f32; 2]) -> f32 {
    let f = batch_fix(Method::Ml, bearings).expect("fix");
    (f.position[0] - truth[0]).hypot(f.position[1] - truth[1])
}

/// RMS error of the ML fix over `runs` seeded draws of 2 degree noise on `bearings`.
fn noisy_rmse(bearings: &[Bearing], truth: [f32; 2], runs: u64) -> f32 {
    use rand_core::SeedableRng;
    let sigma = 2f32.to_radians();
    let ss: f32 = (0..runs)
        .map(|run| {
            let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(run);
            let noisy: Vec<Bearing> = bearings
                .iter()
                .map(|b| Bearing {
                    theta: b.theta + sigma * foxhunt_core::random::normal(&mut rng),
                    sigma,
                    ..*b
                })
                .collect();
            fix_error(&noisy, truth).powi(2)
        })
        .sum();
    (ss / runs as f32).sqrt()
}

#[test]
fn a_20_km_drive_is_exact_at_47_and_70_north() {
    for (lat, bar_before) in [(47.0, 5.0), (70.0, 10.0)] {
        let origin = LatLon { lat, lon: 10.0 };
        let frame = LocalFrame::new(origin, 0.0).expect("frame");
        // The drive of the field tests: 10 km east, then 10 km north, a bearing every 50 m
        // (10 m/s), true azimuths to an emitter at (6 km, 4 km).
        let e_local = [6000.0f64, 4000.0];
        let emitter = frame.to_geodetic(e_local).expect("emitter");
        let route: Vec<[f64; 2]> = (0..400)
            .map(|k| {
                let s = 50.0 * k as f64;
                if s < 10_000.0 {
                    [s, 0.0]
                } else {
                    [10_000.0, s - 10_000.0]
                }
            })
            .collect();
        let mut bytes = Vec::new();
        let mut raw = Vec::new();
        for (k, v) in route.iter().enumerate() {
            let here = frame.to_geodetic(*v).expect("vehicle");
            let ms = 5000 * k as u32;
            fix(
                &mut bytes,
                ms,
                here,
                10.0,
                if v[1] == 0.0 { 90.0 } else { 0.0 },
            );
            let a = azimuth_at(here, emitter);
            pfoxb(&mut bytes, ms, a, 'T');
            raw.push(a);
        }
        let (got, rx) = decode(&bytes, BridgeConfig::default());
        assert_eq!(got.len(), route.len(), "{:?}", rx.counters());
        let after: Vec<Bearing> = got.iter().map(|b| b.bearing).collect();
        // What the bridge did before: the azimuth as measured, at the same place.
        let before: Vec<Bearing> = got
            .iter()
            .zip(&raw)
            .map(|(b, a)| {
                Bearing::from_azimuth(b.bearing.vehicle, (*a as f32).to_radians(), b.bearing.sigma)
            })
            .collect();
        let truth = [e_local[0] as f32, e_local[1] as f32];
        let worst = |bs: &[Bearing]| {
            bs.iter()
                .map(|b| b.residual(&truth).abs())
                .fold(0.0f32, f32::max)
        };
        let (e_before, e_after) = (fix_error(&before, truth), fix_error(&after, truth));
        let (w_before, w_after) = (worst(&before), worst(&after));
        let (r_before, r_after) = (
            noisy_rmse(&before, truth, 40),
            noisy_rmse(&after, truth, 40),
        );
        eprintln!(
            "{lat} N: noise-free fix {e_before:.1} m off before, {e_after:.3} m after; worst \
             bearing {:.4} deg before, {:.6} deg after; 2 deg noise, 40 runs: rmse \
             {r_before:.1} m before, {r_after:.1} m after",
            w_before.to_degrees(),
            w_after.to_degrees()
        );
        // After: the positions carry 1.9 mm of NMEA rounding and the azimuths 5e-5 degrees
        // of PFOXB's four decimals, at 2-10 km: 1e-5 rad is twice both, with f32 room.
        assert!(w_after < 1e-5, "{lat}: worst residual {w_after} rad");
        assert!(e_after < 0.2, "{lat}: fix {e_after} m off");
        // Before: the convergence reaches 0.19 (47 N) and 0.37 degrees (70 N) at the far end.
        assert!(
            e_before > bar_before,
            "{lat}: uncorrected fix only {e_before} m off"
        );
        // With noise the bias adds to the spread: the corrected rmse is smaller. (Both are
        // over the same 40 noise draws, so the difference is the bias alone.)
        assert!(
            r_after < r_before,
            "{lat}: rmse {r_after} against {r_before}"
        );
    }
}

/// A straight drive east at 20 m/s from the origin, `hz` fixes a second for `seconds`, with
/// a true bearing stamped at each whole second but written `late_ms` after it; the bytes and
/// the bearings written.
fn late_drive(hz: u32, seconds: u32, late_ms: u32) -> (Vec<u8>, usize) {
    let origin = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    let frame = LocalFrame::new(origin, 0.0).expect("frame");
    let step = 1000 / hz;
    let mut bytes = Vec::new();
    let mut due: Vec<u32> = (1..seconds).map(|s| s * 1000).collect();
    let mut written = 0;
    for k in 0..=(seconds * hz) {
        let ms = k * step;
        let p = frame
            .to_geodetic([20.0 * f64::from(ms) / 1000.0, 0.0])
            .expect("vehicle");
        fix(&mut bytes, ms, p, 20.0, 90.0);
        while due.first().is_some_and(|t| t + late_ms <= ms) {
            pfoxb(&mut bytes, due.remove(0), 0.0, 'T');
            written += 1;
        }
    }
    (bytes, written)
}

#[test]
fn bearings_seconds_behind_a_fast_gps_are_placed_where_the_vehicle_was() {
    for hz in [10, 20, 50] {
        let (bytes, written) = late_drive(hz, 12, 1500);
        let (got, rx) = decode(&bytes, BridgeConfig::default());
        let c = rx.counters().1;
        assert_eq!((got.len(), written), (10, 10), "{hz} Hz: {c:?}");
        let worst = got
            .iter()
            .map(|b| {
                let t = (b.time_ms - 36_000_000) as f32 / 1000.0;
                (b.bearing.vehicle[0] - 20.0 * t).hypot(b.bearing.vehicle[1])
            })
            .fold(0.0f32, f32::max);
        eprintln!("{hz} Hz GPS, bearings 1.5 s late: 10 of 10 placed, worst {worst:.4} m off");
        // On a straight line at constant speed interpolation is exact: what is left is the
        // NMEA rounding (1.9 mm) and f32 at 240 m. The 8-fix history placed them at the
        // oldest fix kept, 14 m (10 Hz) to 27 m (50 Hz) from the truth.
        assert!(worst < 0.01, "{hz} Hz: {worst} m off");
        assert_eq!((c.late, c.stale_fix), (0, 0), "{hz} Hz");
        assert!(rx.bridge.fix_history().len() <= FIX_HISTORY);
    }
}

#[test]
fn a_bearing_older_than_the_fixes_kept_is_counted_not_misplaced() {
    // 7 s late, the span 5 s: the fixes around it are gone.
    let (bytes, written) = late_drive(10, 12, 7000);
    let (got, rx) = decode(&bytes, BridgeConfig::default());
    let c = rx.counters().1;
    // The bearings of seconds 1-5, written at 8-12 s, past the span: all counted late, none
    // placed.
    assert_eq!((got.len(), c.late, written), (0, 5, 5), "{c:?}");
    // A longer span places them.
    let config = BridgeConfig {
        fix_span_ms: 8000,
        ..BridgeConfig::default()
    };
    let (got, rx) = decode(&bytes, config);
    assert_eq!((got.len(), rx.counters().1.late), (5, 0));
}

/// A drive at 10 m/s with a true-heading sensor (HDT with each 1 Hz fix) that turns left at
/// `rate` deg/s from t = 10 s to 20 s, a relative bearing (and a true one) half a second
/// after each fix.
fn turning_drive(rate: f64) -> Vec<u8> {
    let frame = LocalFrame::new(
        LatLon {
            lat: 47.0,
            lon: 8.0,
        },
        0.0,
    )
    .expect("frame");
    let heading = |t: f64| 90.0 - rate * (t.clamp(10.0, 20.0) - 10.0);
    let mut p = [0.0f64, 0.0];
    let mut bytes = Vec::new();
    for k in 0..30u32 {
        let t = f64::from(k);
        let h = heading(t);
        let geo = frame.to_geodetic(p).expect("vehicle");
        fix(&mut bytes, k * 1000, geo, 10.0, h);
        hdt(&mut bytes, h);
        pfoxb(&mut bytes, k * 1000 + 500, 10.0, 'R');
        pfoxb(&mut bytes, k * 1000 + 500, h + 10.0, 'T');
        let mid = heading(t + 0.5).to_radians();
        p = [p[0] + 10.0 * mid.sin(), p[1] + 10.0 * mid.cos()];
    }
    bytes
}

#[test]
fn relative_bearings_taken_in_a_fast_turn_are_rejected_by_name() {
    let relative =
        |b: &&BearingMeasurement| b.heading != foxhunt_bridge::bridge::HeadingSource::TrueBearing;
    // 5 deg/s for 10 s: the bearings whose window (the second up to the sample after them)
    // sees the turn are rejected: those at 10.5 s to 19.5 s.
    let (got, rx) = decode(&turning_drive(5.0), BridgeConfig::default());
    let c = rx.counters().1;
    let kept = got.iter().filter(relative).count();
    eprintln!(
        "5 deg/s turn: {kept} relative bearings kept, {} rejected turning",
        c.turning
    );
    assert_eq!((kept, c.turning), (20, 10), "{c:?}");
    // True bearings came turned by the DF unit: not the bridge's heading to gate.
    assert_eq!(got.len() - kept, 30);
    // A gentle 1 deg/s turn passes the default 2 deg/s gate; no gate passes everything.
    let (got, rx) = decode(&turning_drive(1.0), BridgeConfig::default());
    assert_eq!(
        (got.iter().filter(relative).count(), rx.counters().1.turning),
        (30, 0)
    );
    let open = BridgeConfig {
        yaw_gate_deg_s: None,
        ..BridgeConfig::default()
    };
    let (got, rx) = decode(&turning_drive(5.0), open);
    assert_eq!(
        (got.iter().filter(relative).count(), rx.counters().1.turning),
        (30, 0)
    );
    // The rate the bridge measures inside the turn is the turn's.
    let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
    rx.feed(&turning_drive(5.0)[..], &mut |_| {});
    let rate = rx.bridge.yaw_rate_at(36_000_000 + 15_000).expect("a rate");
    // HDT's two decimals: 0.01 deg over 1 s.
    assert!((rate - 5.0).abs() < 0.02, "{rate} deg/s");
}
