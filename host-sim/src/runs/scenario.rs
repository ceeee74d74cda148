//! The canonical scenarios of docs/src/scenarios.md as data, in one place: each
//! carries its model, the methods of its table, its particle counts and the source papers'
//! figures. Scenario files a user writes are read here too.

use foxhunt_core::canonical::{self as c, AOA_BEARING_VAR, AOA_EMITTER};
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{Bearing, Method, RssiTracker, random};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Deserialize;
use std::f32::consts::PI;

/// A benchmark scenario: a model, the methods compared on it, and how many runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name printed in reports.
    pub name: String,
    /// What is estimated.
    pub model: ScenarioModel,
    /// The methods of its table, in order.
    pub methods: Vec<Method>,
    /// Particle counts of its table (one row per method and count).
    pub particles: Vec<usize>,
    /// The plain filter every swarm method is compared with at equal cost.
    pub baseline: Method,
    /// The source papers' own figures for rows of this table.
    pub papers: Vec<PaperFigure>,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed; run r uses seed * 1_000_003 + r.
    pub seed: u64,
}

/// What a scenario estimates.
#[derive(Debug, Clone, PartialEq)]
pub enum ScenarioModel {
    /// A static emitter located from a drive's bearings.
    Bearing(Drive),
    /// A ZigBee node tracked indoors from RSSI at three anchors (seed 003).
    Rssi {
        /// The node's model.
        tracker: RssiTracker<3>,
        /// Its initial true state [x, vx, y, vy].
        start: [f32; 4],
        /// Steps per run.
        steps: usize,
    },
    /// The univariate nonstationary growth model (seed 001's benchmark).
    Ungm {
        /// Steps per run.
        steps: usize,
    },
}

/// A static emitter and the drive that sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct Drive {
    /// True emitter position, metres.
    pub emitter: [f32; 2],
    /// Vehicle positions, one bearing each.
    pub route: Vec<[f32; 2]>,
    /// Bearing noise variance, rad^2.
    pub bearing_var: f32,
    /// Share of bearings replaced by uniform ones on (-pi, pi].
    pub wild_fraction: f32,
    /// Jitter variance of the seeds' sequential filters, m^2 per step.
    pub process_var: f32,
}

/// A paper's figure for one row of a table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperFigure {
    /// The row's method.
    pub method: Method,
    /// The row's particle count, when the paper's table has several.
    pub particles: Option<usize>,
    /// The figure, with its source.
    pub text: &'static str,
}

/// Names of the canonical scenarios, in table order.
pub const NAMES: [&str; 8] = [
    "aoa-afsa",
    "aoa-firefly",
    "aoa-pf-vs-kf",
    "aoa-drive",
    "aoa-afsa-wild",
    "rssi-sim",
    "rssi-lab",
    "ungm",
];

/// A named route.
pub fn route(name: &str, emitter: [f32; 2]) -> Option<Vec<[f32; 2]>> {
    match name {
        "loop300" => Some(
            (0..c::LOOP300_POINTS)
                .map(|k| c::loop300(emitter, k))
                .collect(),
        ),
        "L600" => Some((0..c::ROUTE600_POINTS).map(c::l600).collect()),
        "line600" => Some((0..c::ROUTE600_POINTS).map(c::line600).collect()),
        _ => None,
    }
}

const fn paper(method: Method, particles: Option<usize>, text: &'static str) -> PaperFigure {
    PaperFigure {
        method,
        particles,
        text,
    }
}

/// Seed 003's table 1 (rssi-sim, 50 runs): average RMSE in metres by N and method.
const SEED_003: [PaperFigure; 12] = {
    use Method::{Gpf, GsaGpf, PsoGpf, SirSeed};
    [
        paper(SirSeed, Some(50), "seed 003: 1.2539"),
        paper(Gpf, Some(50), "seed 003: 0.6094"),
        paper(PsoGpf, Some(50), "seed 003: 0.5374"),
        paper(GsaGpf, Some(50), "seed 003: 0.4502"),
        paper(SirSeed, Some(100), "seed 003: 0.7443"),
        paper(Gpf, Some(100), "seed 003: 0.5006"),
        paper(PsoGpf, Some(100), "seed 003: 0.4515"),
        paper(GsaGpf, Some(100), "seed 003: 0.3599"),
        paper(SirSeed, Some(200), "seed 003: 0.6356"),
        paper(Gpf, Some(200), "seed 003: 0.3836"),
        paper(PsoGpf, Some(200), "seed 003: 0.3503"),
        paper(GsaGpf, Some(200), "seed 003: 0.3119"),
    ]
};

/// The methods of a bearing table without a paper of its own: the seeds' SIR and its swarms,
/// the tuned filters, the EKF and every batch fix.
const DRIVE_METHODS: [Method; 13] = {
    use Method::*;
    [
        SirSeed, Sir, SirRobust, AfsaPf, FaPfImp, Gpf, Ekf, Ple, BcPle, Wiv, Ml, MlHuber, MlRobust,
    ]
};

impl Scenario {
    /// A canonical scenario by name.
    pub fn named(name: &str) -> Option<Self> {
        use Method::*;
        let drive = |emitter: [f32; 2], var: f32, q: f32, steps: usize, r: &str| {
            let mut route = route(r, emitter)?;
            route.truncate(steps);
            Some(Drive {
                emitter,
                route,
                bearing_var: var,
                wild_fraction: 0.0,
                process_var: q,
            })
        };
        let bearing = |d: Drive, methods: &[Method], n: usize, papers: &[PaperFigure]| Scenario {
            name: name.to_string(),
            model: ScenarioModel::Bearing(d),
            methods: methods.to_vec(),
            particles: vec![n],
            baseline: Sir,
            papers: papers.to_vec(),
            runs: 100,
            seed: 1,
        };
        let tracking = |model, methods: &[Method], counts: &[usize], runs, papers: &[_]| Scenario {
            name: name.to_string(),
            model,
            methods: methods.to_vec(),
            particles: counts.to_vec(),
            baseline: SirWide,
            papers: papers.to_vec(),
            runs,
            seed: 1,
        };
        let rssi_methods = [SirSeed, SirWide, Gpf, PsoGpf, GsaGpf];
        Some(match name {
            "aoa-afsa" => bearing(
                drive(AOA_EMITTER, AOA_BEARING_VAR, 1.0, 60, "loop300")?,
                &[
                    SirSeed, Sir, SirRobust, AfsaPf, Gpf, Ekf, Ple, BcPle, Wiv, Ml, MlHuber,
                    MlRobust,
                ],
                100,
                &[
                    paper(
                        SirSeed,
                        None,
                        "seed 002 PF: rel_x 0.266 %, rel_y 0.206 %, 0.183 s",
                    ),
                    paper(
                        AfsaPf,
                        None,
                        "seed 002 AFSA-PF: rel_x 0.101 %, rel_y 0.091 %, 0.352 s",
                    ),
                ],
            ),
            "aoa-firefly" => bearing(
                drive([3000.0, 2200.0], 3.8e-4, 5.0, 40, "loop300")?,
                &[SirSeed, Sir, FaPf, FaPfImp, Gpf, Ekf, Ml, MlRobust],
                80,
                &[
                    paper(
                        SirSeed,
                        None,
                        "seed 001 PF: about 4x the improved FA-PF's error",
                    ),
                    paper(
                        FaPfImp,
                        None,
                        "seed 001 improved FA-PF: largest error 0.23 %, < 0.3 s",
                    ),
                ],
            ),
            "aoa-pf-vs-kf" => bearing(
                drive([1400.0, 600.0], 3.8018e-4, 1.0, 60, "loop300")?,
                &[SirSeed, Sir, Ekf, Ml, MlRobust],
                500,
                &[
                    paper(
                        SirSeed,
                        None,
                        "seed 004: PF (N = 500) beats the linearised KF",
                    ),
                    paper(Ekf, None, "seed 004: worse than the PF"),
                ],
            ),
            "aoa-drive" => bearing(
                drive(AOA_EMITTER, AOA_BEARING_VAR, 1.0, 60, "L600")?,
                &DRIVE_METHODS,
                100,
                &[],
            ),
            "aoa-afsa-wild" => {
                let mut d = drive(AOA_EMITTER, AOA_BEARING_VAR, 1.0, 60, "loop300")?;
                d.wild_fraction = 0.1;
                bearing(
                    d,
                    &[
                        SirSeed, Sir, SirRobust, Gpf, Ekf, Ple, Ml, MlHuber, MlRobust,
                    ],
                    100,
                    &[],
                )
            }
            "rssi-sim" => tracking(
                ScenarioModel::Rssi {
                    tracker: c::RSSI_SIM,
                    start: c::RSSI_SIM_START,
                    steps: 60,
                },
                &rssi_methods,
                &[50, 100, 200],
                50,
                &SEED_003,
            ),
            "rssi-lab" => tracking(
                ScenarioModel::Rssi {
                    tracker: c::RSSI_LAB,
                    start: c::RSSI_LAB_START,
                    steps: 30,
                },
                &rssi_methods,
                &[100],
                50,
                &[],
            ),
            "ungm" => tracking(
                ScenarioModel::Ungm { steps: 50 },
                &[SirSeed, SirWide, Gpf, FaPfImp, AfsaPf],
                &[50],
                100,
                &[
                    paper(SirSeed, None, "seed 001 PF: 3.0190"),
                    paper(FaPfImp, None, "seed 001 improved FA-PF: 1.4322"),
                ],
            ),
            _ => return None,
        })
    }

    /// Every canonical scenario, in table order.
    pub fn all() -> Vec<Scenario> {
        NAMES.iter().filter_map(|n| Scenario::named(n)).collect()
    }

    /// The drive of a bearing scenario.
    pub fn drive(&self) -> Option<&Drive> {
        match &self.model {
            ScenarioModel::Bearing(d) => Some(d),
            _ => None,
        }
    }

    /// Steps of one run: bearings of the drive, or the tracking run's length.
    pub fn steps(&self) -> usize {
        match &self.model {
            ScenarioModel::Bearing(d) => d.route.len(),
            ScenarioModel::Rssi { steps, .. } | ScenarioModel::Ungm { steps } => *steps,
        }
    }

    /// The generator of run `run`, so any row can be rerun exactly.
    pub fn rng(&self, run: usize) -> XorShiftRng {
        XorShiftRng::seed_from_u64(self.seed.wrapping_mul(1_000_003).wrapping_add(run as u64))
    }

    /// The label of its rows at `particles`: the name, with the count when the table has
    /// several.
    pub fn label(&self, particles: usize) -> String {
        if self.particles.len() > 1 {
            format!("{}/N={particles}", self.name)
        } else {
            self.name.clone()
        }
    }

    /// The paper's figure for a row, if it printed one.
    pub fn paper(&self, method: Method, particles: usize) -> Option<&'static str> {
        self.papers
            .iter()
            .find(|p| p.method == method && p.particles.is_none_or(|n| n == particles))
            .map(|p| p.text)
    }

    /// Parse a scenario file (TOML, docs/src/formats/files.md): a bearing scenario with the
    /// methods of a drive's table. Unknown keys and values no run can use are errors that name
    /// them.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let f: ScenarioFile = crate::inputs::files::parse_toml(text)?;
        let emitter: [f32; 2] = f.emitter.as_slice().try_into().map_err(|_| {
            format!(
                "`emitter` must be two numbers [east, north], not {}",
                f.emitter.len()
            )
        })?;
        let route = match (f.route, f.points) {
            (Some(_), Some(_)) => return Err("give either `route` or `points`, not both".into()),
            (Some(r), None) => route(&r, emitter).ok_or_else(|| {
                format!("unknown route `{r}`: use loop300, L600 or line600, or give `points`")
            })?,
            (None, Some(p)) => p,
            (None, None) => return Err("missing `route` (a named route) or `points`".into()),
        };
        let bearing_var = match (f.bearing_var_rad2, f.bearing_sigma_deg) {
            (Some(_), Some(_)) => {
                return Err("give either `bearing_var_rad2` or `bearing_sigma_deg`".into());
            }
            (Some(v), None) => v,
            (None, Some(d)) => {
                if !(d > 0.0 && d < 90.0) {
                    return Err(format!(
                        "`bearing_sigma_deg` must lie in (0, 90) degrees, not {d}"
                    ));
                }
                d.to_radians().powi(2)
            }
            (None, None) => AOA_BEARING_VAR,
        };
        let particles = f.particles.unwrap_or(100);
        let s = Scenario {
            name: f.name.unwrap_or_else(|| "scenario-file".into()),
            model: ScenarioModel::Bearing(Drive {
                emitter,
                route,
                bearing_var,
                wild_fraction: f.wild_fraction.unwrap_or(0.0),
                process_var: f.process_var.unwrap_or(1.0),
            }),
            methods: DRIVE_METHODS.to_vec(),
            particles: vec![particles],
            baseline: Method::Sir,
            papers: Vec::new(),
            runs: f.runs.unwrap_or(100),
            seed: f.seed.unwrap_or(1),
        };
        s.validate()?;
        Ok(s)
    }

    /// A scenario file from disk; errors name the file.
    pub fn load(path: &std::path::Path) -> Result<Self, String> {
        let text = crate::inputs::files::read_text(path)?;
        Self::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Reject values no run can use, with a message that names the key.
    pub fn validate(&self) -> Result<(), String> {
        if self.runs == 0 {
            return Err("`runs` must be at least 1".into());
        }
        if let Some(n) = self
            .particles
            .iter()
            .find(|n| !foxhunt_core::PARTICLE_COUNTS.contains(n))
        {
            return Err(format!(
                "{n} particles is not a compiled size; use one of {:?}",
                foxhunt_core::PARTICLE_COUNTS
            ));
        }
        let Some(d) = self.drive() else {
            return Ok(());
        };
        let finite = |v: f32| v.is_finite();
        if !d.emitter.iter().all(|v| finite(*v)) {
            return Err("`emitter` must be two finite numbers".into());
        }
        if d.route.len() < 2 || !d.route.iter().flatten().all(|v| finite(*v)) {
            return Err("the route needs at least two finite points".into());
        }
        let sigma = d.bearing_var.sqrt();
        if !(d.bearing_var > 0.0 && sigma < PI / 2.0) {
            return Err(format!(
                "`bearing_var_rad2` must be positive and below (pi/2)^2, not {}",
                d.bearing_var
            ));
        }
        if !(0.0..=1.0).contains(&d.wild_fraction) {
            return Err(format!(
                "`wild_fraction` must lie in [0, 1], not {}",
                d.wild_fraction
            ));
        }
        if !(d.process_var >= 0.0 && finite(d.process_var)) {
            return Err(format!(
                "`process_var` must be a finite number >= 0, not {}",
                d.process_var
            ));
        }
        Ok(())
    }
}

impl Drive {
    /// Bearing noise standard deviation, radians.
    pub fn sigma(&self) -> f32 {
        self.bearing_var.sqrt()
    }

    /// The noise-free bearings of the route (the geometry the CRLB is computed on).
    pub fn geometry(&self) -> Vec<Bearing> {
        self.route
            .iter()
            .map(|v| Bearing {
                vehicle: *v,
                theta: predicted(&self.emitter, v),
                sigma: self.sigma(),
            })
            .collect()
    }

    /// The noisy bearings of one run, with wild bearings as configured.
    pub fn simulate(&self, rng: &mut XorShiftRng) -> Vec<Bearing> {
        let sigma = self.sigma();
        self.geometry()
            .into_iter()
            .map(|mut b| {
                b.theta = if random::uniform(rng) < self.wild_fraction {
                    random::uniform_in(rng, -PI, PI)
                } else {
                    wrap(b.theta + sigma * random::normal(rng))
                };
                b
            })
            .collect()
    }
}

/// A scenario file as written (docs/src/formats/files.md).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: Option<String>,
    emitter: Vec<f32>,
    route: Option<String>,
    points: Option<Vec<[f32; 2]>>,
    bearing_var_rad2: Option<f32>,
    bearing_sigma_deg: Option<f32>,
    wild_fraction: Option<f32>,
    process_var: Option<f32>,
    particles: Option<usize>,
    runs: Option<usize>,
    seed: Option<u64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_crlb_matches_the_table() {
        // docs/src/scenarios.md prints the CRLB rmse of each scenario to 3 significant figures.
        for (name, expect) in [
            ("aoa-afsa", 1.51),
            ("aoa-firefly", 1.89),
            ("aoa-pf-vs-kf", 1.51),
            ("aoa-drive", 51.1),
        ] {
            let s = Scenario::named(name).expect("canonical");
            let d = s.drive().expect("bearing scenario");
            let c = foxhunt_core::fix::crlb::crlb(&d.emitter, &d.geometry()).expect("bound");
            assert!(
                (c.rmse - expect).abs() / expect < 0.01,
                "{name}: {}",
                c.rmse
            );
        }
    }

    #[test]
    fn every_canonical_scenario_is_valid_and_named_once() {
        let all = Scenario::all();
        assert_eq!(all.len(), NAMES.len());
        for s in &all {
            s.validate().expect("valid");
            assert!(s.methods.contains(&s.baseline) || s.drive().is_some());
            for p in &s.papers {
                assert!(s.methods.contains(&p.method), "{}: {:?}", s.name, p);
            }
        }
    }

    #[test]
    fn scenario_file_defaults_and_unknown_keys() {
        let s = Scenario::from_toml("emitter = [1200.0, 800.0]\nroute = \"loop300\"").unwrap();
        let d = s.drive().unwrap();
        assert_eq!(
            (s.particles.clone(), s.runs, s.seed, d.route.len()),
            (vec![100], 100, 1, 60)
        );
        let e =
            Scenario::from_toml("emitter = [1.0, 2.0]\nroute = \"L600\"\ncolour = 3").unwrap_err();
        assert!(e.contains("colour") && !e.contains('\n'), "{e}");
        let p = Scenario::from_toml(
            "emitter = [1.0, 2.0]\npoints = [[0.0, 0.0], [5.0, 0.0]]\nbearing_sigma_deg = 1.0",
        )
        .unwrap();
        assert_eq!(p.drive().unwrap().route.len(), 2);
        assert!((p.drive().unwrap().bearing_var - 3.046e-4).abs() < 1e-6);
        let three = Scenario::from_toml("emitter = [1.0, 2.0, 3.0]\nroute = \"L600\"").unwrap_err();
        assert!(
            three.contains("two numbers") && three.contains('3'),
            "{three}"
        );
    }
}
