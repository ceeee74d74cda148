//! What an extract holds for the graph, whichever its format: the ways a car drives on (their
//! class, `maxspeed`, `oneway`) and their nodes, and the graph built from them.

use super::extract::Extract;
use super::osm_xml::{MarkupRuns, read_xml};
use super::{RoadGraph, Segment};
use crate::inputs::files::{ROADS_CAP, open_capped};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Speed of a road class, m/s (used where `maxspeed` says nothing).
pub(super) fn class_speed(class: &str) -> Option<f32> {
    let kmh = match class.trim_end_matches("_link") {
        "motorway" => 110.0,
        "trunk" => 90.0,
        "primary" => 70.0,
        "secondary" => 60.0,
        "tertiary" => 50.0,
        "unclassified" | "road" => 40.0,
        "residential" => 30.0,
        "living_street" => 10.0,
        "service" => 20.0,
        _ => return None,
    };
    Some(kmh / 3.6)
}

/// `maxspeed` in m/s: "50", "50 km/h", "30 mph".
pub(super) fn max_speed(text: &str) -> Option<f32> {
    let t = text.trim();
    let (number, factor) = match t.strip_suffix("mph") {
        Some(n) => (n, 1.609_344 / 3.6),
        None => (t.trim_end_matches("km/h"), 1.0 / 3.6),
    };
    number
        .trim()
        .parse::<f32>()
        .ok()
        .filter(|v| *v > 0.0 && v.is_finite())
        .map(|v| v * factor)
}

/// A way's tags that matter.
#[derive(Debug, Default, Clone)]
pub(super) struct WayTags {
    highway: Option<String>,
    oneway: Option<String>,
    maxspeed: Option<String>,
}

impl WayTags {
    fn set(&mut self, k: &str, v: &str) {
        match k {
            "highway" => self.highway = Some(v.to_string()),
            "oneway" => self.oneway = Some(v.to_string()),
            "maxspeed" => self.maxspeed = Some(v.to_string()),
            _ => {}
        }
    }

    /// (speed, direction: 1 forward only, -1 backward only, 0 both) for a drivable way.
    fn drivable(&self) -> Option<(f32, i8)> {
        let class = self.highway.as_deref()?;
        let default = class_speed(class)?;
        let speed = self
            .maxspeed
            .as_deref()
            .and_then(max_speed)
            .unwrap_or(default);
        let dir = match self.oneway.as_deref() {
            Some("yes" | "true" | "1") => 1,
            Some("-1" | "reverse") => -1,
            Some("no" | "false" | "0") => 0,
            _ if class == "motorway" => 1,
            _ => 0,
        };
        Some((speed, dir))
    }
}

/// What an extract holds for the graph: node coordinates by id and the drivable ways.
#[derive(Debug, Default)]
pub(super) struct Osm {
    nodes: HashMap<i64, LatLon>,
    ways: Vec<(Vec<i64>, f32, i8)>,
}

impl Extract for Osm {
    /// Nodes off the globe are dropped (their ways end there).
    fn node(&mut self, id: i64, at: LatLon) {
        if at.lat.abs() <= 90.0 && at.lon.abs() <= 180.0 {
            self.nodes.insert(id, at);
        }
    }

    fn way(&mut self, refs: &[i64], at: &[LatLon], tags: &mut dyn Iterator<Item = (&str, &str)>) {
        let mut kept = WayTags::default();
        for (k, v) in tags {
            kept.set(k, v);
        }
        if let Some((speed, dir)) = kept.drivable()
            && refs.len() >= 2
        {
            for (id, ll) in refs.iter().zip(at) {
                self.node(*id, *ll);
            }
            self.ways.push((refs.to_vec(), speed, dir));
        }
    }
}

impl Osm {
    /// The graph of the ways, their nodes numbered in order of first use; nodes a way names
    /// but the extract lacks end that way's run there.
    pub(super) fn graph(&self) -> Result<RoadGraph, String> {
        let mut index: HashMap<i64, u32> = HashMap::new();
        let mut geodetic: Vec<LatLon> = Vec::new();
        let mut segments: Vec<Segment> = Vec::new();
        for (refs, speed, dir) in &self.ways {
            let mut last: Option<u32> = None;
            for id in refs {
                let Some(ll) = self.nodes.get(id) else {
                    last = None;
                    continue;
                };
                let n = *index.entry(*id).or_insert_with(|| {
                    geodetic.push(*ll);
                    (geodetic.len() - 1) as u32
                });
                if let Some(p) = last {
                    match dir {
                        1 => segments.push((p, n, *speed, false)),
                        -1 => segments.push((n, p, *speed, false)),
                        _ => segments.push((p, n, *speed, true)),
                    }
                }
                last = Some(n);
            }
        }
        let Some(first) = geodetic.first() else {
            return Err("no drivable road (highway=...) in the extract".into());
        };
        let frame = LocalFrame::new(*first, 0.0).map_err(|e| format!("bad coordinates: {e:?}"))?;
        let positions: Vec<[f32; 2]> = geodetic
            .iter()
            .map(|g| {
                frame
                    .to_local(*g)
                    .map(|p| [p[0] as f32, p[1] as f32])
                    .unwrap_or([f32::NAN; 2])
            })
            .collect();
        let mut g = RoadGraph::new(positions, &segments);
        g.geodetic = geodetic;
        Ok(g)
    }
}

/// Read the extract at `path`: `.pbf` as OSM PBF, anything else as OSM XML, streamed (at most
/// [`ROADS_CAP`] bytes of it; what is not a file or a pipe is refused before reading).
pub(super) fn read_extract(path: &Path, into: &mut impl Extract) -> Result<(), String> {
    let file = open_capped(path, ROADS_CAP, "a road extract")?;
    if path.to_string_lossy().ends_with(".pbf") {
        return read_pbf(file, path, into);
    }
    read_xml(std::io::BufReader::new(MarkupRuns::new(file)), into)
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Read an OSM PBF extract from `file`, the one at `path` (its errors name the file).
pub(super) fn read_pbf(
    file: impl Read,
    path: &Path,
    into: &mut impl Extract,
) -> Result<(), String> {
    use crate::inputs::osm_pbf::{Element, PbfReader};
    let (mut refs, mut at) = (Vec::new(), Vec::new());
    let reader = PbfReader::new(std::io::BufReader::new(file), path.display().to_string());
    reader
        .read_all(|el| match el {
            Element::Node(n) => into.node(
                n.id,
                LatLon {
                    lat: n.lat,
                    lon: n.lon,
                },
            ),
            Element::Way(w) => {
                refs.clear();
                refs.extend(w.refs());
                at.clear();
                at.extend(w.locations().map(|(lat, lon)| LatLon { lat, lon }));
                into.way(&refs, &at, &mut w.tags());
            }
        })
        .map_err(|e| e.to_string())
}
