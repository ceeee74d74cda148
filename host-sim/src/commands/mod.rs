//! The `foxhunt` subcommands: each one's options (clap) and the orchestration that reads its
//! inputs, calls the library and writes its outputs. `main.rs` only dispatches here.

pub mod bench;
pub mod frames;
pub mod history;
pub mod locate;
pub mod perf;
pub mod publish;
pub mod serve;
pub mod simulate;
pub mod track;
pub mod values;

use crate::guidance::guide::Guide;
use crate::inputs::roads::RoadGraph;
use crate::inputs::stations::{Network, parse_reference};
use crate::runs::field::Condition;
use crate::runs::guidance::bench::Set;
use crate::runs::scenario::NAMES;
use clap::builder::TypedValueParser;
use foxhunt_core::Method;
use foxhunt_core::guidance::stop::StopRule;

/// The registry's methods as clap values: `--help` lists them, and an unknown name is a usage
/// error (exit status 2) that lists them too.
pub fn method() -> impl clap::builder::TypedValueParser<Value = Method> {
    clap::builder::PossibleValuesParser::new(Method::ALL.map(|m| m.name()))
        .try_map(|name| Method::from_name(&name).ok_or(format!("unknown method `{name}`")))
}

/// Every name `foxhunt bench --scenario` takes: the canonical scenarios, `all`, the field
/// conditions (`field`, `field/NAME`), the small-sample table (`small-n`) and the guidance
/// sets (`guidance`, `guidance/SET`).
pub fn bench_scenarios() -> Vec<String> {
    let mut names: Vec<String> = NAMES.iter().map(|n| n.to_string()).collect();
    names.push("all".into());
    names.push("field".into());
    names.extend(Condition::ALL.iter().map(|c| format!("field/{}", c.name())));
    names.push("network".into());
    names.extend(
        crate::runs::network::NetworkCondition::ALL
            .iter()
            .map(|c| format!("network/{}", c.short_name())),
    );
    names.push("small-n".into());
    names.push("moving".into());
    names.extend(
        crate::runs::moving::NAMES
            .iter()
            .map(|n| format!("moving/{n}")),
    );
    names.push("guidance".into());
    names.extend(Set::all().iter().map(|s| s.name()));
    names.push("guidance/plot".into());
    names
}

/// `values` as a clap value parser that lists them in `--help` and in its usage error.
pub fn one_of(values: Vec<String>) -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        values
            .into_iter()
            .map(|v| clap::builder::PossibleValue::new(clap::builder::Str::from(v))),
    )
}

/// Drive guidance's options, shared by `locate` and `serve` (flattened into both).
#[derive(Debug, Clone, clap::Args)]
pub struct GuidanceArgs {
    /// An OpenStreetMap extract (.osm.pbf or OSM XML): the advice becomes the next road turn
    /// and the point to drive to (and `serve` draws the roads as its basemap). Without it the
    /// advice is a free heading, as in open terrain.
    #[arg(long, value_name = "FILE")]
    pub roads: Option<std::path::PathBuf>,
    /// The stop rule's target: "good enough" once the fix's CEP50 and the bias-aware bound's
    /// are below this many metres, with consistent residuals and enough independent bearings.
    #[arg(long, value_name = "M", default_value_t = StopRule::default().target_cep50_m,
          value_parser = values::f32_where(|m| m > 0.0 && m.is_finite(), "a number of metres > 0"))]
    pub target_cep50_m: f32,
}

/// A network's description, shared by `locate` and `serve` (flattened into both): the map
/// and the fix take the same stations and references.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct NetworkArgs {
    /// A stations file (TOML): each DF station's id, surveyed position, offset prior or
    /// calibration, noise and antenna, and reference transmitters (docs/src/networks.md).
    #[arg(long, value_name = "FILE")]
    pub stations: Option<std::path::PathBuf>,
    /// A reference transmitter at LAT,LON on MHZ (repeatable): its channel's bearings
    /// calibrate every station that hears it.
    #[arg(long, value_name = "LAT,LON@MHZ", allow_hyphen_values = true)]
    pub reference: Vec<String>,
}

impl NetworkArgs {
    /// The network these options describe, if any (the file read and checked whole).
    pub fn network(&self) -> Result<Option<std::sync::Arc<Network>>, String> {
        if self.stations.is_none() && self.reference.is_empty() {
            return Ok(None);
        }
        let mut n = match &self.stations {
            Some(path) => Network::load(path)?,
            None => Network::default(),
        };
        for r in &self.reference {
            n.add_reference(parse_reference(r)?)?;
        }
        Ok(Some(std::sync::Arc::new(n)))
    }
}

impl GuidanceArgs {
    /// The guide these options ask for: the extract read (an unreadable one is the command's
    /// error), the target checked.
    pub fn guide(&self) -> Result<Guide, String> {
        // The target first: a bad number should not wait for a large extract to load.
        Guide::new(None, self.target_cep50_m)?;
        let roads = self.roads.as_deref().map(RoadGraph::load).transpose()?;
        Guide::new(roads, self.target_cep50_m)
    }
}
