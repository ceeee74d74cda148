//! Why a capture gives no fix, in words a user can act on.

use crate::inputs::capture::Decoded;
use crate::locate::report::RegionReport;
use foxhunt_core::fix::device::WIDEST_CEILING;
use foxhunt_core::fix::locate::motion::Motion;
use foxhunt_core::fix::locate::{ChannelOutcome, NoEmitter, Observation};
use foxhunt_core::model::bearing::wrap;
use foxhunt_core::{Bearing, Error};

/// Why a capture gives no position for the vehicle, in words a user can act on.
pub(crate) fn no_vehicle_position(d: &Decoded) -> String {
    let g = d.gps;
    if g.seen == 0 && d.bearing_records.seen > 0 && d.bridge.no_fix + d.bridge.stale_fix == 0 {
        // Bearings that needed no GPS fix (KrakenSDR records bring their own positions): the
        // first one placed would have set the frame, so none was, and why is their story.
        return no_bearing(d);
    }
    if g.seen == 0
        && let Some(u) = d.unit.report()
    {
        return format!(
            "no fix: the capture holds the DF unit's own sentences but no GPS fix or bearing, \
             and the unit reports no position ({})",
            u.status_text.unwrap_or("no fix sentence")
        );
    }
    if g.seen == 0 {
        let bad = d.stream.bad_checksum + d.stream.malformed;
        return if bad > 0 {
            format!(
                "no GPS fix: no GGA/RMC/GLL/GNS sentence decoded ({bad} sentences failed their \
                 checksum or framing)"
            )
        } else {
            "no GPS fix: the capture holds no GGA/RMC/GLL/GNS sentence, so bearings cannot be \
             placed"
                .into()
        };
    }
    format!(
        "no GPS fix: {} position sentences, {} saying the receiver has no fix, {} with a \
         malformed or out-of-range field",
        g.seen, g.no_fix, g.malformed
    )
}

/// Why a capture with a vehicle track gives no usable bearing.
pub(crate) fn no_bearing(d: &Decoded) -> String {
    let (r, b) = (d.bearing_records, &d.bridge);
    if r.seen == 0 {
        return "no bearing record in the capture (no $PFOXB, Agrelo or KrakenSDR record)".into();
    }
    let mut why = Vec::new();
    let mut reason = |n: u32, text: &str| {
        if n > 0 {
            why.push(format!("{n} {text}"));
        }
    };
    reason(r.malformed, "with a malformed or out-of-range field");
    reason(b.low_quality, "at or below the quality gate");
    reason(b.no_heading, "relative with no heading to turn them by");
    reason(b.no_bearing, "saying the DF unit had no bearing");
    reason(b.no_fix, "before any GPS fix");
    reason(
        b.stale_fix,
        "with no GPS fix within the allowed gap of their time",
    );
    reason(b.late, "older than the GPS fixes kept");
    reason(
        b.turning,
        "taken while the vehicle turned faster than the yaw-rate gate",
    );
    reason(
        b.time_jump,
        "whose time jumped away from the records around them (a corrupt time)",
    );
    format!(
        "no usable bearing: of {} bearing records, {}",
        r.seen,
        if why.is_empty() {
            "none reached the bridge".into()
        } else {
            why.join(", ")
        }
    )
}

/// How far the bearings' lines turn over the drive, degrees: the spread (5th to 95th
/// percentile) of their directions as undirected lines, so a few wild ones do not count. A
/// distant emitter's lines hardly turn; nearly parallel lines cross anywhere noise puts them.
fn turn_deg(bearings: &[Bearing]) -> f32 {
    let Some(first) = bearings.first() else {
        return 0.0;
    };
    let half = core::f32::consts::FRAC_PI_2;
    let mut d: Vec<f32> = bearings
        .iter()
        .map(|b| {
            let x = (b.theta - first.theta).rem_euclid(2.0 * half);
            if x > half { x - 2.0 * half } else { x }
        })
        .collect();
    d.sort_by(f32::total_cmp);
    let at = |q: f32| d[((d.len() - 1) as f32 * q).round() as usize];
    (at(0.95) - at(0.05)).to_degrees()
}

/// The bearings' typical noise, degrees (the median of their sigmas).
fn noise_deg(bearings: &[Bearing]) -> f32 {
    let mut s: Vec<f32> = bearings.iter().map(|b| b.sigma).collect();
    s.sort_by(f32::total_cmp);
    s.get(s.len() / 2).map_or(1.0, |x| x.to_degrees())
}

/// Whether nearly all of at least five bearings point away from where their lines cross (the
/// pseudo-linear fix, which treats a bearing as an undirected line): the sign of a reversed or
/// mirrored DF convention. Fewer, a mixed picture, or lines that turn too little for their
/// crossing to mean anything (a distant emitter: noise puts it behind as often as ahead) is a
/// geometry problem instead.
pub(crate) fn points_away(bearings: &[Bearing]) -> bool {
    if turn_deg(bearings) < 10.0 * noise_deg(bearings).max(1.0) {
        return false;
    }
    let Ok(f) = foxhunt_core::fix::ple::ple(bearings) else {
        return false;
    };
    let away = bearings
        .iter()
        .filter(|b| b.residual(&f.position).cos() < 0.0)
        .count();
    bearings.len() >= 5 && 10 * away >= 9 * bearings.len()
}

/// Why the bearings give no fix, in words a user can act on.
pub fn explain(e: Error, bearings: &[Bearing]) -> String {
    match e {
        Error::TooFewMeasurements if bearings.len() == 1 => {
            "only one usable bearing: a fix needs at least two bearings from different places"
                .into()
        }
        Error::TooFewMeasurements => "too few usable bearings for a fix".into(),
        Error::StationaryVehicle => {
            "the vehicle never moved: bearings from one place give a direction, not a position"
                .into()
        }
        // Before "parallel": mirrored bearings of a good drive leave a likelihood region that
        // runs out of range (the fit finds no side of the vehicle to settle on).
        _ if points_away(bearings) => "the bearings point away from where their lines cross \
             (they meet behind the vehicle): is the DF unit's angle convention reversed (180 \
             degrees) or mirrored?"
            .into(),
        Error::ParallelBearings if turn_deg(bearings) > 0.01 => format!(
            "the bearings turn by only {:.1} degrees over the drive against {:.1} degrees of \
             noise: the emitter may lie anywhere along the line of bearing out to the search's \
             edge (a distant emitter, or bearings too noisy), so its range is unknown; drive \
             across the line of bearing, or closer",
            turn_deg(bearings),
            noise_deg(bearings)
        ),
        Error::ParallelBearings => "all bearings are parallel: they never cross, so the range is \
             unknown; drive across the line of bearing"
            .into(),
        Error::ShallowCrossing => {
            "the bearings cross too shallowly for a fix; drive further across the line of bearing"
                .into()
        }
        Error::DegenerateGeometry => "the bearings do not pin down a point (their information is \
             singular); drive across the line of bearing"
            .into(),
        Error::BehindVehicle => "the bearings meet behind the vehicle: no emitter there".into(),
        Error::NotConverged => "the method did not settle on a point the bearings agree on (its \
             estimate lies outside their own 95 % likelihood region, or no crossing most of \
             them meet at was found); ml-robust fits them directly"
            .into(),
        e => format!("no fix: {e}"),
    }
}

/// A distance in words: metres below a kilometre, else kilometres.
pub fn distance_words(m: f32) -> String {
    if m < 1000.0 {
        format!("{m:.0} m")
    } else {
        format!("{:.1} km", m / 1000.0)
    }
}

/// The range interval of a region in words: `1.2 km to unbounded`, `300 m to 2.5 km`.
pub fn range_words(r: &RegionReport) -> String {
    let to = r
        .max_range_m
        .map_or_else(|| "unbounded".to_string(), distance_words);
    format!("{} to {to}", distance_words(r.min_range_m))
}

/// Why a channel with a region has no fix, in words: "parallel" only when the bearings are.
pub fn open_range(r: &RegionReport) -> String {
    if r.parallel {
        format!(
            "all bearings are parallel: they never cross, so the range is unknown (bearing \
             {:.1} deg +- {:.1} deg, range {}); drive across the line of bearing",
            r.bearing_deg,
            r.half_width_deg,
            range_words(r)
        )
    } else {
        format!(
            "the range is open: the bearings hold a line of bearing, {:.1} deg +- {:.1} deg, \
             and a range of {}, not a fix; drive across the line of bearing",
            r.bearing_deg,
            r.half_width_deg,
            range_words(r)
        )
    }
}

/// Why a channel of `n` bearings has no consistent emitter, in words (`max_sigma`: the noise,
/// radians, above which the pipeline calls bearings too scattered).
pub(crate) fn no_emitter(why: NoEmitter, n: u32, bearings: &[Bearing], max_sigma: f32) -> String {
    match why {
        NoEmitter::TooFew if n <= 1 => {
            explain(Error::TooFewMeasurements, bearings.get(..1).unwrap_or(&[]))
        }
        NoEmitter::NoConsensus => "no consistent emitter: no point has more bearings agreeing \
             than chance would give (noise, or bearings of nothing)"
            .into(),
        NoEmitter::TooNoisy => format!(
            "no consistent emitter: the bearings scatter by more than {:.0} degrees about any \
             point",
            max_sigma.to_degrees()
        ),
        NoEmitter::TooFew => format!(
            "no consistent emitter: {n} bearings are too few to estimate their noise and check \
             the fit (at least 5 that cross well)"
        ),
        NoEmitter::Geometry(e) => format!("no consistent emitter: {}", explain(e, bearings)),
        NoEmitter::OffsetBeyondPrior(b) => offset_beyond(&b),
        NoEmitter::Moving(m) => moving(&m),
    }
}

/// How much a channel's bearings change from one to the next ([`step_deg`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Steps {
    /// The robust sd of a step over root 2, degrees: the bearings' noise, if noise is all.
    pub deg: f32,
    /// The steps it was taken from.
    pub pairs: usize,
}

impl Steps {
    /// Whether these steps are too small for noise that scatters by more than `max_deg`: the
    /// median of n steps of Gaussian noise has a relative sd of about 1.17 / root n (the
    /// sample median of |N(0, 2 sd^2)|), so a step under 1 - 3.5 / root n of the ceiling is
    /// three sds below the least noise that scatters beyond it; and under a third of it
    /// whatever n (a step that small was noise in none of the field captures, measured).
    pub fn steady(&self, max_deg: f32) -> bool {
        let below = 1.0 - 3.5 / (self.pairs as f32).sqrt();
        self.deg < max_deg * below.max(1.0 / 3.0)
    }

    /// Whether these steps are too large for noise within `max_deg`: three sds of their
    /// median above it (the mirror of [`Steps::steady`]), so that the bearings' own noise, not
    /// only their scatter about a point, passes the ceiling.
    pub fn beyond(&self, max_deg: f32) -> bool {
        self.deg > max_deg * (1.0 + 3.5 / (self.pairs as f32).sqrt())
    }
}

/// How much a station's bearing changes from one to the next: the robust sd of the steps
/// between its consecutive bearings (at most [`STEP_GAP_S`] apart) over root 2, pooled over
/// the stations of `observations` (one channel's, any order); `None` below [`STEADY_PAIRS`]
/// such pairs. Noise makes each step about root 2 of its sd; bearings that follow something
/// which changes smoothly (an emitter that moves, an error that turns with the vehicle) step
/// by far less than they scatter about any one point.
pub(crate) fn step_deg(observations: &[Observation]) -> Option<Steps> {
    let mut seen: Vec<&Observation> = observations.iter().collect();
    seen.sort_by(|a, b| {
        a.station
            .cmp(&b.station)
            .then(a.time_s.total_cmp(&b.time_s))
    });
    let mut steps: Vec<f32> = seen
        .windows(2)
        .filter(|p| p[0].station == p[1].station && p[1].time_s - p[0].time_s <= STEP_GAP_S)
        .map(|p| wrap(p[1].bearing.theta - p[0].bearing.theta).abs())
        .collect();
    if steps.len() < STEADY_PAIRS {
        return None;
    }
    steps.sort_by(f32::total_cmp);
    let median = steps[steps.len() / 2];
    // The median absolute step of Gaussian noise is 0.674 of the steps' sd, root 2 of the
    // bearings'.
    Some(Steps {
        deg: (median / 0.6745 / core::f32::consts::SQRT_2).to_degrees(),
        pairs: steps.len(),
    })
}

/// Consecutive bearings of a station at most this far apart, seconds, count as a step.
const STEP_GAP_S: f32 = 5.0;

/// Steps needed before [`step_deg`] says anything.
const STEADY_PAIRS: usize = 20;

/// What a channel with no consistent emitter, heard by `stations` DF stations, whose bearings
/// step by `step` (its [`step_deg`]) adds to `why` (the bearings scatter, agree on nothing, or
/// pin no point): bearings whose steps are too small for noise beyond the ceiling `max_sigma`
/// (radians; [`Steps::steady`]) follow something, not noise; bearings too scattered whose own
/// steps pass that ceiling but not the widest class's ([`Steps::beyond`]) are as noisy as a
/// Yagi's or an indoor array's, and the user is told how to say so. One station's offset beyond its
/// prior may be an emitter that moves: one station's bearings on a drone circling 500 m away
/// fit a still point with a 15 or 60 degree offset (`move-vehicle-turning` run 1), and nothing
/// in them tells the two apart. Nothing for the other reasons.
pub(crate) fn steady_clause(
    why: NoEmitter,
    step: Option<Steps>,
    stations: usize,
    max_sigma: f32,
) -> String {
    let spread = matches!(
        why,
        NoEmitter::TooNoisy | NoEmitter::NoConsensus | NoEmitter::Geometry(_)
    );
    let track = match stations {
        1 => "one station cannot place it; with a second, `foxhunt track` follows it",
        _ => "`foxhunt track` follows it",
    };
    match step {
        Some(s) if spread && s.steady(max_sigma.to_degrees()) => format!(
            "; yet each bearing differs from its station's one before by only about {:.1} \
             degrees: they follow something that changes, not noise: an emitter that moves \
             ({track}), or an error that changes with the vehicle's heading or place \
             (multipath, a direction-dependent error)",
            s.deg
        ),
        Some(s)
            if matches!(why, NoEmitter::TooNoisy)
                && max_sigma < WIDEST_CEILING
                && s.beyond(max_sigma.to_degrees())
                && !s.beyond(WIDEST_CEILING.to_degrees()) =>
        {
            format!(
                "; each bearing differs from its station's one before by about {:.1} degrees: \
                 noise beyond the {:.0} of this class of DF unit, as a hand-turned Yagi's (up \
                 to 20) or an indoor angle-of-arrival array's (10-16); if the stations are such, \
                 say so (`antenna = \"yagi\"` or `\"indoor-aoa\"` in a `--stations` file); \
                 `foxhunt track` takes stations this noisy as indoor arrays unasked",
                s.deg,
                max_sigma.to_degrees()
            )
        }
        _ if matches!(why, NoEmitter::OffsetBeyondPrior(_)) && stations == 1 => {
            "; or the emitter moves: one station's bearings on an emitter that moves can fit a \
             still one with a large offset (a second station tells them apart)"
                .into()
        }
        _ => String::new(),
    }
}

/// The reason code of an emitter that moves ([`reason_code`]).
pub const MOVING: &str = "moving";

/// Why a channel has no emitter, as the `--json` reports' code (`None` for an emitter).
pub fn reason_code(outcome: ChannelOutcome) -> Option<&'static str> {
    Some(match outcome {
        ChannelOutcome::Emitter(_) => return None,
        ChannelOutcome::Region(_) => "open_range",
        ChannelOutcome::NoConsistentEmitter(why) => match why {
            NoEmitter::Moving(_) => MOVING,
            NoEmitter::NoConsensus => "no_consensus",
            NoEmitter::TooNoisy => "too_noisy",
            NoEmitter::TooFew => "too_few",
            NoEmitter::Geometry(_) => "geometry",
            NoEmitter::OffsetBeyondPrior(_) => "offset_beyond_prior",
        },
    })
}

/// [`NoEmitter::Moving`] in words: what the check saw, and where to go instead.
pub(crate) fn moving(m: &Motion) -> String {
    let p = if m.p_value < 1e-6 {
        "p < 1e-6".to_string()
    } else {
        format!("p = {:.1e}", m.p_value)
    };
    format!(
        "the emitter moves: use `foxhunt track` (the early bearings, {:.0}-{:.0} s, \
         meet {} from the late ones, {:.0}-{:.0} s: {:.0} sd apart, their noise and the \
         stations' offsets counted; an emitter that stands still does that with {p})",
        m.early.time_span[0],
        m.early.time_span[1],
        distance_words(m.apart_m),
        m.late.time_span[0],
        m.late.time_span[1],
        m.apart_sd,
    )
}

/// [`NoEmitter::OffsetBeyondPrior`] in words (degrees as the reports give offsets).
pub(crate) fn offset_beyond(b: &foxhunt_core::fix::locate::OffsetBeyond) -> String {
    let or = b
        .second
        .map(|s| {
            format!(
                " or {:.0} deg (the drive cannot tell which)",
                s.to_degrees()
            )
        })
        .unwrap_or_default();
    format!(
        "no consistent emitter: the DF unit's offset is about {:.0} deg{or}, {:.0} sds beyond \
         its prior ({:.0} +- {:.0} deg): check the antenna (mounting, array indexing, cables), \
         then calibrate",
        b.offset.to_degrees(),
        b.z.abs(),
        b.prior.mean.to_degrees(),
        b.prior.sd.to_degrees()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_core::Bearing;

    fn at(station: u16, t: f32, theta: f32) -> Observation {
        Observation {
            bearing: Bearing {
                vehicle: [0.0, 0.0],
                theta,
                sigma: 0.035,
            },
            time_s: t,
            freq_mhz: None,
            station,
            stamped: true,
        }
    }

    #[test]
    fn steps_read_noise_as_noise_and_a_sweep_as_steady() {
        // Two stations interleaved, 2 degrees of noise on bearings that sweep 40 degrees: the
        // steps give the noise back (within a tenth: 200 steps' median), not the sweep.
        let mut x = 0x2545_f491u32;
        let mut normal = || {
            // A sum of twelve uniforms less six: close enough to a normal draw here.
            (0..12)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    x as f32 / u32::MAX as f32
                })
                .sum::<f32>()
                - 6.0
        };
        let obs: Vec<Observation> = (0..200)
            .map(|k| {
                let sweep = (40.0f32 * k as f32 / 200.0).to_radians();
                at(
                    (k % 2) as u16,
                    k as f32,
                    sweep + 2f32.to_radians() * normal(),
                )
            })
            .collect();
        let s = step_deg(&obs).expect("enough steps");
        assert!((s.deg - 2.0).abs() < 0.2 * 2.0 + 0.2, "{s:?}");
        assert_eq!(s.pairs, 198);
        // Uniform bearings step by about a third of the circle: far past any ceiling.
        let wild: Vec<Observation> = (0..100)
            .map(|k| at(0, k as f32, std::f32::consts::PI * normal() / 2.0))
            .collect();
        assert!(step_deg(&wild).expect("steps").deg > 30.0);
        // Steps more than five seconds apart, or too few, say nothing.
        let sparse: Vec<Observation> = (0..100).map(|k| at(0, 10.0 * k as f32, 0.0)).collect();
        assert_eq!(step_deg(&sparse), None);
        assert_eq!(step_deg(&obs[..20]), None);
    }

    #[test]
    fn the_clause_speaks_only_for_steady_bearings_that_meet_nowhere() {
        let ceiling = 10f32.to_radians();
        let steps = |deg: f32, pairs: usize| Some(Steps { deg, pairs });
        let one = steady_clause(NoEmitter::TooNoisy, steps(3.0, 20), 1, ceiling);
        assert!(one.contains("moves (one station cannot place it"), "{one}");
        let three = steady_clause(NoEmitter::NoConsensus, steps(3.0, 20), 3, ceiling);
        assert!(
            three.contains("moves (`foxhunt track` follows it)"),
            "{three}"
        );
        // Twenty steps: a third of the ceiling at most (their median's sd is a quarter of it).
        assert_eq!(
            steady_clause(NoEmitter::TooNoisy, steps(3.5, 20), 1, ceiling),
            ""
        );
        // 600 steps of noise beyond 10 degrees would not read under 8.57 (three sds).
        let many = steady_clause(NoEmitter::TooNoisy, steps(3.5, 600), 1, ceiling);
        assert!(many.contains("only about 3.5 degrees"), "{many}");
        assert!(steps(8.5, 600).is_some_and(|s| s.steady(10.0)));
        assert!(!steps(8.6, 600).is_some_and(|s| s.steady(10.0)));
        assert_eq!(
            steady_clause(NoEmitter::TooNoisy, steps(7.0, 100), 1, ceiling),
            ""
        );
        assert_eq!(steady_clause(NoEmitter::TooNoisy, None, 1, ceiling), "");
        assert_eq!(
            steady_clause(NoEmitter::TooFew, steps(1.0, 20), 1, ceiling),
            ""
        );
        let beyond = NoEmitter::OffsetBeyondPrior(foxhunt_core::fix::locate::OffsetBeyond {
            station: 0,
            offset: -0.26,
            second: None,
            prior: foxhunt_core::fix::bias::BiasPrior { mean: 0.0, sd: 0.1 },
            z: 4.0,
        });
        // Noise itself past the ceiling (12 degrees over 600 steps, the bar 11.4), yet within
        // an indoor array's: the arrays' class is named; not at 11 degrees, nor at 30, nor for
        // a class whose ceiling is already the widest (there 12 degrees is steady).
        let arrays = steady_clause(NoEmitter::TooNoisy, steps(12.0, 600), 4, ceiling);
        assert!(arrays.contains("by about 12.0 degrees"), "{arrays}");
        assert!(
            arrays.contains("`\"indoor-aoa\"` in a `--stations` file"),
            "{arrays}"
        );
        for (deg, max) in [(11.0, ceiling), (30.0, ceiling), (12.0, WIDEST_CEILING)] {
            let clause = steady_clause(NoEmitter::TooNoisy, steps(deg, 600), 4, max);
            assert!(!clause.contains("indoor-aoa"), "{deg} at {max}: {clause}");
        }
        let alone = steady_clause(beyond, steps(3.0, 20), 1, ceiling);
        assert!(alone.contains("or the emitter moves"), "{alone}");
        assert_eq!(steady_clause(beyond, steps(3.0, 20), 3, ceiling), "");
    }
}
