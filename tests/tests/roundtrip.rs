//! simulate -> locate, end to end through the bytes: every canonical drive, clean and with
//! 10 % wild bearings plus 1 % corrupted bytes, is located within 3 sigma of its bound (the
//! bias-aware one: the default fix estimates the DF unit's offset too).

use foxhunt_core::fix::bias::{BiasPrior, crlb};
use foxhunt_core::linalg::inverse2;
use foxhunt_sim::inputs::capture::decode;
use foxhunt_sim::locate::{LocateOptions, locate};
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::runs::simulate::{CaptureOptions, drive_capture};

fn mahalanobis(name: &str, options: CaptureOptions) -> (f32, u32) {
    let scenario = Scenario::named(name).expect("scenario");
    let s = scenario.drive().expect("a drive");
    let bytes = drive_capture(&scenario, &options).expect("capture");
    let d = decode(&bytes, Default::default(), false);
    let report = locate(&d, &LocateOptions::default()).expect("a fix").report;
    let fix = &report.emitters[0];
    let truth = [s.emitter[0] - s.route[0][0], s.emitter[1] - s.route[0][1]];
    // The bound of the bearings that came through, at the true emitter and the true noise,
    // with the offset unknown under the default prior.
    let used = d.bearings_with_sigma(s.sigma());
    let bound = crlb(&truth, &used, BiasPrior::default()).expect("bound");
    let inv = inverse2(&bound.covariance).expect("invertible");
    let e = [fix.east_m - truth[0], fix.north_m - truth[1]];
    let d2 =
        e[0] * (inv[0][0] * e[0] + inv[0][1] * e[1]) + e[1] * (inv[1][0] * e[0] + inv[1][1] * e[1]);
    let rejected: u32 = report.rejected.values().sum();
    (d2.sqrt(), rejected)
}

#[test]
fn every_canonical_drive_is_located_within_three_sigma_of_its_crlb() {
    let drives = Scenario::all().into_iter().filter(|s| s.drive().is_some());
    for name in drives.map(|s| s.name) {
        let name = name.as_str();
        let (clean, _) = mahalanobis(name, CaptureOptions::default());
        let damaged = CaptureOptions {
            wild_fraction: Some(0.1),
            corrupt_fraction: 0.01,
            ..CaptureOptions::default()
        };
        let (rough, rejected) = mahalanobis(name, damaged);
        eprintln!(
            "{name}: {clean:.2} sigma clean, {rough:.2} sigma with wild bearings and corrupt bytes"
        );
        // 3 sigma of a 2-D Gaussian holds 98.9 % of fixes: one run per case, seeded. With 10 %
        // wild bearings the robust fix gives up some efficiency (its rmse is 1.24x the clean
        // one on aoa-afsa-wild, issue bar 1.3), so its ellipse is 1.3 times the bound's.
        assert!(clean <= 3.0, "{name}: {clean} sigma");
        assert!(rough <= 3.0 * 1.3, "{name} damaged: {rough} sigma");
        assert!(rejected > 0, "{name}: the damage was not counted");
    }
}

#[test]
fn the_reported_ellipse_is_honest_over_many_drives() {
    // 100 captures of aoa-drive (the weak, long-range geometry), each located with the
    // default method and the noise estimated from its own residuals.
    let scenario = Scenario::named("aoa-drive").expect("scenario");
    let s = scenario.drive().expect("a drive");
    let truth = [s.emitter[0] - s.route[0][0], s.emitter[1] - s.route[0][1]];
    let runs = 100;
    let mut inside = 0;
    for run in 0..runs {
        let bytes = drive_capture(
            &scenario,
            &CaptureOptions {
                run,
                ..CaptureOptions::default()
            },
        )
        .expect("capture");
        let d = decode(&bytes, Default::default(), false);
        let l = locate(&d, &LocateOptions::default()).expect("a fix");
        let drawn = &l.drawn[0];
        inside += drawn.ellipse.contains(&drawn.position, &truth) as u32;
    }
    eprintln!("95 % ellipse holds the emitter in {inside} of {runs}");
    // Binomial standard error at 95 % over 100 runs is 2.2 %: 88 is 3 of them below; an
    // ellipse that held the truth every time would be too wide to be honest either.
    assert!((88..100).contains(&inside), "{inside} of {runs}");
}

#[test]
fn indoor_capture_is_tracked_through_the_bytes() {
    use foxhunt_sim::runs::simulate::indoor_capture;
    use foxhunt_sim::track::{capture::measure, tracks::tracks};
    let (bytes, anchors, truth) = indoor_capture("rssi-sim", 0).expect("capture");
    let m = measure(&bytes, Some(&anchors));
    assert_eq!(m.unknown.0, 0);
    let options = foxhunt_sim::commands::track::default_options().expect("options");
    let t = tracks(&m, Some(&anchors), &options).expect("track");
    let points = &t.tracks[0].points;
    assert_eq!(points.len(), truth.len());
    let mean: f32 = points
        .iter()
        .zip(&truth)
        .map(|(p, x)| (p.position[0] - x[0]).hypot(p.position[1] - x[1]))
        .sum::<f32>()
        / truth.len() as f32;
    eprintln!("rssi-sim through the bytes: mean error {mean:.2} m");
    // The tracker's rmse over 20 rssi-sim runs is 0.70 m (docs/src/tracking.md), its start
    // unknown (anywhere in the room) and RSSI quantised to the link quality's 0.42 dB: a mean
    // of 1 m leaves room for one run's spread, and is still 10x better than the room's size.
    assert!(mean < 1.0, "mean error {mean} m");
}

#[test]
fn the_bundled_captures_are_what_simulate_writes_today() {
    // serial-bridge/captures holds `foxhunt simulate --scenario aoa-drive --out
    // serial-bridge/captures/aoa-drive.nmea` and `foxhunt simulate --scenario rssi-sim --out
    // serial-bridge/captures/rssi-sim.znp --force` (the book's commands): regenerate them
    // with those when the simulation changes.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures");
    let read = |f: &str| std::fs::read(dir.join(f)).expect("bundled capture");
    let drive = Scenario::named("aoa-drive").expect("scenario");
    let written = drive_capture(&drive, &CaptureOptions::default()).expect("capture");
    assert!(written == read("aoa-drive.nmea"), "aoa-drive.nmea is stale");
    let (bytes, anchors, _) =
        foxhunt_sim::runs::simulate::indoor_capture("rssi-sim", 0).expect("capture");
    assert!(bytes == read("rssi-sim.znp"), "rssi-sim.znp is stale");
    let text = anchors.to_toml("rssi-sim").expect("toml");
    assert_eq!(
        text.as_bytes(),
        read("rssi-sim.anchors.toml").as_slice(),
        "rssi-sim.anchors.toml is stale"
    );
}
