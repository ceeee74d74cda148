//! Field conditions as bearing sets: what real DF drives do to a fix (FIELD.md), simulated so
//! the default `locate` pipeline can be measured on them over seeded Monte Carlo runs.
//!
//! Each [`Condition`] makes the observations of one run (bearings with time, source and
//! frequency, as a DF unit and the bridge deliver them) and the truth they were made from;
//! [`measure`] runs [`foxhunt_core::fix::locate::locate`] on `runs` of them in parallel and
//! counts what a user would care about: whether an emitter was reported, whether its ellipse
//! holds the truth, how far off it is against the bias-aware bound, whether a ghost came out
//! as another source.
//!
//! The drives (chosen; the canonical routes of SCENARIOS.md where one fits):
//! - `u-drive`: 9 km, 240 bearings (one per 37.5 m at 10 m/s), a U round an emitter at
//!   (0, 1500): east along y = 0 from x = -1500, north along x = 1500, west along y = 3000.
//!   Its bearings span more than 180 degrees, so a mounting offset is observable.
//! - `L600` (SCENARIOS.md), with the emitter at 1.4 km (aoa-drive) or 10 km.
//! - `long`: a 20 km L (10 km east, 10 km north, 400 bearings) placed at 47 or 70 degrees
//!   north and simulated on the WGS-84 ellipsoid: each bearing is the true azimuth at the
//!   vehicle plus noise, turned into the local frame of the drive's start by the meridian
//!   convergence (what the bridge does; `uncorrected` leaves it out, as it did before).

use crate::report::Row;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::bias::{self, BiasPrior};
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, Observation, Report, Source};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::random;
use foxhunt_core::{Error, Method};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;
use std::f32::consts::PI;

const DEG: f32 = PI / 180.0;

/// Channels a field report holds at most (the host pipeline's).
pub const CHANNELS: usize = 16;
/// Other sources a field report holds at most.
pub const OTHERS: usize = 16;

/// A simulated field condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Condition {
    /// The U drive with a 2 degree mounting offset.
    Bias2,
    /// The U drive with a 4 degree mounting offset.
    Bias4,
    /// aoa-drive (L600) with a 4 degree offset: the drive cannot see it, the prior governs.
    Bias4Short,
    /// The U drive, a contiguous quarter of it seeing a reflection 950 m from the emitter.
    Multipath,
    /// Two emitters 1 km apart on 145.000 and 146.520 MHz, bearings alternating.
    TwoEmitters,
    /// The U drive at 20 m/s with a DF reporting 5 times a second the running mean of its
    /// last 10 raw bearings (6 degrees each): errors correlated over 2 s.
    Correlated,
    /// The U drive's 240 bearings, every one uniformly random.
    PureNoise,
    /// 3 to 10 bearings spread along the U drive (run r has 3 + r % 8), noise 3 degrees while
    /// the unit claims 2: only the estimated noise is honest.
    FewBearings,
    /// L600 with the emitter 10 km away, 1.117 degree noise.
    Distant,
    /// The 20 km L at 47 degrees north.
    Long47,
    /// The 20 km L at 70 degrees north.
    Long70,
    /// The 20 km L at 70 degrees north without the meridian convergence turned out.
    Long70Uncorrected,
    /// aoa-drive's L600 with 2 degree noise and 15 % wild bearings.
    Wild15,
    /// The canonical aoa-afsa-wild (loop300, 10 % wild, 1.117 degrees).
    AoaAfsaWild,
    /// The canonical aoa-afsa (loop300, clean).
    AoaAfsa,
    /// The canonical aoa-drive (L600, clean).
    AoaDrive,
}

impl Condition {
    /// Every condition, in report order.
    pub const ALL: [Condition; 16] = [
        Condition::Bias2,
        Condition::Bias4,
        Condition::Bias4Short,
        Condition::Multipath,
        Condition::TwoEmitters,
        Condition::Correlated,
        Condition::PureNoise,
        Condition::FewBearings,
        Condition::Distant,
        Condition::Long47,
        Condition::Long70,
        Condition::Long70Uncorrected,
        Condition::Wild15,
        Condition::AoaAfsaWild,
        Condition::AoaAfsa,
        Condition::AoaDrive,
    ];

    /// The name printed in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Condition::Bias2 => "bias-2deg",
            Condition::Bias4 => "bias-4deg",
            Condition::Bias4Short => "bias-4deg-L600",
            Condition::Multipath => "multipath",
            Condition::TwoEmitters => "two-emitters",
            Condition::Correlated => "correlated-5hz",
            Condition::PureNoise => "pure-noise",
            Condition::FewBearings => "few-bearings",
            Condition::Distant => "distant-10km",
            Condition::Long47 => "long-20km-47n",
            Condition::Long70 => "long-20km-70n",
            Condition::Long70Uncorrected => "long-20km-70n-uncorrected",
            Condition::Wild15 => "wild-15pct-2deg",
            Condition::AoaAfsaWild => "aoa-afsa-wild",
            Condition::AoaAfsa => "aoa-afsa",
            Condition::AoaDrive => "aoa-drive",
        }
    }
}

/// One emitter of a simulated drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Position, local metres.
    pub position: [f32; 2],
    /// Its frequency, MHz, if the unit reports one.
    pub freq_mhz: Option<f32>,
}

/// The observations of one run and what made them.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDrive {
    /// The observations, in time order.
    pub observations: Vec<Observation>,
    /// The emitters (none for pure noise).
    pub emitters: Vec<Truth>,
    /// A reflection some bearings see, if any.
    pub ghost: Option<[f32; 2]>,
    /// The unit's true mounting offset, radians.
    pub bias: f32,
    /// The true bearing noise, radians (the sd of a reported bearing's error).
    pub sigma: f32,
}

/// The seeded generator of run `run` of a condition (independent streams per condition).
pub fn rng(condition: Condition, run: usize) -> XorShiftRng {
    let salt = Condition::ALL
        .iter()
        .position(|c| *c == condition)
        .unwrap_or(0) as u64;
    XorShiftRng::seed_from_u64(
        (salt + 1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(run as u64),
    )
}

/// The U drive: `n` vehicle positions, 9 km round (0, 1500).
pub fn u_route(n: usize) -> Vec<[f32; 2]> {
    (0..n)
        .map(|k| {
            let s = 9000.0 * k as f32 / n as f32;
            if s < 3000.0 {
                [-1500.0 + s, 0.0]
            } else if s < 6000.0 {
                [1500.0, s - 3000.0]
            } else {
                [1500.0 - (s - 6000.0), 3000.0]
            }
        })
        .collect()
}

/// SCENARIOS.md's L600.
pub fn l600() -> Vec<[f32; 2]> {
    crate::scenario::route("L600", [0.0, 0.0]).unwrap_or_default()
}

fn bearing_to(target: [f32; 2], v: [f32; 2], error: f32, stated: f32) -> Bearing {
    Bearing {
        vehicle: v,
        theta: wrap(predicted(&target, &v) + error),
        sigma: stated,
    }
}

/// Observations at 1 s spacing from bearings.
fn timed(bearings: impl IntoIterator<Item = Bearing>, dt: f32) -> Vec<Observation> {
    bearings
        .into_iter()
        .enumerate()
        .map(|(k, b)| Observation::new(b, k as f32 * dt))
        .collect()
}

const U_EMITTER: [f32; 2] = [0.0, 1500.0];

/// A drive past one emitter: `sigma` noise (stated as `stated`), offset `bias`, a share
/// `wild` of uniform bearings.
fn simple(
    route: &[[f32; 2]],
    e: [f32; 2],
    sigma: f32,
    stated: f32,
    bias: f32,
    wild: f32,
    rng: &mut XorShiftRng,
) -> FieldDrive {
    let bearings = route.iter().map(|v| {
        if random::uniform(rng) < wild {
            Bearing {
                vehicle: *v,
                theta: random::uniform_in(rng, -PI, PI),
                sigma: stated,
            }
        } else {
            bearing_to(e, *v, bias + sigma * random::normal(rng), stated)
        }
    });
    FieldDrive {
        observations: timed(bearings.collect::<Vec<_>>(), 1.0),
        emitters: vec![Truth {
            position: e,
            freq_mhz: None,
        }],
        ghost: None,
        bias,
        sigma,
    }
}

/// The 20 km L at `lat`, on the ellipsoid; `turned`: the convergence turned out.
fn long_drive(lat: f64, turned: bool, rng: &mut XorShiftRng) -> FieldDrive {
    let origin = LatLon { lat, lon: 10.0 };
    let sigma = 2.0 * DEG;
    let Ok(frame) = LocalFrame::new(origin, 0.0) else {
        return FieldDrive {
            observations: Vec::new(),
            emitters: Vec::new(),
            ghost: None,
            bias: 0.0,
            sigma,
        };
    };
    let e = [6000.0f64, 4000.0];
    let emitter = frame.to_geodetic(e).unwrap_or(origin);
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
    let bearings: Vec<Bearing> = route
        .iter()
        .filter_map(|&v| {
            let here = frame.to_geodetic(v).ok()?;
            // The true azimuth at the vehicle: the emitter in the vehicle's own tangent plane.
            let local = LocalFrame::new(here, 0.0).ok()?;
            let t = local.to_local(emitter).ok()?;
            let azimuth = t[0].atan2(t[1]) as f32 + sigma * random::normal(rng);
            // The vehicle's north in the drive's frame: the convergence of the meridians.
            let north = local.to_geodetic([0.0, 100.0]).ok()?;
            let n = frame.to_local(north).ok()?;
            let convergence = if turned {
                ((n[0] - v[0]).atan2(n[1] - v[1])) as f32
            } else {
                0.0
            };
            Some(Bearing {
                vehicle: [v[0] as f32, v[1] as f32],
                theta: wrap(PI / 2.0 - (azimuth + convergence)),
                sigma,
            })
        })
        .collect();
    FieldDrive {
        observations: timed(bearings, 5.0),
        emitters: vec![Truth {
            position: [e[0] as f32, e[1] as f32],
            freq_mhz: None,
        }],
        ghost: None,
        bias: 0.0,
        sigma,
    }
}

/// The observations of run `run` of `condition`.
pub fn simulate(condition: Condition, run: usize) -> FieldDrive {
    let mut rng = rng(condition, run);
    let rng = &mut rng;
    let two = 2.0 * DEG;
    let aoa = 3.801e-4f32.sqrt();
    match condition {
        Condition::Bias2 => simple(&u_route(240), U_EMITTER, two, two, 2.0 * DEG, 0.0, rng),
        Condition::Bias4 => simple(&u_route(240), U_EMITTER, two, two, 4.0 * DEG, 0.0, rng),
        Condition::Bias4Short => simple(&l600(), [1200.0, 800.0], aoa, aoa, 4.0 * DEG, 0.0, rng),
        Condition::Multipath => {
            let ghost = [900.0, 1800.0];
            let route = u_route(240);
            let bearings = route.iter().enumerate().map(|(k, v)| {
                let target = if (60..120).contains(&k) {
                    ghost
                } else {
                    U_EMITTER
                };
                bearing_to(target, *v, two * random::normal(rng), two)
            });
            FieldDrive {
                observations: timed(bearings.collect::<Vec<_>>(), 1.0),
                emitters: vec![Truth {
                    position: U_EMITTER,
                    freq_mhz: None,
                }],
                ghost: Some(ghost),
                bias: 0.0,
                sigma: two,
            }
        }
        Condition::TwoEmitters => {
            let a = Truth {
                position: U_EMITTER,
                freq_mhz: Some(145.0),
            };
            let b = Truth {
                position: [-700.0, 2200.0],
                freq_mhz: Some(146.52),
            };
            let mut observations = Vec::new();
            for (k, v) in u_route(240).iter().enumerate() {
                for (j, t) in [a, b].iter().enumerate() {
                    let mut o = Observation::new(
                        bearing_to(t.position, *v, two * random::normal(rng), two),
                        k as f32 + 0.5 * j as f32,
                    );
                    o.freq_mhz = t.freq_mhz;
                    observations.push(o);
                }
            }
            FieldDrive {
                observations,
                emitters: vec![a, b],
                ghost: None,
                bias: 0.0,
                sigma: two,
            }
        }
        Condition::Correlated => {
            // 9 km at 20 m/s, 5 reports a second: 2250 reports.
            let route = u_route(2250);
            let raw_sigma = 6.0 * DEG;
            let mut window = [0.0f32; 10];
            for w in window.iter_mut() {
                *w = raw_sigma * random::normal(rng);
            }
            let bearings: Vec<Bearing> = route
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    window[k % 10] = raw_sigma * random::normal(rng);
                    let mean = window.iter().sum::<f32>() / 10.0;
                    bearing_to(U_EMITTER, *v, mean, two)
                })
                .collect();
            FieldDrive {
                observations: timed(bearings, 0.2),
                emitters: vec![Truth {
                    position: U_EMITTER,
                    freq_mhz: None,
                }],
                ghost: None,
                bias: 0.0,
                sigma: raw_sigma / 10f32.sqrt(),
            }
        }
        Condition::PureNoise => {
            let mut d = simple(&u_route(240), U_EMITTER, two, two, 0.0, 1.0, rng);
            d.emitters.clear();
            d
        }
        Condition::FewBearings => {
            let n = 3 + run % 8;
            let full = u_route(240);
            let route: Vec<[f32; 2]> = (0..n).map(|k| full[(k * 239) / (n - 1)]).collect();
            simple(&route, U_EMITTER, 3.0 * DEG, two, 0.0, 0.0, rng)
        }
        Condition::Distant => simple(&l600(), [8000.0, 6000.0], aoa, aoa, 0.0, 0.0, rng),
        Condition::Long47 => long_drive(47.0, true, rng),
        Condition::Long70 => long_drive(70.0, true, rng),
        Condition::Long70Uncorrected => long_drive(70.0, false, rng),
        Condition::Wild15 => simple(&l600(), [1200.0, 800.0], two, two, 0.0, 0.15, rng),
        Condition::AoaAfsaWild | Condition::AoaAfsa | Condition::AoaDrive => {
            let name = match condition {
                Condition::AoaAfsaWild => "aoa-afsa-wild",
                Condition::AoaAfsa => "aoa-afsa",
                _ => "aoa-drive",
            };
            let scenario = crate::scenario::Scenario::named(name);
            let Some((s, d)) = scenario.as_ref().and_then(|s| Some((s, s.drive()?))) else {
                return simple(&l600(), [1200.0, 800.0], aoa, aoa, 0.0, 0.0, rng);
            };
            // The bench's own runs: the same bearings `foxhunt bench` scores.
            let mut r = s.rng(run);
            let bearings = d.simulate(&mut r);
            FieldDrive {
                observations: timed(bearings, 1.0),
                emitters: vec![Truth {
                    position: d.emitter,
                    freq_mhz: None,
                }],
                ghost: None,
                bias: 0.0,
                sigma: d.sigma(),
            }
        }
    }
}

/// What one run of the pipeline gave, judged against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOutcome {
    /// An emitter was reported for the truth's channel.
    pub found: bool,
    /// Error of that emitter, metres.
    pub error: f32,
    /// Its 95 % ellipse holds the truth.
    pub covered: bool,
    /// The probability, under the ellipse's own distribution (chi-square, or 2 F(2, dof) when
    /// the noise was estimated), of a truth at least this far out: below 0.0027 is "beyond
    /// 3 sigma" (the 99.73 % of three sigmas in one dimension).
    pub tail: f32,
    /// The bias-aware bound at the truth (the drive's geometry, true noise, the prior), m.
    pub bound: f32,
    /// A ghost was reported as another source within its own 95 % ellipse (or 200 m).
    pub ghost_reported: bool,
    /// The emitter's reported offset, radians.
    pub bias: f32,
    /// The truth lies within the reported CEP50.
    pub within_cep50: bool,
}

/// The observations' geometry at the truth with the true noise: the bound's input.
fn truth_geometry(d: &FieldDrive, t: &Truth) -> Vec<Bearing> {
    d.observations
        .iter()
        .filter(|o| o.freq_mhz == t.freq_mhz)
        .map(|o| Bearing {
            vehicle: o.bearing.vehicle,
            theta: predicted(&t.position, &o.bearing.vehicle),
            sigma: d.sigma,
        })
        .collect()
}

/// Run the pipeline on one drive.
pub fn run_locate(
    d: &FieldDrive,
    config: &LocateConfig,
    seed: u64,
) -> Result<Report<CHANNELS, OTHERS>, Error> {
    crate::runs::pipeline(&d.observations, config, seed)
}

/// The emitter reported for the channel of truth `t`.
pub fn emitter_for<'a>(r: &'a Report<CHANNELS, OTHERS>, t: &Truth) -> Option<&'a Source> {
    let same = |f: Option<f32>| match (f, t.freq_mhz) {
        (None, None) => true,
        (Some(a), Some(b)) => (a - b).abs() < 0.05,
        _ => false,
    };
    r.channels().iter().find_map(|c| match c.outcome {
        ChannelOutcome::Emitter(i) if same(c.freq_mhz) => r.emitters().get(i),
        _ => None,
    })
}

/// Whether the source's ellipse holds `truth`, and the tail probability of its distance.
fn sigmas_of(s: &Source, truth: &[f32; 2]) -> (bool, f32) {
    let m = mahalanobis(&s.covariance, &s.position, truth).unwrap_or(f32::INFINITY);
    let m2 = (m * m) as f64;
    let covered = m * m <= s.ellipse_scale;
    // P(2 F(2, d) > m^2) = (1 + m^2 / d)^(-d/2); P(chi2(2) > m^2) = exp(-m^2 / 2).
    let tail = if s.sigma_estimated {
        let d = s.dof as f64;
        (1.0 + m2 / d).powf(-d / 2.0)
    } else {
        (-m2 / 2.0).exp()
    };
    (covered, tail as f32)
}

/// The tail probability of three sigmas in one dimension.
pub const THREE_SIGMA_TAIL: f32 = 0.0027;

/// Judge one run: for each truth, its channel's emitter (none when the pipeline failed).
pub fn judge(
    d: &FieldDrive,
    r: Option<&Report<CHANNELS, OTHERS>>,
    prior: BiasPrior,
) -> Vec<RunOutcome> {
    d.emitters
        .iter()
        .map(|t| {
            let bound = bias::crlb(&t.position, &truth_geometry(d, t), prior)
                .map(|b| b.rmse)
                .unwrap_or(f32::INFINITY);
            let ghost_reported = d.ghost.is_some_and(|g| {
                r.into_iter().flat_map(|r| r.others()).any(|o| {
                    let (inside, _) = sigmas_of(&o.source, &g);
                    let near = (o.source.position[0] - g[0]).hypot(o.source.position[1] - g[1]);
                    inside || near < 200.0
                })
            });
            match r.and_then(|r| emitter_for(r, t)) {
                Some(s) => {
                    let (covered, tail) = sigmas_of(s, &t.position);
                    let error =
                        (s.position[0] - t.position[0]).hypot(s.position[1] - t.position[1]);
                    RunOutcome {
                        found: true,
                        error,
                        covered,
                        tail,
                        bound,
                        ghost_reported,
                        bias: s.bias,
                        within_cep50: error <= s.cep50,
                    }
                }
                None => RunOutcome {
                    found: false,
                    error: f32::NAN,
                    covered: false,
                    tail: f32::NAN,
                    bound,
                    ghost_reported,
                    bias: f32::NAN,
                    within_cep50: false,
                },
            }
        })
        .collect()
}

/// A condition's figures over its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The condition.
    pub condition: Condition,
    /// Runs.
    pub runs: usize,
    /// Per truth emitter (one for most conditions, two for two-emitters): the figures below.
    pub per_emitter: Vec<EmitterSummary>,
    /// Runs with no consistent emitter in any channel.
    pub no_emitter: usize,
    /// Runs in which the ghost was reported as another source.
    pub ghost_reported: usize,
}

/// Figures for one truth emitter over the runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmitterSummary {
    /// Runs with an emitter reported for its channel.
    pub found: usize,
    /// Of those, runs whose 95 % ellipse holds the truth.
    pub covered: usize,
    /// Of those, runs with the truth beyond 3 sigma (the 99.73 % region) of the ellipse.
    pub beyond_3_sigma: usize,
    /// Root mean square error of the found fixes, metres.
    pub rmse: f64,
    /// Root mean square of the bias-aware bound over the runs, metres.
    pub bound: f64,
    /// Mean reported offset, degrees.
    pub mean_bias_deg: f64,
    /// Of the found runs, those with the truth within the reported CEP50.
    pub within_cep50: usize,
}

impl EmitterSummary {
    /// Share of found runs whose ellipse holds the truth.
    pub fn coverage(&self) -> f64 {
        self.covered as f64 / self.found.max(1) as f64
    }
    /// rmse / bound.
    pub fn ratio(&self) -> f64 {
        self.rmse / self.bound
    }
}

/// Measure `condition` over `runs` seeded runs with `config` (its priors also set the bound).
pub fn measure(condition: Condition, runs: usize, config: &LocateConfig) -> Summary {
    let outcomes: Vec<(Vec<RunOutcome>, bool)> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let d = simulate(condition, run);
            let r = run_locate(&d, config, run as u64).ok();
            let none = r.as_ref().is_none_or(|r| r.emitters().is_empty());
            (judge(&d, r.as_ref(), config.priors[0]), none)
        })
        .collect();
    let emitters = outcomes.first().map(|o| o.0.len()).unwrap_or(0);
    let per_emitter = (0..emitters)
        .map(|e| {
            let mut s = EmitterSummary {
                found: 0,
                covered: 0,
                beyond_3_sigma: 0,
                rmse: 0.0,
                bound: 0.0,
                mean_bias_deg: 0.0,
                within_cep50: 0,
            };
            let mut sq = 0.0f64;
            let mut bound_sq = 0.0f64;
            for (o, _) in &outcomes {
                let Some(o) = o.get(e) else { continue };
                bound_sq += (o.bound as f64).powi(2);
                if o.found {
                    s.found += 1;
                    s.covered += o.covered as usize;
                    s.beyond_3_sigma += (o.tail < THREE_SIGMA_TAIL) as usize;
                    sq += (o.error as f64).powi(2);
                    s.mean_bias_deg += (o.bias / DEG) as f64;
                    s.within_cep50 += o.within_cep50 as usize;
                }
            }
            s.rmse = (sq / s.found.max(1) as f64).sqrt();
            s.bound = (bound_sq / runs.max(1) as f64).sqrt();
            s.mean_bias_deg /= s.found.max(1) as f64;
            s
        })
        .collect();
    Summary {
        condition,
        runs,
        per_emitter,
        no_emitter: outcomes.iter().filter(|o| o.1).count(),
        ghost_reported: outcomes
            .iter()
            .filter(|o| o.0.first().is_some_and(|r| r.ghost_reported))
            .count(),
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<26} runs {:>3}  no-emitter {:>3}",
            self.condition.name(),
            self.runs,
            self.no_emitter
        )?;
        for e in &self.per_emitter {
            write!(
                f,
                "  | found {:>3} coverage {:>5.1} % >3sd {:>2} rmse {:>8.1} m bound {:>8.1} m ratio {:>5.2} bias {:>5.2} deg",
                e.found,
                100.0 * e.coverage(),
                e.beyond_3_sigma,
                e.rmse,
                e.bound,
                e.ratio(),
                e.mean_bias_deg
            )?;
        }
        if self.condition == Condition::Multipath {
            write!(f, "  | ghost reported {}", self.ghost_reported)?;
        }
        Ok(())
    }
}

/// The estimators the field bench compares: the pipeline, and for context the plain fixes and
/// filters a user could ask `locate` for (run as `locate` runs them: noise estimated from the
/// residuals, no offset, one emitter from all bearings).
pub const BENCH_METHODS: [Method; 6] = [
    Method::MlRobust,
    Method::Ml,
    Method::MlHuber,
    Method::SirRobust,
    Method::Gpf,
    Method::Ekf,
];

/// Particles of the particle methods in the field bench (what `locate` uses).
const BENCH_PARTICLES: usize = 1000;

/// A field-bench row with nothing measured yet.
fn row(label: &str, method: Method, runs: usize) -> Row {
    Row::new(label.to_string(), method, BENCH_PARTICLES, runs)
}

/// The pipeline's rows for a condition: one per true emitter.
fn pipeline_rows(c: Condition, runs: usize) -> Vec<Row> {
    let t = std::time::Instant::now();
    let config = LocateConfig::default();
    let s = measure(c, runs, &config);
    let seconds = t.elapsed().as_secs_f64() / runs.max(1) as f64;
    let label = format!("field/{}", c.name());
    let mut note = Vec::new();
    if c == Condition::Multipath {
        note.push(format!(
            "ghost reported as another source in {} of {runs}",
            s.ghost_reported
        ));
    }
    if s.per_emitter.is_empty() {
        let mut r = row(&label, Method::MlRobust, runs);
        r.found = Some((runs - s.no_emitter) as f64 / runs.max(1) as f64);
        r.time_s = seconds;
        r.note = Some(format!(
            "no consistent emitter in {} of {runs} runs (there is none)",
            s.no_emitter
        ));
        return vec![r];
    }
    let several = s.per_emitter.len() > 1;
    s.per_emitter
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let label = if several {
                format!("{label}#{}", i + 1)
            } else {
                label.clone()
            };
            let mut r = row(&label, Method::MlRobust, runs);
            let found = e.found.max(1) as f64;
            r.found = Some(e.found as f64 / runs.max(1) as f64);
            r.time_s = seconds;
            if e.found > 0 {
                r.rmse = Some(e.rmse);
                r.coverage = Some(e.covered as f64 / found);
                r.cep50_share = Some(e.within_cep50 as f64 / found);
                r.beyond_3_sigma = Some(e.beyond_3_sigma);
            }
            r.crlb = Some(e.bound).filter(|b| b.is_finite());
            r.ratio = r.rmse.zip(r.crlb).map(|(e, b)| e / b);
            r.failures = runs - e.found;
            let mut n = note.clone();
            n.push(format!("mean offset {:.2} deg", e.mean_bias_deg));
            r.note = Some(n.join("; "));
            r
        })
        .collect()
}

/// One plain-method run judged: error (m; NaN with no truth), inside the 95 % ellipse, within
/// CEP50, beyond 3 sigma, the bias-aware bound (m).
type Judged = (f64, bool, bool, bool, f64);

/// A plain method's row for a condition: one fix from all bearings, judged against the
/// nearest true emitter.
fn method_row(c: Condition, m: Method, runs: usize) -> Row {
    let label = format!("field/{}", c.name());
    let t = std::time::Instant::now();
    let outcomes: Vec<Option<Judged>> = crate::montecarlo::pool().install(|| {
        (0..runs)
            .into_par_iter()
            .map(|run| {
                let d = simulate(c, run);
                let bearings: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
                let mut rng = XorShiftRng::seed_from_u64(run as u64);
                let (f, _) = crate::runs::with_estimated_noise(
                    m,
                    BENCH_PARTICLES,
                    0.0,
                    &bearings,
                    false,
                    &mut rng,
                )
                .ok()?;
                let Some(t) = d.emitters.iter().min_by(|a, b| {
                    let da = (a.position[0] - f.position[0]).hypot(a.position[1] - f.position[1]);
                    let db = (b.position[0] - f.position[0]).hypot(b.position[1] - f.position[1]);
                    da.total_cmp(&db)
                }) else {
                    // No emitter at all (pure noise): any fix is a wrong one.
                    return Some((f64::NAN, false, false, true, f64::NAN));
                };
                let m =
                    mahalanobis(&f.covariance, &f.position, &t.position).unwrap_or(f32::INFINITY);
                let error = (f.position[0] - t.position[0]).hypot(f.position[1] - t.position[1]);
                let bound = bias::crlb(&t.position, &truth_geometry(&d, t), BiasPrior::default())
                    .map(|b| b.rmse as f64)
                    .unwrap_or(f64::INFINITY);
                Some((
                    error as f64,
                    m * m <= f.ellipse_scale,
                    error <= f.cep50,
                    // Beyond the 99.73 % region of a chi-square(2) ellipse: m^2 > 11.83.
                    m * m > 11.829,
                    bound,
                ))
            })
            .collect()
    });
    let mut r = row(&label, m, runs);
    r.time_s = t.elapsed().as_secs_f64() / runs.max(1) as f64;
    let ok: Vec<_> = outcomes.iter().flatten().collect();
    r.failures = runs - ok.len();
    r.found = Some(ok.len() as f64 / runs.max(1) as f64);
    let judged: Vec<_> = ok.iter().filter(|o| o.0.is_finite()).collect();
    if judged.is_empty() {
        if !ok.is_empty() {
            r.note = Some(format!(
                "a fix in {} of {runs} runs where there is no emitter: the method cannot say so",
                ok.len()
            ));
        }
        return r;
    }
    let k = judged.len() as f64;
    r.rmse = Some((judged.iter().map(|o| o.0 * o.0).sum::<f64>() / k).sqrt());
    r.coverage = Some(judged.iter().filter(|o| o.1).count() as f64 / k);
    r.cep50_share = Some(judged.iter().filter(|o| o.2).count() as f64 / k);
    r.beyond_3_sigma = Some(judged.iter().filter(|o| o.3).count());
    let bound = (judged.iter().map(|o| o.4 * o.4).sum::<f64>() / k).sqrt();
    r.crlb = Some(bound).filter(|b| b.is_finite());
    r.ratio = r.rmse.zip(r.crlb).map(|(e, b)| e / b);
    if c == Condition::TwoEmitters {
        r.note = Some("one fix for two emitters, judged against the nearer".into());
    }
    r
}

/// The field bench: every condition of `conditions`, the pipeline and the plain methods, over
/// `runs` seeded runs each.
pub fn bench(conditions: &[Condition], runs: usize) -> Vec<Row> {
    let mut rows = Vec::new();
    for &c in conditions {
        rows.extend(pipeline_rows(c, runs));
        for &m in BENCH_METHODS.iter().skip(1) {
            rows.push(method_row(c, m, runs));
        }
    }
    rows
}

/// A condition by name (`Condition::name`).
pub fn condition(name: &str) -> Option<Condition> {
    Condition::ALL.into_iter().find(|c| c.name() == name)
}

/// A field condition's run written as the bytes a DF unit and its GPS would send: per bearing a
/// GGA fix at the vehicle and a `$PFOXB` carrying its own position, time and frequency
/// (433.920 MHz where the condition has none), the route's first point at `origin`. The truths
/// come back in the capture's local frame (origin: that first point). The long drives are
/// simulated on the ellipsoid with the convergence already turned out and are not written; on
/// the others (a few km) the meridians' convergence between the vehicle and the origin is
/// under 0.05 degrees and is left in.
pub fn capture(
    condition: Condition,
    run: usize,
    origin: LatLon,
) -> Result<(Vec<u8>, Vec<Truth>), String> {
    use foxhunt_bridge::nmea::{Gga, Pfoxb, Reference, UtcTime, write_sentence};
    use foxhunt_core::model::bearing::theta_to_azimuth;
    if matches!(
        condition,
        Condition::Long47 | Condition::Long70 | Condition::Long70Uncorrected
    ) {
        return Err(format!(
            "`{}` is simulated on the ellipsoid and is not written as a capture",
            condition.name()
        ));
    }
    let d = simulate(condition, run);
    let start = d
        .observations
        .first()
        .map(|o| o.bearing.vehicle)
        .ok_or("the condition made no bearings")?;
    let frame = LocalFrame::new(origin, 0.0).map_err(|_| "origin out of range".to_string())?;
    let geo = |p: [f32; 2]| {
        frame
            .to_geodetic([f64::from(p[0] - start[0]), f64::from(p[1] - start[1])])
            .map_err(|_| "a route point is out of range".to_string())
    };
    // 10:00:00 UTC, the bearings' own times after it.
    let time = |t: f32| UtcTime {
        ms_of_day: 36_000_000 + (f64::from(t) * 1000.0).round() as u32,
    };
    let mut out = String::new();
    let mut line = String::new();
    for o in &d.observations {
        let position = geo(o.bearing.vehicle)?;
        let fix = Gga {
            talker: *b"GP",
            time: time(o.time_s),
            position,
            quality: Some(1),
            satellites: Some(9),
            hdop: Some(0.9),
            altitude_m: Some(0.0),
        };
        let bearing = Pfoxb {
            time: time(o.time_s),
            azimuth_deg: f64::from(theta_to_azimuth(o.bearing.theta).to_degrees()) % 360.0,
            reference: Reference::True,
            quality: 80.0,
            freq_mhz: f64::from(o.freq_mhz.unwrap_or(433.92)),
            position: Some(position),
        };
        for body in [
            {
                line.clear();
                fix.emit(&mut line).map_err(|_| "a GGA did not format")?;
                line.clone()
            },
            {
                line.clear();
                bearing
                    .emit(&mut line)
                    .map_err(|_| "a PFOXB did not format")?;
                line.clone()
            },
        ] {
            write_sentence(&mut out, &body).map_err(|_| "a sentence did not format")?;
        }
    }
    let truths = d
        .emitters
        .iter()
        .map(|t| Truth {
            position: [t.position[0] - start[0], t.position[1] - start[1]],
            freq_mhz: t.freq_mhz,
        })
        .collect();
    Ok((out.into_bytes(), truths))
}
