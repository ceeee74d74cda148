//! The drives of the field conditions: routes, emitters and how each condition's bearings
//! go wrong.

use super::{Condition, DEG, FieldDrive, StationTruth, Truth, rng};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior};
use foxhunt_core::fix::device::DeviceClass;
use foxhunt_core::fix::locate::Observation;
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::random;
use rand_xorshift::XorShiftRng;
use std::f32::consts::PI;

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

/// The canonical L600 route (docs/src/scenarios.md).
pub fn l600() -> Vec<[f32; 2]> {
    crate::runs::scenario::route("L600", [0.0, 0.0]).unwrap_or_default()
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
        stations: Vec::new(),
        bias,
        sigma,
    }
}

/// 60 s at 15 m/s along an arc of 3 km radius (1.2 km, turning 23 degrees), 5 running-mean
/// reports a second (the last 10 raw bearings of 8 degrees), the emitter 8 km off to the
/// side of the drive's heading, an offset from the default prior.
fn open_correlated_curved(rng: &mut XorShiftRng) -> FieldDrive {
    let bias = foxhunt_core::fix::bias::DEFAULT_BIAS_SD * random::normal(rng);
    let (radius, speed) = (3000.0f32, 15.0f32);
    let route = reports(60.0, |k| {
        let a = speed * k / RunningMean::RATE_HZ / radius;
        [radius * a.sin(), radius * (1.0 - a.cos())]
    });
    let drive = RunningMean {
        route,
        emitter: [6000.0, 5300.0],
        raw_sigma: 8.0 * DEG,
        bias,
        stated: None,
    };
    drive.drive(rng)
}

/// A unit reporting 5 times a second the running mean of its last 10 raw bearings, from a
/// vehicle on `route` (a position per report).
struct RunningMean {
    route: Vec<[f32; 2]>,
    emitter: [f32; 2],
    /// Sd of each raw bearing, radians.
    raw_sigma: f32,
    /// The unit's offset, radians.
    bias: f32,
    /// The sd the unit states (none: the running mean's own, raw_sigma / sqrt(10)).
    stated: Option<f32>,
}

/// The vehicle's position at each report of `seconds` of driving, from `at(k)` (k the
/// report's index).
fn reports(seconds: f32, at: impl Fn(f32) -> [f32; 2]) -> Vec<[f32; 2]> {
    let n = (seconds * RunningMean::RATE_HZ) as usize;
    (0..n).map(|k| at(k as f32)).collect()
}

impl RunningMean {
    const RATE_HZ: f32 = 5.0;
    const WINDOW: usize = 10;

    fn drive(&self, rng: &mut XorShiftRng) -> FieldDrive {
        let mean_sigma = self.raw_sigma / (Self::WINDOW as f32).sqrt();
        let mut window = [0.0f32; Self::WINDOW];
        for w in window.iter_mut() {
            *w = self.raw_sigma * random::normal(rng);
        }
        let stated = self.stated.unwrap_or(mean_sigma);
        let bearings: Vec<Bearing> = self
            .route
            .iter()
            .enumerate()
            .map(|(k, v)| {
                window[k % Self::WINDOW] = self.raw_sigma * random::normal(rng);
                let mean = window.iter().sum::<f32>() / Self::WINDOW as f32;
                bearing_to(self.emitter, *v, self.bias + mean, stated)
            })
            .collect();
        FieldDrive {
            observations: timed(bearings, 1.0 / Self::RATE_HZ),
            emitters: vec![Truth {
                position: self.emitter,
                freq_mhz: None,
            }],
            ghost: None,
            stations: Vec::new(),
            bias: self.bias,
            sigma: mean_sigma,
        }
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
            stations: Vec::new(),
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
        stations: Vec::new(),
        bias: 0.0,
        sigma,
    }
}

/// A calibrated unit with a residue: 1800 bearings (3 degrees) along 1.5 km of straight road,
/// the emitter 3 km broadside; the calibration says 0 +- 0.05 degrees, the unit's offset has
/// since moved by an error of the sd its stations file states, 0.2 to 1 degree by run.
fn systematic(run: usize, rng: &mut XorShiftRng) -> FieldDrive {
    let n = 1800;
    let route: Vec<[f32; 2]> = (0..n)
        .map(|k| [1500.0 * k as f32 / (n - 1) as f32, 0.0])
        .collect();
    let emitter = [750.0f32, 3000.0];
    let sigma = 3.0 * DEG;
    let calibrated = 0.05 * DEG;
    let unmodelled = (0.2 + 0.2 * (run % 5) as f32) * DEG;
    let bias = calibrated * random::normal(rng) + unmodelled * random::normal(rng);
    let bearings: Vec<Bearing> = route
        .iter()
        .map(|v| bearing_to(emitter, *v, bias + sigma * random::normal(rng), sigma))
        .collect();
    FieldDrive {
        observations: timed(bearings, 1.0 / 3.0),
        emitters: vec![Truth {
            position: emitter,
            freq_mhz: None,
        }],
        ghost: None,
        stations: vec![StationTruth {
            id: "doppler".into(),
            fixed: false,
            offset: bias,
            sigma,
            prior: BiasPrior {
                mean: 0.0,
                sd: calibrated,
            },
            class: Some(DeviceClass::Doppler),
            unmodelled: Some(unmodelled),
        }],
        bias,
        sigma,
    }
}

/// Four fixed arrays of the indoor angle-of-arrival class at the corners of a 2 x 1.5 km site,
/// the emitter somewhere inside: 15 degree noise quantised to 2 degrees (as such arrays
/// report), 37 reports a second per array for 30 s, interleaved in time. Each array's offset
/// is drawn from the default prior plus its class's unmodelled error; its stations file
/// states the class (whose 13 degree noise the bearings carry) and nothing else. (In a room of
/// metres the likelihood walk's 2.5 m allowance for the stations' positions widens the
/// ellipse: docs/src/field.md, "Device classes".)
fn aoa_array(rng: &mut XorShiftRng) -> FieldDrive {
    let corners = [
        [0.0f32, 0.0],
        [2000.0, 0.0],
        [2000.0, 1500.0],
        [0.0, 1500.0],
    ];
    let emitter = [
        random::uniform_in(rng, 400.0, 1600.0),
        random::uniform_in(rng, 300.0, 1200.0),
    ];
    let class = DeviceClass::IndoorAoa.noise();
    let stated = class.noise.unwrap_or(13.0 * DEG);
    let sigma = 15.0 * DEG;
    let quantum = 2.0 * DEG;
    let prior = BiasPrior::default();
    let stations: Vec<StationTruth> = corners
        .iter()
        .enumerate()
        .map(|(k, _)| {
            let offset = prior.sd * random::normal(rng) + class.unmodelled * random::normal(rng);
            StationTruth {
                id: format!("array-{}", k + 1),
                fixed: true,
                offset,
                sigma,
                prior,
                class: Some(DeviceClass::IndoorAoa),
                unmodelled: None,
            }
        })
        .collect();
    let rate = 37.0f32;
    let per_anchor = (30.0 * rate) as usize;
    let mut observations = Vec::with_capacity(per_anchor * corners.len());
    for k in 0..per_anchor {
        for (s, (at, st)) in corners.iter().zip(&stations).enumerate() {
            let raw = predicted(&emitter, at) + st.offset + sigma * random::normal(rng);
            let theta = wrap((raw / quantum).round() * quantum);
            let mut o = Observation::new(
                Bearing {
                    vehicle: *at,
                    theta,
                    sigma: stated,
                },
                (k as f32 + s as f32 / corners.len() as f32) / rate,
            );
            o.station = s as u16;
            observations.push(o);
        }
    }
    FieldDrive {
        observations,
        emitters: vec![Truth {
            position: emitter,
            freq_mhz: None,
        }],
        ghost: None,
        stations,
        bias: 0.0,
        sigma,
    }
}

/// The course (theta) of the U drive at route point `v`: east, north, then west.
fn u_course(v: [f32; 2]) -> f32 {
    if v[1] <= 0.0 && v[0] < 1500.0 {
        0.0
    } else if v[0] >= 1500.0 && v[1] < 3000.0 {
        PI / 2.0
    } else {
        PI
    }
}

/// A pseudo-Doppler unit whose error depends on the bearing relative to the vehicle (the
/// `direction-dependent-2-5deg` condition's): first and second harmonics of amplitude drawn
/// from 2-5 degrees each with a random phase, an offset from the default prior, 2 degrees of
/// noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionUnit {
    /// Its offset, radians.
    pub bias: f32,
    /// Its harmonic coefficients a_1, b_1, a_2, b_2, radians.
    pub coefficients: [f32; 4],
    /// Its bearing noise, radians.
    pub sigma: f32,
}

impl DirectionUnit {
    /// A unit drawn from `rng`.
    pub fn draw(rng: &mut XorShiftRng) -> Self {
        let sigma = 2.0 * DEG;
        let bias = foxhunt_core::fix::bias::DEFAULT_BIAS_SD * random::normal(rng);
        let mut coefficients = [0.0f32; 4];
        for k in 0..2 {
            let amplitude = random::uniform_in(rng, 2.0, 5.0) * DEG;
            let phase = random::uniform_in(rng, -PI, PI);
            coefficients[2 * k] = amplitude * phase.cos();
            coefficients[2 * k + 1] = amplitude * phase.sin();
        }
        Self {
            bias,
            coefficients,
            sigma,
        }
    }

    /// Its bearings of `emitter` from `route`, the vehicle's course at point k `course(k)`.
    pub fn bearings(
        &self,
        emitter: [f32; 2],
        route: &[[f32; 2]],
        course: impl Fn(usize) -> f32,
        rng: &mut XorShiftRng,
    ) -> Vec<Bearing> {
        let table = DirectionPrior {
            mean: self.coefficients,
            sd: 0.0,
        };
        route
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let truth = predicted(&emitter, v);
                // The antenna's error is a property of the true relative bearing.
                let e = table.error_at(wrap(truth - course(k)));
                let error = self.bias + e + self.sigma * random::normal(rng);
                bearing_to(emitter, *v, error, self.sigma)
            })
            .collect()
    }

    /// The first `points` of the U drive's 240 bearings of its emitter, 1 s apart (all 240:
    /// the field condition's drive; 160: its first two legs, an L).
    pub fn u_drive(&self, points: usize, rng: &mut XorShiftRng) -> FieldDrive {
        let mut route = u_route(240);
        route.truncate(points);
        let bearings = self.bearings(U_EMITTER, &route, |k| u_course(route[k]), rng);
        FieldDrive {
            observations: timed(bearings, 1.0),
            emitters: vec![Truth {
                position: U_EMITTER,
                freq_mhz: None,
            }],
            ghost: None,
            stations: Vec::new(),
            bias: self.bias,
            sigma: self.sigma,
        }
    }
}

/// The U drive's 240 bearings (2 degrees) from a [`DirectionUnit`].
fn direction_dependent(rng: &mut XorShiftRng) -> FieldDrive {
    DirectionUnit::draw(rng).u_drive(240, rng)
}

/// `correlated-5hz` on a curved track: 9 km at 20 m/s (450 s) along an arc of 2 km radius
/// (258 degrees) round (0, 0), 5 reports a second, each the running mean of the last 10 raw
/// bearings (6 degrees each; the unit states 2), the emitter at (400, 300), off the arc's
/// centre.
fn correlated_curved(rng: &mut XorShiftRng) -> FieldDrive {
    let (radius, speed) = (2000.0f32, 20.0f32);
    let route = reports(450.0, |k| {
        let a = speed * k / RunningMean::RATE_HZ / radius;
        [radius * a.sin(), -radius * a.cos()]
    });
    let drive = RunningMean {
        route,
        emitter: [400.0, 300.0],
        raw_sigma: 6.0 * DEG,
        bias: 0.0,
        stated: Some(2.0 * DEG),
    };
    drive.drive(rng)
}

/// The observations of run `run` of `condition`.
pub fn simulate(condition: Condition, run: usize) -> FieldDrive {
    if condition == Condition::DirectionUnstated {
        return simulate(Condition::DirectionDependent, run);
    }
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
                stations: Vec::new(),
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
                stations: Vec::new(),
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
                stations: Vec::new(),
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
        Condition::OpenNoisyFew => {
            let n = 6 + run % 7;
            let first: Vec<[f32; 2]> = l600().into_iter().take(30).collect();
            let route: Vec<[f32; 2]> = (0..n)
                .map(|k| first[(k * (first.len() - 1)) / (n - 1)])
                .collect();
            let bias = foxhunt_core::fix::bias::DEFAULT_BIAS_SD * random::normal(rng);
            let sigma = 15.0 * DEG;
            simple(&route, [1200.0, 800.0], sigma, sigma, bias, 0.0, rng)
        }
        Condition::OpenCorrelatedCurved => open_correlated_curved(rng),
        Condition::Systematic => systematic(run, rng),
        Condition::AoaArray15 => aoa_array(rng),
        Condition::DirectionDependent | Condition::DirectionUnstated => direction_dependent(rng),
        Condition::CorrelatedCurved => correlated_curved(rng),
        Condition::AoaAfsaWild | Condition::AoaAfsa | Condition::AoaDrive => {
            let name = match condition {
                Condition::AoaAfsaWild => "aoa-afsa-wild",
                Condition::AoaAfsa => "aoa-afsa",
                _ => "aoa-drive",
            };
            let scenario = crate::runs::scenario::Scenario::named(name);
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
                stations: Vec::new(),
                bias: 0.0,
                sigma: d.sigma(),
            }
        }
    }
}
