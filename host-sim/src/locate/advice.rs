//! The guidance advice as `foxhunt locate` reports it: the move's point and next turn in
//! latitude and longitude, each emitter's verdict and the advice in one line.

use crate::estimate::options::LocateOptions;
use crate::guidance::guide::Guide;
use crate::inputs::capture::Decoded;
use crate::locate::report::{LatLonReport, LocatedAdvice, geodetic};
use foxhunt_core::fix::locate::Source;

/// [`Guide::advise_every`] as `foxhunt locate` reports it.
pub fn located_advice(
    guide: &mut Guide,
    d: &Decoded,
    emitters: &[Source],
    o: &LocateOptions,
) -> Result<LocatedAdvice, String> {
    let frame = d.frame.ok_or("no GPS fix yet")?;
    let g = guide.advise_every(d, emitters, o)?;
    let a = g.advice;
    let ll = |p: [f32; 2]| {
        let g = geodetic(&frame, p);
        LatLonReport {
            lat: g.lat,
            lon: g.lon,
        }
    };
    let target = ll(a.waypoint);
    let line = g.line_to(Some(&format!("{:.5}, {:.5}", target.lat, target.lon)));
    Ok(LocatedAdvice {
        report: a.report(),
        target,
        turn_at: a.turn.map(|t| ll(t.at)),
        emitters: g.emitters,
        for_emitters: g.for_emitters,
        line,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-emitter field condition's capture (240 bearings on each of two channels).
    fn two_emitters() -> Vec<u8> {
        use crate::runs::field::{Condition, capture};
        capture(
            Condition::TwoEmitters,
            0,
            crate::runs::simulate::DEFAULT_ORIGIN,
        )
        .map(|(b, _)| b)
        .unwrap_or_default()
    }

    fn decode(bytes: &[u8]) -> Decoded {
        let mut d =
            crate::inputs::capture::Decoder::new(foxhunt_bridge::BridgeConfig::default(), false);
        d.feed(bytes);
        d.finish()
    }

    /// Every number of an advice is finite, every emitter has a verdict, and the move is for
    /// exactly those not good enough.
    fn check(a: &LocatedAdvice, emitters: usize) -> Result<(), String> {
        let r = &a.report;
        let numbers = [
            r.heading_deg,
            r.waypoint[0],
            r.waypoint[1],
            r.predicted_cep50_m,
        ];
        let verdicts = a
            .emitters
            .iter()
            .flat_map(|v| [v.bound_cep50_m, v.offset_known_cep50_m])
            .chain([r.bound_cep50_m, r.offset_known_cep50_m, r.reached_s])
            .flatten();
        let finite = numbers.into_iter().chain(verdicts).all(f32::is_finite)
            && a.target.lat.is_finite()
            && a.target.lon.is_finite();
        if !finite {
            return Err(format!("a number is not finite: {a:?}"));
        }
        if a.emitters.len() != emitters {
            return Err(format!(
                "{} verdicts for {emitters} emitters",
                a.emitters.len()
            ));
        }
        let short: Vec<usize> = a
            .emitters
            .iter()
            .filter(|v| !v.good_enough)
            .map(|v| v.emitter)
            .collect();
        if emitters > 0 && short != a.for_emitters {
            return Err(format!("move for {:?}, short: {short:?}", a.for_emitters));
        }
        if emitters > 0 && r.good_enough != short.is_empty() {
            return Err(format!(
                "good enough {} with {short:?} short",
                r.good_enough
            ));
        }
        Ok(())
    }

    #[test]
    fn two_emitters_each_get_a_verdict_and_the_move_is_for_the_one_short() {
        let bytes = two_emitters();
        let lines: Vec<&[u8]> = bytes.split_inclusive(|b| *b == b'\n').collect();
        // 200 sentences: 100 bearings, 50 per emitter; emitter 1's CEP50 is then below 100 m
        // and emitter 2's above it (77 m and 137 m in this run).
        let d = decode(&lines[..200].concat());
        let o = LocateOptions::default();
        let mut g = Guide::new(None, 100.0).unwrap();
        let l = crate::locate::locate_guided(&d, &o, &mut g).unwrap();
        let cep: Vec<f32> = l.report.emitters.iter().map(|e| e.cep50_m).collect();
        let a = l.report.advice.expect("advice");
        check(&a, 2).unwrap();
        assert!(cep[0] < 100.0 && cep[1] > 100.0, "{cep:?}");
        assert!(
            a.emitters[0].good_enough && !a.emitters[1].good_enough,
            "{a:?}"
        );
        assert_eq!(a.for_emitters, vec![2]);
        assert!(
            a.line
                .contains(" for emitter 2; emitter 1: good enough; emitter 2: "),
            "{}",
            a.line
        );
        // The move is the one for emitter 2 alone (emitter 1 resolved earns nothing more).
        let alone = g.advise(&d, l.emitters.get(1), &o).unwrap();
        assert_eq!(a.report.heading_deg, alone.report().heading_deg, "{a:?}");
        // The whole drive: both good enough, and the line says so for both.
        let d = decode(&bytes);
        let l = crate::locate::locate_guided(&d, &o, &mut g).unwrap();
        let a = l.report.advice.expect("advice");
        check(&a, 2).unwrap();
        assert!(a.report.good_enough && a.for_emitters.is_empty(), "{a:?}");
        assert_eq!(a.line, "good enough: stop (emitters 1, 2)");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Any prefix of a two-emitter drive, bytes corrupted, any target: advice or a
        /// one-line error, never a panic or a number that is not finite.
        #[test]
        fn any_two_emitter_prefix_advises_soundly(
            cut in 0usize..70_000,
            flips in proptest::collection::vec((0usize..70_000, 1u8..=255), 0..40),
            target in 5.0f32..500.0,
        ) {
            let mut bytes = two_emitters();
            bytes.truncate(cut);
            for (at, x) in flips {
                if let Some(b) = bytes.get_mut(at) {
                    *b ^= x;
                }
            }
            let d = decode(&bytes);
            let mut g = Guide::new(None, target).unwrap();
            let advice = match crate::locate::locate_guided(&d, &LocateOptions::default(), &mut g) {
                Ok(l) => l.report.advice.map(|a| (a, l.report.emitters.len())),
                Err(e) => e.advice.map(|a| (a, 0)),
            };
            if let Some((a, n)) = advice {
                proptest::prop_assert!(check(&a, n).is_ok(), "{:?}", check(&a, n));
                let json = serde_json::to_string(&a).unwrap();
                proptest::prop_assert!(!json.contains("NaN") && !json.contains("inf"), "{}", json);
            }
        }
    }
}
