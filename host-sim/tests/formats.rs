//! simulate -> locate in every DF unit's format: each canonical drive written as PFOXB,
//! Agrelo (with HDT beside it), KrakenSDR CSV and KrakenSDR XML, clean and with wild bearings
//! and corrupt bytes, is located within 3 sigma of its bound (the Mahalanobis distance of the
//! fix from the truth under the bias-aware bound of the bearings that came through: the
//! default fix estimates the DF unit's offset too).

use foxhunt_bridge::bridge::BridgeConfig;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::bias::{BiasPrior, crlb};
use foxhunt_core::linalg::inverse2;
use foxhunt_sim::inputs::capture::decode;
use foxhunt_sim::locate::{LocateOptions, locate};
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::runs::simulate::{CaptureFormat, CaptureOptions, drive_capture};

/// The fix's Mahalanobis distance from the truth, the bearings used, and the frames and
/// bearings rejected.
fn mahalanobis(name: &str, options: CaptureOptions, config: BridgeConfig) -> (f32, usize, u32) {
    let scenario = Scenario::named(name).expect("scenario");
    let s = scenario.drive().expect("a drive");
    let bytes = drive_capture(&scenario, &options).expect("capture");
    let d = decode(&bytes, config, false);
    let report = locate(&d, &LocateOptions::default()).expect("a fix").report;
    let fix = &report.emitters[0];
    // Every format puts its first record at the route's first point, the local origin; when
    // damage costs a Kraken-only capture its first record, the next one is the origin.
    let at_start = [s.emitter[0] - s.route[0][0], s.emitter[1] - s.route[0][1]];
    let emitter = LocalFrame::new(options.origin, 0.0)
        .and_then(|f| f.to_geodetic([f64::from(at_start[0]), f64::from(at_start[1])]))
        .expect("emitter");
    let t = d.frame.expect("a frame").to_local(emitter).expect("truth");
    let truth = [t[0] as f32, t[1] as f32];
    let used = d.bearings_with_sigma(s.sigma());
    let bound = crlb(&truth, &used, BiasPrior::default()).expect("bound");
    let inv = inverse2(&bound.covariance).expect("invertible");
    let e = [fix.east_m - truth[0], fix.north_m - truth[1]];
    let d2 =
        e[0] * (inv[0][0] * e[0] + inv[0][1] * e[1]) + e[1] * (inv[1][0] * e[0] + inv[1][1] * e[1]);
    let (st, br) = (&d.stream, &d.bridge);
    let rejected = st.bad_checksum
        + st.malformed
        + st.truncated
        + st.garbage_bytes
        + br.bad_field
        + br.bad_position
        + br.no_heading
        + br.turning;
    (d2.sqrt(), d.observations.len(), rejected)
}

/// Whether a drive turns faster than the default yaw gate (2 deg/s at a point a second)
/// somewhere other than at a single corner: the heading turns at most of its points.
fn circling(name: &str) -> bool {
    let scenario = Scenario::named(name).expect("scenario");
    let route = &scenario.drive().expect("a drive").route;
    let course: Vec<f32> = route
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).atan2(w[1][1] - w[0][1]).to_degrees())
        .collect();
    let turns = course
        .windows(2)
        .filter(|c| ((c[1] - c[0] + 540.0).rem_euclid(360.0) - 180.0).abs() > 2.0)
        .count();
    2 * turns > course.len()
}

#[test]
fn every_drive_in_every_format_is_located_within_three_sigma_of_its_crlb() {
    let drives: Vec<String> = Scenario::all()
        .into_iter()
        .filter(|s| s.drive().is_some())
        .map(|s| s.name)
        .collect();
    let mut table = Vec::new();
    for format in CaptureFormat::ALL {
        for name in &drives {
            let steps = Scenario::named(name)
                .and_then(|s| s.drive().map(|d| d.route.len()))
                .expect("drive");
            let clean = CaptureOptions {
                format,
                ..CaptureOptions::default()
            };
            // loop300 circles the emitter at 6 degrees a second: the default yaw gate (2 deg/s)
            // rejects every relative bearing of it, as it should in the field; the simulation
            // has no GPS-DF latency, so its bearings in the turn are exact, and these drives
            // are located with the gate open.
            let config = if circling(name) {
                let scenario = Scenario::named(name).expect("scenario");
                let bytes = drive_capture(&scenario, &clean).expect("capture");
                let c = decode(&bytes, BridgeConfig::default(), false).bridge;
                // Relative formats: all but the first bearings (before the heading samples
                // span a window) are rejected as turning; PFOXB's true bearings are not.
                let relative = format != CaptureFormat::Pfoxb;
                assert!(
                    (c.turning as usize + 2 >= steps) == relative,
                    "{name} in {}: {} turning",
                    format.name(),
                    c.turning
                );
                BridgeConfig {
                    yaw_gate_deg_s: None,
                    ..BridgeConfig::default()
                }
            } else {
                BridgeConfig::default()
            };
            let (d, used, _) = mahalanobis(name, clean, config);
            // 1 % of PFOXB's bytes corrupt, about two bytes a bearing; the same number of bytes
            // per bearing in the other formats (a Kraken CSV line is 2.3 KB: 1 % of its bytes
            // would leave no line whole).
            let size = |f: CaptureFormat| {
                let scenario = Scenario::named(name).expect("scenario");
                let o = CaptureOptions { format: f, ..clean };
                drive_capture(&scenario, &o).expect("capture").len() as f32
            };
            let corrupt = 0.01 * size(CaptureFormat::Pfoxb) / size(format);
            // Only PFOXB and NMEA carry a checksum: in the Agrelo and Kraken records a corrupt
            // digit that keeps its field well formed is a wrong value (a latitude kilometres
            // off, a heading turned), which no reader can tell. Their damaged drives get the
            // wild bearings; the corrupt bytes are measured and shown, not asserted.
            let checked = format == CaptureFormat::Pfoxb;
            let damaged = CaptureOptions {
                wild_fraction: Some(0.1),
                corrupt_fraction: if checked { corrupt } else { 0.0 },
                ..clean
            };
            let (rough, _, rejected) = mahalanobis(name, damaged, config);
            let shown = if checked {
                String::new()
            } else {
                let o = CaptureOptions {
                    corrupt_fraction: corrupt,
                    ..damaged
                };
                let scenario = Scenario::named(name).expect("scenario");
                let bytes = drive_capture(&scenario, &o).expect("capture");
                let d = decode(&bytes, config, false);
                match locate(&d, &LocateOptions::default()) {
                    Ok(l) => format!(
                        "; with corrupt bytes too: fix {:.0} m east {:.0} m north",
                        l.report.emitters[0].east_m, l.report.emitters[0].north_m
                    ),
                    Err(e) => format!("; with corrupt bytes too: {e}"),
                }
            };
            table.push(format!(
                "{:10} {name:14} {d:.2} sigma ({used}/{steps} bearings), damaged {rough:.2} sigma{shown}",
                format.name()
            ));
            // 3 sigma of a 2-D Gaussian holds 98.9 % of fixes: one seeded run per case. With
            // 10 % wild bearings the robust fix gives up some efficiency (1.24x the clean rmse
            // on aoa-afsa-wild, issue bar 1.3): its bar is 1.3 times wider, as in roundtrip.rs.
            assert!(d <= 3.0, "{}: {name} {d} sigma", format.name());
            assert!(
                rough <= 3.0 * 1.3,
                "{}: {name} damaged {rough} sigma",
                format.name()
            );
            assert!(
                rejected > 0 || !checked,
                "{}: {name}: damage not counted",
                format.name()
            );
            // The relative formats lose at most the bearings at a corner of the route to
            // the yaw gate (the heading turns 90 degrees between two fixes); loop300 turns
            // 1.2 degrees a second, under the gate.
            assert!(
                used + 2 >= steps,
                "{}: {name}: {used} of {steps}",
                format.name()
            );
        }
    }
    eprintln!("{}", table.join("\n"));
}

#[test]
fn a_20_km_drive_far_north_is_exact_in_every_format() {
    // The convergence the simulation writes in (azimuths from north at the vehicle) and the
    // bridge turns out: a 20 km L at 70 N (10 km east, 10 km north, a bearing every 250 m)
    // with 0.001 degree noise. Uncorrected, north at the far end is 0.25 degrees off the
    // frame's, tens of metres at these ranges.
    let mut points = Vec::new();
    for k in 0..=40 {
        points.push(format!("[{}.0, 0.0]", 250 * k));
    }
    for k in 1..=40 {
        points.push(format!("[10000.0, {}.0]", 250 * k));
    }
    let text = format!(
        "name = \"far-north\"\nemitter = [6000.0, 4000.0]\npoints = [{}]\nbearing_sigma_deg = 0.001\n",
        points.join(", ")
    );
    let scenario = Scenario::from_toml(&text).expect("scenario");
    let truth = [6000.0f32, 4000.0];
    for format in CaptureFormat::ALL {
        let o = CaptureOptions {
            format,
            origin: foxhunt_bridge::nmea::LatLon {
                lat: 70.0,
                lon: 25.0,
            },
            ..CaptureOptions::default()
        };
        let bytes = drive_capture(&scenario, &o).expect("capture");
        let d = decode(&bytes, BridgeConfig::default(), false);
        let bearings: Vec<_> = d.bearings().copied().collect();
        let fit =
            foxhunt_core::estimator::batch_fix(foxhunt_core::Method::Ml, &bearings).expect("fix");
        let off = (fit.position[0] - truth[0]).hypot(fit.position[1] - truth[1]);
        eprintln!(
            "{:10} 20 km at 70 N: {off:.2} m from the truth ({} bearings)",
            format.name(),
            d.observations.len()
        );
        // What is left is each format's rounding: Agrelo's tenths of a degree (0.03 degree
        // sd, 5 m at 10 km per bearing, about 1 m over 80), the others' hundredths or finer.
        assert!(off < 3.0, "{}: {off} m", format.name());
    }
}
