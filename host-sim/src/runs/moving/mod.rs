//! The moving-emitter scenarios (docs/src/tracking.md): a drone crossing a city, turning,
//! stopping and going, hovering, seen by fixed stations, by vehicles or both, through bearings,
//! RSSI or both. Each scenario simulates
//! its runs' updates and truth ([`MovingScenario::simulate`]), the bench measures every
//! tracking method on them against the posterior Cramér-Rao bound ([`bench`](mod@bench)), and
//! `foxhunt simulate --condition move-*` writes a run as its stations log it ([`capture`]).
//!
//! The city (chosen): an 8 km square with a fixed station at each corner. Paths at 12 m/s:
//! `straight` east along y = 2500 m for 10 minutes (the crossing of docs/src/tracking.md);
//! `turning` 2 minutes east, a full circle of 500 m radius (0.29 m/s^2), then east again;
//! `stop-and-go` 150 s moving, 150 s still, twice; `hover` still for 10 minutes. Vehicles
//! drive the sides of a 6 km square at 10 m/s. Stations report once a second: fixed ones with
//! 2 degree noise, vehicles 3 degrees; each unit's offset is drawn per run from N(0, 2
//! degrees), the trackers' prior. RSSI (outdoors): -40 dBm at 1 m, exponent 2.5, 6 dB noise;
//! the emitter's power is unknown to 6 dB and the exponent to 0.2, both drawn per run from
//! those priors. `move-vehicle-turning` and `move-vehicle-hover` watch from one vehicle alone:
//! what `foxhunt track` refuses (its range is not observable), measured.
//!
//! Indoors, `move-indoor-aoa` ([`indoor`]): a person walking a room, four wall anchors
//! reporting 37 angles a second with the error traits of real Bluetooth 5.1 arrays.

pub mod bench;
mod capture;
pub mod indoor;
pub mod locate;
pub mod triangulate;

pub use capture::{FREQ_MHZ, MovingCapture, capture};

use crate::runs::field::DirectionUnit;
use crate::track::moving::{K, Settings, Update};
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior};
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::model::rssi::PathLoss;
use foxhunt_core::random;
use foxhunt_core::track::{Epoch, Layout, Level, Motion};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

const DEG: f32 = PI / 180.0;

/// The names of the moving scenarios, in table order.
pub const NAMES: [&str; 13] = [
    "move-fixed-straight",
    "move-fixed-turning",
    "move-fixed-stop-and-go",
    "move-fixed-hover",
    "move-vehicles-turning",
    "move-vehicle-turning",
    "move-vehicle-hover",
    "move-mixed-stop-and-go",
    "move-fixed-rssi",
    "move-mixed-both",
    "move-indoor-aoa",
    "move-vehicles-direction",
    "move-vehicles-direction-ignored",
];

/// How the emitter moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// East at 12 m/s.
    Straight,
    /// East, a full circle, east.
    Turning,
    /// Moving and still in turns.
    StopAndGo,
    /// Still.
    Hover,
    /// A person walking a room at 1.2 m/s, with turns and stops.
    Walk,
}

/// A leg of a path: how long, at what speed, turning at what rate (rad/s, left positive).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Leg {
    seconds: f32,
    speed: f32,
    turn: f32,
}

impl Path {
    fn start(self) -> [f32; 2] {
        match self {
            Path::Straight => [400.0, 2500.0],
            Path::Turning => [1200.0, 2000.0],
            Path::StopAndGo => [1000.0, 3000.0],
            Path::Hover => [4000.0, 4500.0],
            Path::Walk => [3.0, 2.5],
        }
    }

    fn legs(self) -> Vec<Leg> {
        let go = |seconds| Leg {
            seconds,
            speed: SPEED,
            turn: 0.0,
        };
        let stop = |seconds| Leg {
            seconds,
            speed: 0.0,
            turn: 0.0,
        };
        match self {
            Path::Straight => vec![go(600.0)],
            Path::Turning => {
                let circle = TAU * 500.0 / SPEED;
                vec![
                    go(120.0),
                    Leg {
                        seconds: circle,
                        speed: SPEED,
                        turn: TAU / circle,
                    },
                    go(480.0 - circle),
                ]
            }
            Path::StopAndGo => vec![go(150.0), stop(150.0), go(150.0), stop(150.0)],
            Path::Hover => vec![stop(600.0)],
            Path::Walk => {
                let walk = |seconds| Leg {
                    seconds,
                    speed: indoor::WALK_SPEED,
                    turn: 0.0,
                };
                // A quarter circle of 1.5 m radius, left.
                let corner = Leg {
                    seconds: FRAC_PI_2 * 1.5 / indoor::WALK_SPEED,
                    speed: indoor::WALK_SPEED,
                    turn: indoor::WALK_SPEED / 1.5,
                };
                // Round the room anticlockwise with pauses, into the middle, back and north.
                vec![
                    walk(7.0),
                    corner,
                    walk(4.0),
                    stop(6.0),
                    corner,
                    walk(6.0),
                    corner,
                    walk(2.5),
                    corner,
                    walk(3.0),
                    stop(8.0),
                    corner,
                    corner,
                    walk(3.0),
                    stop(4.0),
                    Leg {
                        turn: -indoor::WALK_SPEED / 1.5,
                        ..corner
                    },
                    walk(1.0),
                ]
            }
        }
    }

    /// The true position, velocity and whether it moves at `t` seconds (integrated in 10 ms
    /// steps along the legs, heading east at the start).
    pub fn at(self, t: f32) -> ([f32; 2], [f32; 2], bool) {
        let mut p = self.start();
        let mut heading = 0.0f32;
        let mut left = t.max(0.0);
        for leg in self.legs() {
            let span = left.min(leg.seconds);
            // Exact for straight legs and arcs: integrate the arc in closed form.
            if leg.turn == 0.0 {
                p[0] += leg.speed * span * heading.cos();
                p[1] += leg.speed * span * heading.sin();
            } else {
                let r = leg.speed / leg.turn;
                let h1 = heading + leg.turn * span;
                p[0] += r * (h1.sin() - heading.sin());
                p[1] -= r * (h1.cos() - heading.cos());
                heading = h1;
            }
            left -= span;
            if left <= 0.0 && span < leg.seconds {
                let v = [leg.speed * heading.cos(), leg.speed * heading.sin()];
                return (p, v, leg.speed > 0.0);
            }
        }
        (p, [0.0, 0.0], false)
    }
}

/// The drone's speed, m/s.
const SPEED: f32 = 12.0;
/// The city's side, metres.
const CITY: f32 = 8000.0;

/// Where a station is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Route {
    /// A fixed station.
    Fixed([f32; 2]),
    /// A vehicle driving the 6 km square's sides at 10 m/s from corner `corner` (0: south
    /// west, then anticlockwise).
    Square {
        /// The starting corner.
        corner: usize,
    },
}

impl Route {
    /// Where it is at `t` seconds.
    pub fn at(&self, t: f32) -> [f32; 2] {
        match *self {
            Route::Fixed(p) => p,
            Route::Square { corner } => {
                let corners = [
                    [1000.0, 1000.0],
                    [7000.0, 1000.0],
                    [7000.0, 7000.0],
                    [1000.0, 7000.0],
                ];
                let side = 6000.0;
                let s = (10.0 * t.max(0.0) + side * corner as f32) % (4.0 * side);
                let k = ((s / side) as usize).min(3);
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                let w = (s - side * k as f32) / side;
                [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1])]
            }
        }
    }
}

/// One station of a scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Station {
    /// Where it is.
    pub route: Route,
    /// Its bearing noise, radians (indoors: the sd the trackers give it,
    /// [`indoor::tracked_sd`], the noise itself drawn by [`indoor::report`]).
    pub sigma: f32,
}

/// A moving-emitter scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingScenario {
    /// Name in reports.
    pub name: String,
    /// How the emitter moves.
    pub path: Path,
    /// Who watches.
    pub stations: Vec<Station>,
    /// Whether the stations report bearings.
    pub bearings: bool,
    /// Whether they report RSSI.
    pub rssi: bool,
    /// Sd of each unit's offset (truth drawn from it; the trackers' prior), radians.
    pub offset_sd: f32,
    /// Mean of the trackers' offset prior, radians (0 but indoors).
    pub offset_mean: f32,
    /// Indoor arrays' error traits (none: Gaussian noise of each station's sd and a
    /// Gaussian offset).
    pub aoa: Option<indoor::AoaErrors>,
    /// The vehicles' units' direction-dependent error and what the trackers are told of it
    /// (none: no such error).
    pub direction: Option<DirectionErrors>,
    /// The stations' path loss (RSSI).
    pub law: PathLoss,
    /// RSSI noise, dB.
    pub rssi_sigma_db: f32,
    /// Sd of the emitter's unknown power, dB (truth and prior).
    pub power_sd: f32,
    /// Sd of the exponent's correction (truth and prior).
    pub exponent_sd: f32,
    /// Seconds per run.
    pub duration_s: f32,
    /// Updates per second.
    pub rate_hz: f32,
    /// The trackers' motion model.
    pub motion: Motion,
    /// Seconds at the start left out of every figure (the tracker finding the emitter).
    pub warmup_s: f32,
    /// The noise the trackers are told every bearing has, radians (none: each station's
    /// own); told one, they estimate each station's from its bearings
    /// ([`crate::track::noise`]), as `track` does where the records' noise is a default.
    pub told_sigma: Option<f32>,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed.
    pub seed: u64,
}

/// Each vehicle's unit with a direction-dependent error: first and second harmonics of the
/// bearing relative to its course, each of an amplitude drawn from 2-5 degrees with a random
/// phase (the `direction-dependent-2-5deg` field condition's units,
/// [`DirectionUnit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionErrors {
    /// The sd of a calibration the trackers are told, radians: each coefficient the truth's
    /// plus an error of that sd, stated with it (as a stations file's `direction_deg` and
    /// `direction_error_deg`). `None`: the trackers are told nothing of it.
    pub calibration_sd: Option<f32>,
}

/// The calibration sd of `move-vehicles-direction`, radians: a lap past a known transmitter
/// measures each coefficient to about 0.15 degrees (docs/src/field.md, "Calibration"); 0.2.
const CALIBRATION_SD: f32 = 0.2 * DEG;

/// One simulated run.
#[derive(Debug, Clone)]
pub struct MovingRun {
    /// The updates.
    pub updates: Vec<Update>,
    /// At each update: the true position, velocity and whether it moves.
    pub truth: Vec<([f32; 2], [f32; 2], bool)>,
    /// Each source's true offset, radians.
    pub offsets: Vec<f32>,
    /// True power offset (dB) and exponent correction.
    pub rssi: (f32, f32),
    /// Each station's direction-dependent error as the trackers are told it (none: nothing
    /// told, or no such error).
    pub tables: Vec<Option<DirectionPrior>>,
}

fn fixed4() -> Vec<Station> {
    [[0.0, 0.0], [CITY, 0.0], [CITY, CITY], [0.0, CITY]]
        .into_iter()
        .map(|p| Station {
            route: Route::Fixed(p),
            sigma: 2.0 * DEG,
        })
        .collect()
}

fn vehicle(corner: usize) -> Station {
    Station {
        route: Route::Square { corner },
        sigma: 3.0 * DEG,
    }
}

impl MovingScenario {
    /// A scenario by name.
    pub fn named(name: &str) -> Option<Self> {
        let base = |path, stations: Vec<Station>, bearings, rssi| MovingScenario {
            name: name.to_string(),
            path,
            stations,
            bearings,
            rssi,
            offset_sd: 2.0 * DEG,
            offset_mean: 0.0,
            aoa: None,
            direction: None,
            law: PathLoss {
                p0: -40.0,
                d0: 1.0,
                eta: 2.5,
            },
            rssi_sigma_db: 6.0,
            power_sd: 6.0,
            exponent_sd: 0.2,
            duration_s: 600.0,
            rate_hz: 1.0,
            motion: Motion::OUTDOOR,
            warmup_s: 30.0,
            told_sigma: None,
            runs: 100,
            seed: 1,
        };
        let mixed = || vec![fixed4()[0], fixed4()[2], vehicle(1)];
        Some(match name {
            "move-fixed-straight" => base(Path::Straight, fixed4(), true, false),
            "move-fixed-turning" => base(Path::Turning, fixed4(), true, false),
            "move-fixed-stop-and-go" => base(Path::StopAndGo, fixed4(), true, false),
            "move-fixed-hover" => base(Path::Hover, fixed4(), true, false),
            "move-vehicle-turning" => base(Path::Turning, vec![vehicle(0)], true, false),
            "move-vehicle-hover" => base(Path::Hover, vec![vehicle(0)], true, false),
            "move-vehicles-turning" => {
                base(Path::Turning, vec![vehicle(0), vehicle(2)], true, false)
            }
            "move-mixed-stop-and-go" => base(Path::StopAndGo, mixed(), true, false),
            "move-fixed-rssi" => base(Path::Straight, fixed4(), false, true),
            "move-mixed-both" => base(Path::Turning, mixed(), true, true),
            "move-vehicles-direction" | "move-vehicles-direction-ignored" => MovingScenario {
                direction: Some(DirectionErrors {
                    calibration_sd: (name == "move-vehicles-direction").then_some(CALIBRATION_SD),
                }),
                ..base(Path::Turning, vec![vehicle(0), vehicle(2)], true, false)
            },
            "move-indoor-aoa" => {
                let anchors = indoor::ANCHORS
                    .iter()
                    .enumerate()
                    .map(|(a, (at, _))| Station {
                        route: Route::Fixed(*at),
                        sigma: indoor::tracked_sd(a),
                    })
                    .collect();
                let (mean, sd) = indoor::bias_prior();
                MovingScenario {
                    offset_mean: mean,
                    offset_sd: sd,
                    aoa: Some(indoor::AoaErrors::ALL),
                    duration_s: Path::Walk.legs().iter().map(|l| l.seconds).sum(),
                    rate_hz: indoor::RATE_HZ,
                    motion: Motion::INDOOR,
                    warmup_s: 3.0,
                    runs: 30,
                    ..base(Path::Walk, anchors, true, false)
                }
            }
            _ => return None,
        })
    }

    /// Every moving scenario, in table order.
    pub fn all() -> Vec<Self> {
        NAMES.iter().filter_map(|n| Self::named(n)).collect()
    }

    /// Updates per run.
    pub fn steps(&self) -> usize {
        (self.duration_s * self.rate_hz).round() as usize
    }

    /// What the state holds: an offset per station reporting bearings, RSSI terms.
    pub fn layout(&self) -> Layout {
        Layout {
            sources: if self.bearings {
                self.stations.len() as u8
            } else {
                0
            },
            rssi: self.rssi,
        }
    }

    /// The tracker's settings for this scenario (the default method and count).
    pub fn settings(&self) -> Settings {
        let mut s = Settings::new(self.layout(), self.motion);
        s.offsets = vec![
            BiasPrior {
                mean: self.offset_mean,
                sd: self.offset_sd,
            };
            self.stations.len()
        ];
        if self.aoa.is_some() {
            s.memory_s = indoor::MEMORY_S;
        }
        s.power_sd = if self.rssi { self.power_sd } else { 0.0 };
        s.exponent_sd = if self.rssi { self.exponent_sd } else { 0.0 };
        // Without bearings the first cloud is the city (or the room, which holds the walker).
        s.region = Some(match self.aoa {
            Some(_) => {
                let [w, d] = indoor::ROOM;
                s.room = Some(indoor::ROOM);
                ([w / 2.0, d / 2.0], w.max(d) / 3.0)
            }
            None => ([CITY / 2.0, CITY / 2.0], CITY / 3.0),
        });
        s
    }

    /// The generator of run `run`.
    pub fn rng(&self, run: usize) -> XorShiftRng {
        XorShiftRng::seed_from_u64(
            self.seed
                .wrapping_mul(0x5851_F42D_4C95_7F2D)
                .wrapping_add(run as u64),
        )
    }

    /// Run `run`'s updates and truth.
    pub fn simulate(&self, run: usize) -> MovingRun {
        let mut rng = self.rng(run);
        let draws: Vec<indoor::AnchorDraw> = match &self.aoa {
            Some(errors) => self
                .stations
                .iter()
                .map(|_| indoor::AnchorDraw::draw(&mut rng, errors))
                .collect(),
            None => Vec::new(),
        };
        let offsets: Vec<f32> = match self.aoa {
            Some(_) => draws.iter().map(|d| d.bias).collect(),
            None => self
                .stations
                .iter()
                .map(|_| self.offset_sd * random::normal(&mut rng))
                .collect(),
        };
        let rssi = (
            self.power_sd * random::normal(&mut rng),
            self.exponent_sd * random::normal(&mut rng),
        );
        // The vehicles' units' harmonics, and the calibrations the trackers are told.
        let (units, tables) = self.direction_units(&mut rng);
        let dt = 1.0 / self.rate_hz;
        let mut updates = Vec::with_capacity(self.steps());
        let mut truth = Vec::with_capacity(self.steps());
        for k in 0..self.steps() {
            let t = k as f32 * dt;
            let (p, v, moving) = self.path.at(t);
            let mut epoch = Epoch::<K>::new(if k == 0 { 0.0 } else { dt });
            for (s, station) in self.stations.iter().enumerate() {
                let at = station.route.at(t);
                if self.bearings {
                    let truth = predicted(&p, &at);
                    let theta = match &self.aoa {
                        Some(errors) => indoor::report(&mut rng, s, truth, &draws[s], errors),
                        None => {
                            // A unit's error is a property of the true relative bearing.
                            let ahead = station.route.at(t + 0.1);
                            let course = (ahead[1] - at[1]).atan2(ahead[0] - at[0]);
                            let unit = units[s].map_or(0.0, |mean| {
                                DirectionPrior { mean, sd: 0.0 }.error_at(wrap(truth - course))
                            });
                            let noise = station.sigma * random::normal(&mut rng);
                            wrap(truth + offsets[s] + unit + noise)
                        }
                    };
                    let mut o = Observation::new(
                        Bearing {
                            vehicle: at,
                            theta,
                            sigma: self.told_sigma.unwrap_or(station.sigma),
                        },
                        t,
                    );
                    o.station = s as u16;
                    // K holds every station of these scenarios.
                    let _ = epoch.push_bearing(o);
                }
                if self.rssi {
                    let law = PathLoss {
                        p0: self.law.p0 + rssi.0,
                        eta: self.law.eta + rssi.1,
                        ..self.law
                    };
                    let d = (p[0] - at[0]).hypot(p[1] - at[1]);
                    let _ = epoch.push_level(Level {
                        anchor: at,
                        dbm: law.rssi(d) + self.rssi_sigma_db * random::normal(&mut rng),
                        sigma_db: self.rssi_sigma_db,
                        law: self.law,
                    });
                }
            }
            updates.push(Update { t_s: t, epoch });
            truth.push((p, v, moving));
        }
        MovingRun {
            updates,
            truth,
            offsets,
            rssi,
            tables,
        }
    }

    /// Each station's unit's harmonic coefficients (vehicles', where the scenario gives them
    /// a direction-dependent error) and the table the trackers are told, drawn from `rng` (no
    /// draw where the scenario has none, so the other scenarios' runs are as they were).
    fn direction_units(
        &self,
        rng: &mut XorShiftRng,
    ) -> (Vec<Option<[f32; 4]>>, Vec<Option<DirectionPrior>>) {
        let n = self.stations.len();
        let Some(d) = self.direction else {
            return (vec![None; n], vec![None; n]);
        };
        self.stations
            .iter()
            .map(|st| {
                if matches!(st.route, Route::Fixed(_)) {
                    return (None, None);
                }
                let c = DirectionUnit::draw(rng).coefficients;
                let told = d.calibration_sd.map(|sd| DirectionPrior {
                    mean: c.map(|v| v + sd * random::normal(rng)),
                    sd,
                });
                (Some(c), told)
            })
            .unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_continuous_and_legs_add_up() {
        for path in [Path::Straight, Path::Turning, Path::StopAndGo, Path::Hover] {
            let total: f32 = path.legs().iter().map(|l| l.seconds).sum();
            assert!((total - 600.0).abs() < 1e-3, "{path:?}");
            let mut last = path.at(0.0).0;
            for k in 1..=600 {
                let (p, v, _) = path.at(k as f32);
                let step = (p[0] - last[0]).hypot(p[1] - last[1]);
                assert!(step <= SPEED + 0.01, "{path:?} {k}: {step}");
                assert!(v[0].hypot(v[1]) <= SPEED + 1e-3);
                last = p;
            }
        }
        // The circle closes: back on y = 2000 heading east after it.
        let (p, v, _) = Path::Turning.at(120.0 + TAU * 500.0 / SPEED);
        assert!((p[1] - 2000.0).abs() < 1.0 && v[0] > 11.9, "{p:?} {v:?}");
        let (_, _, moving) = Path::StopAndGo.at(200.0);
        assert!(!moving);
    }

    #[test]
    fn the_walk_stays_in_the_room_at_walking_pace() {
        let total: f32 = Path::Walk.legs().iter().map(|l| l.seconds).sum();
        assert!(total > 50.0, "{total}");
        let [w, d] = indoor::ROOM;
        let mut last = Path::Walk.at(0.0).0;
        let mut stopped = 0;
        for k in 1..=(10.0 * total) as usize {
            let (p, v, moving) = Path::Walk.at(k as f32 / 10.0);
            assert!(
                p[0] > 1.0 && p[0] < w - 1.0 && p[1] > 1.0 && p[1] < d - 1.0,
                "{k}: {p:?}"
            );
            assert!((p[0] - last[0]).hypot(p[1] - last[1]) <= 0.121);
            assert!(v[0].hypot(v[1]) <= indoor::WALK_SPEED + 1e-3);
            stopped += usize::from(!moving);
            last = p;
        }
        assert!(stopped > 100, "{stopped}");
    }

    #[test]
    fn vehicles_drive_the_square() {
        let r = Route::Square { corner: 0 };
        assert_eq!(r.at(0.0), [1000.0, 1000.0]);
        let p = r.at(600.0);
        assert!(
            (p[0] - 7000.0).abs() < 1e-2 && (p[1] - 1000.0).abs() < 1e-2,
            "{p:?}"
        );
        let q = Route::Square { corner: 2 }.at(300.0);
        assert!(
            (q[0] - 4000.0).abs() < 1e-2 && (q[1] - 7000.0).abs() < 1e-2,
            "{q:?}"
        );
    }
}
