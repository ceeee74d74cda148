//! The road network guidance drives on: read once per area from an OpenStreetMap extract
//! (`.osm.pbf` through [`super::osm_pbf`], or OSM XML through quick-xml), kept as a compact
//! graph (compressed adjacency: one offset per node, 12 bytes per directed edge), placed in
//! the drive's local frame when the drive's origin is known.
//!
//! Only ways a car drives on are kept (`highway` = motorway ... residential, service, the
//! `_link`s, living_street, unclassified, road); `oneway` is honoured (motorways are one way
//! unless tagged otherwise, `oneway=-1` runs backwards). Speeds come from `maxspeed` where it
//! parses (km/h or mph) and from the road class otherwise. Every OSM node of a kept way is a
//! graph node (no chains contracted), so a curved road is its polyline.

mod extract;
mod osm;
mod osm_xml;
#[cfg(test)]
mod tests;

use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use osm::{Osm, read_extract};
use std::path::Path;

/// One directed road segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// The node it leads to.
    pub to: u32,
    /// Length, metres.
    pub length_m: f32,
    /// Speed driven on it, m/s.
    pub speed: f32,
}

/// A road network: nodes in local metres (and latitude/longitude when read from OSM) and the
/// directed edges out of each.
#[derive(Debug, Clone, Default)]
pub struct RoadGraph {
    positions: Vec<[f32; 2]>,
    geodetic: Vec<LatLon>,
    first: Vec<u32>,
    edges: Vec<Edge>,
}

/// A road between two nodes as it is built: (from, to, speed m/s, both ways).
pub type Segment = (u32, u32, f32, bool);

impl RoadGraph {
    /// A graph of `positions` (local metres) and `segments`; segments naming a missing node,
    /// joining a node to itself or with a bad speed are dropped.
    pub fn new(positions: Vec<[f32; 2]>, segments: &[Segment]) -> Self {
        let n = positions.len();
        let mut directed: Vec<(u32, Edge)> = Vec::with_capacity(2 * segments.len());
        for &(a, b, speed, both) in segments {
            let (Some(pa), Some(pb)) = (positions.get(a as usize), positions.get(b as usize))
            else {
                continue;
            };
            let length_m = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            if a == b || !(speed > 0.0) || !length_m.is_finite() || !(length_m > 0.0) {
                continue;
            }
            directed.push((
                a,
                Edge {
                    to: b,
                    length_m,
                    speed,
                },
            ));
            if both {
                directed.push((
                    b,
                    Edge {
                        to: a,
                        length_m,
                        speed,
                    },
                ));
            }
        }
        directed.sort_by_key(|(from, e)| (*from, e.to));
        directed.dedup_by_key(|(from, e)| (*from, e.to));
        let mut first = vec![0u32; n + 1];
        for (from, _) in &directed {
            first[*from as usize + 1] += 1;
        }
        for i in 0..n {
            first[i + 1] += first[i];
        }
        Self {
            positions,
            geodetic: Vec::new(),
            first,
            edges: directed.into_iter().map(|(_, e)| e).collect(),
        }
    }

    /// Nodes.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// No node at all.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Directed edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Position of node `n`, local metres.
    pub fn position(&self, n: u32) -> Option<[f32; 2]> {
        self.positions.get(n as usize).copied()
    }

    /// Latitude and longitude of node `n` (graphs read from OSM).
    pub fn geodetic(&self, n: u32) -> Option<LatLon> {
        self.geodetic.get(n as usize).copied()
    }

    /// The edges out of node `n`.
    pub fn out(&self, n: u32) -> &[Edge] {
        let (Some(a), Some(b)) = (self.first.get(n as usize), self.first.get(n as usize + 1))
        else {
            return &[];
        };
        self.edges.get(*a as usize..*b as usize).unwrap_or(&[])
    }

    /// Every road once (an undirected pair once), as node pairs: what a map draws.
    pub fn segments(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.len() as u32).flat_map(move |a| {
            self.out(a).iter().filter_map(move |e| {
                let back = self.out(e.to).iter().any(|r| r.to == a);
                (!back || a < e.to).then_some((a, e.to))
            })
        })
    }

    /// The node nearest `p` (O(n)), if any.
    pub fn nearest(&self, p: [f32; 2]) -> Option<u32> {
        self.positions
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.out(*i as u32).is_empty())
            .map(|(i, q)| (i, (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i as u32)
    }

    /// The road nearest `p` (O(edges)): its two nodes, if any.
    pub fn nearest_segment(&self, p: [f32; 2]) -> Option<(u32, u32)> {
        let distance_sq = |a: [f32; 2], b: [f32; 2]| {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len_sq = dx * dx + dy * dy;
            let t = if len_sq > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len_sq).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a[0] + t * dx - p[0]).powi(2) + (a[1] + t * dy - p[1]).powi(2)
        };
        self.segments()
            .filter_map(|(a, b)| Some(((a, b), distance_sq(self.position(a)?, self.position(b)?))))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(s, _)| s)
    }

    /// The same roads placed in `frame` (graphs read from OSM).
    pub fn localise(&mut self, frame: &LocalFrame) {
        for (p, g) in self.positions.iter_mut().zip(&self.geodetic) {
            if let Ok(en) = frame.to_local(*g) {
                *p = [en[0] as f32, en[1] as f32];
            }
        }
        for a in 0..self.positions.len() {
            let pa = self.positions[a];
            let (s, e) = (self.first[a] as usize, self.first[a + 1] as usize);
            for k in s..e {
                let pb = self.positions[self.edges[k].to as usize];
                self.edges[k].length_m = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            }
        }
    }

    /// Read an extract: `.pbf` as OSM PBF, anything else as OSM XML. Nodes are placed in a
    /// frame at the extract's first kept node until [`RoadGraph::localise`] moves them.
    pub fn load(path: &Path) -> Result<Self, String> {
        let mut osm = Osm::default();
        read_extract(path, &mut osm)?;
        osm.graph().map_err(|e| format!("{}: {e}", path.display()))
    }
}
