//! The `foxhunt` subcommands: each one's options (clap) and the orchestration that reads its
//! inputs, calls the library and writes its outputs. `main.rs` only dispatches here.

pub mod bench;
pub mod frames;
pub mod locate;
pub mod perf;
pub mod serve;
pub mod simulate;
pub mod track;

use crate::guidance::guide::Guide;
use crate::inputs::roads::RoadGraph;
use foxhunt_core::Method;
use foxhunt_core::guidance::stop::StopRule;

/// Parse a method name of the registry (clap value parser).
pub fn method(name: &str) -> Result<Method, String> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown method `{name}`; known: {}", names.join(", "))
    })
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
    #[arg(long, value_name = "M", default_value_t = StopRule::default().target_cep50_m)]
    pub target_cep50_m: f32,
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
