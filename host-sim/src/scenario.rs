//! The canonical scenarios of SCENARIOS.md by name, and scenario files a user writes.

use foxhunt_core::random;
use foxhunt_core::{Bearing, model::bearing::predicted};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Deserialize;
use std::f32::consts::PI;

/// A bearing-only static-emitter scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name printed in reports.
    pub name: String,
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
    /// Particles for the sequential filters.
    pub particles: usize,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed; run r uses seed * 1_000_003 + r.
    pub seed: u64,
    /// Which seed paper the scenario reproduces, if any.
    pub paper: Option<Paper>,
}

/// The source paper a scenario reproduces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Paper {
    /// Seed 001: firefly PF.
    Firefly,
    /// Seed 002: artificial fish swarm PF.
    Afsa,
    /// Seed 004: PF versus Kalman filter.
    PfVsKf,
}

/// Names of the canonical bearing scenarios.
pub const NAMES: [&str; 5] = [
    "aoa-afsa",
    "aoa-firefly",
    "aoa-pf-vs-kf",
    "aoa-drive",
    "aoa-afsa-wild",
];

/// A named route.
pub fn route(name: &str, emitter: [f32; 2]) -> Option<Vec<[f32; 2]>> {
    match name {
        "loop300" => {
            // 60 points on a 300 m circle about the emitter, from the point nearest the origin,
            // counter-clockwise.
            let start = libm::atan2f(-emitter[1], -emitter[0]);
            Some(
                (0..60)
                    .map(|k| {
                        let a = start + 2.0 * PI * k as f32 / 60.0;
                        [emitter[0] + 300.0 * a.cos(), emitter[1] + 300.0 * a.sin()]
                    })
                    .collect(),
            )
        }
        "L600" => Some(
            (0..30)
                .map(|k| [10.0 * k as f32, 0.0])
                .chain((1..=30).map(|k| [290.0, 10.0 * k as f32]))
                .collect(),
        ),
        "line600" => Some((0..60).map(|k| [10.0 * k as f32, 0.0]).collect()),
        _ => None,
    }
}

impl Scenario {
    /// A canonical scenario by name.
    pub fn named(name: &str) -> Option<Self> {
        let base = |emitter: [f32; 2], var: f32, q: f32, n: usize, steps: usize, r: &str| {
            let mut route = route(r, emitter)?;
            route.truncate(steps);
            Some(Scenario {
                name: name.to_string(),
                emitter,
                route,
                bearing_var: var,
                wild_fraction: 0.0,
                process_var: q,
                particles: n,
                runs: 100,
                seed: 1,
                paper: None,
            })
        };
        let mut s = match name {
            "aoa-afsa" => base([1200.0, 800.0], 3.801e-4, 1.0, 100, 60, "loop300")?,
            "aoa-firefly" => base([3000.0, 2200.0], 3.8e-4, 5.0, 80, 40, "loop300")?,
            "aoa-pf-vs-kf" => base([1400.0, 600.0], 3.8018e-4, 1.0, 500, 60, "loop300")?,
            "aoa-drive" => base([1200.0, 800.0], 3.801e-4, 1.0, 100, 60, "L600")?,
            "aoa-afsa-wild" => {
                let mut s = base([1200.0, 800.0], 3.801e-4, 1.0, 100, 60, "loop300")?;
                s.wild_fraction = 0.1;
                s
            }
            _ => return None,
        };
        s.paper = match name {
            "aoa-afsa" => Some(Paper::Afsa),
            "aoa-firefly" => Some(Paper::Firefly),
            "aoa-pf-vs-kf" => Some(Paper::PfVsKf),
            _ => None,
        };
        Some(s)
    }

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

    /// The generator of run `run`, so any row can be rerun exactly.
    pub fn rng(&self, run: usize) -> XorShiftRng {
        XorShiftRng::seed_from_u64(self.seed.wrapping_mul(1_000_003).wrapping_add(run as u64))
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
                    foxhunt_core::model::bearing::wrap(b.theta + sigma * random::normal(rng))
                };
                b
            })
            .collect()
    }

    /// Parse a scenario file (TOML, format of SCENARIOS.md). Unknown keys are an error that
    /// names them.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let f: ScenarioFile = toml::from_str(text).map_err(|e| e.to_string())?;
        let route = match (f.route, f.points) {
            (Some(_), Some(_)) => return Err("give either `route` or `points`, not both".into()),
            (Some(r), None) => route(&r, f.emitter).ok_or_else(|| {
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
            (None, Some(d)) => (d.to_radians()).powi(2),
            (None, None) => 3.801e-4,
        };
        let s = Scenario {
            name: f.name.unwrap_or_else(|| "scenario-file".into()),
            emitter: f.emitter,
            route,
            bearing_var,
            wild_fraction: f.wild_fraction.unwrap_or(0.0),
            process_var: f.process_var.unwrap_or(1.0),
            particles: f.particles.unwrap_or(100),
            runs: f.runs.unwrap_or(100),
            seed: f.seed.unwrap_or(1),
            paper: None,
        };
        s.validate()?;
        Ok(s)
    }

    /// Reject values no run can use, with a message that names the key.
    pub fn validate(&self) -> Result<(), String> {
        let finite = |v: f32| v.is_finite();
        if !self.emitter.iter().all(|v| finite(*v)) {
            return Err("`emitter` must be two finite numbers".into());
        }
        if self.route.len() < 2 || !self.route.iter().flatten().all(|v| finite(*v)) {
            return Err("the route needs at least two finite points".into());
        }
        if !(self.bearing_var > 0.0 && finite(self.bearing_var)) {
            return Err("`bearing_var_rad2` must be positive".into());
        }
        if !(0.0..=1.0).contains(&self.wild_fraction) {
            return Err("`wild_fraction` must lie in [0, 1]".into());
        }
        if !(self.process_var >= 0.0 && finite(self.process_var)) {
            return Err("`process_var` must be >= 0".into());
        }
        if self.runs == 0 {
            return Err("`runs` must be at least 1".into());
        }
        Ok(())
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: Option<String>,
    emitter: [f32; 2],
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
        // SCENARIOS.md prints the CRLB rmse of each scenario to 3 significant figures.
        for (name, expect) in [
            ("aoa-afsa", 1.51),
            ("aoa-firefly", 1.89),
            ("aoa-pf-vs-kf", 1.51),
            ("aoa-drive", 51.1),
        ] {
            let s = Scenario::named(name).unwrap();
            let c = foxhunt_core::fix::crlb::crlb(&s.emitter, &s.geometry()).unwrap();
            assert!(
                (c.rmse - expect).abs() / expect < 0.01,
                "{name}: {}",
                c.rmse
            );
        }
    }

    #[test]
    fn scenario_file_defaults_and_unknown_keys() {
        let s = Scenario::from_toml("emitter = [1200.0, 800.0]\nroute = \"loop300\"").unwrap();
        assert_eq!(
            (s.particles, s.runs, s.seed, s.route.len()),
            (100, 100, 1, 60)
        );
        let e =
            Scenario::from_toml("emitter = [1.0, 2.0]\nroute = \"L600\"\ncolour = 3").unwrap_err();
        assert!(e.contains("colour"), "{e}");
        let p = Scenario::from_toml(
            "emitter = [1.0, 2.0]\npoints = [[0.0, 0.0], [5.0, 0.0]]\nbearing_sigma_deg = 1.0",
        )
        .unwrap();
        assert_eq!(p.route.len(), 2);
        assert!((p.bearing_var - 3.046e-4).abs() < 1e-6);
    }
}
