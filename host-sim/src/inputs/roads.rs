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

use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use std::collections::HashMap;
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

/// Speed of a road class, m/s (used where `maxspeed` says nothing).
fn class_speed(class: &str) -> Option<f32> {
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
fn max_speed(text: &str) -> Option<f32> {
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
struct WayTags {
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

/// What the two readers hand over, element by element, whichever the format.
trait Extract {
    /// A node and where it is (as the file says: not checked).
    fn node(&mut self, id: i64, at: LatLon);
    /// A way: its nodes in order, their locations when the file carries them on the way
    /// (else empty), and its tags.
    fn way(&mut self, refs: &[i64], at: &[LatLon], tags: &mut dyn Iterator<Item = (&str, &str)>);
}

/// What an extract holds for the graph: node coordinates by id and the drivable ways.
#[derive(Debug, Default)]
struct Osm {
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
    fn graph(&self) -> Result<RoadGraph, String> {
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

/// Read the extract at `path`: `.pbf` as OSM PBF, anything else as OSM XML.
fn read_extract(path: &Path, into: &mut impl Extract) -> Result<(), String> {
    if path.to_string_lossy().ends_with(".pbf") {
        return read_pbf(path, into);
    }
    let text = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    read_xml(&text, into).map_err(|e| format!("{}: {e}", path.display()))
}

/// A tag as read from XML: key, value.
type Tag = (String, String);

/// Read OSM XML (`<node id lat lon>`, `<way><nd ref/><tag k v/></way>`).
fn read_xml(bytes: &[u8], into: &mut impl Extract) -> Result<(), String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut buf = Vec::new();
    // The way being read: its refs and tags.
    let mut way: Option<(Vec<i64>, Vec<Tag>)> = None;
    let attr = |e: &quick_xml::events::BytesStart<'_>, key: &[u8]| -> Option<String> {
        e.attributes()
            .flatten()
            .find(|a| a.key.as_ref() == key)
            .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
    };
    loop {
        let ev = reader
            .read_event_into(&mut buf)
            .map_err(|e| format!("OSM XML at byte {}: {e}", reader.buffer_position()))?;
        match &ev {
            Event::Start(e) | Event::Empty(e) => match e.name().as_ref() {
                b"node" => {
                    let id = attr(e, b"id").and_then(|v| v.parse::<i64>().ok());
                    let lat = attr(e, b"lat").and_then(|v| v.parse::<f64>().ok());
                    let lon = attr(e, b"lon").and_then(|v| v.parse::<f64>().ok());
                    if let (Some(id), Some(lat), Some(lon)) = (id, lat, lon) {
                        into.node(id, LatLon { lat, lon });
                    }
                }
                b"way" => {
                    way = Some((Vec::new(), Vec::new()));
                    if matches!(ev, Event::Empty(_)) {
                        way = None;
                    }
                }
                b"nd" => {
                    if let (Some(w), Some(r)) =
                        (way.as_mut(), attr(e, b"ref").and_then(|v| v.parse().ok()))
                    {
                        w.0.push(r);
                    }
                }
                b"tag" => {
                    if let (Some(w), Some(k), Some(v)) =
                        (way.as_mut(), attr(e, b"k"), attr(e, b"v"))
                    {
                        w.1.push((k, v));
                    }
                }
                _ => {}
            },
            Event::End(e) if e.name().as_ref() == b"way" => {
                if let Some((refs, tags)) = way.take() {
                    let mut tags = tags.iter().map(|(k, v)| (k.as_str(), v.as_str()));
                    into.way(&refs, &[], &mut tags);
                }
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    Ok(())
}

/// Read an OSM PBF extract (its errors name the file).
fn read_pbf(path: &Path, into: &mut impl Extract) -> Result<(), String> {
    use super::osm_pbf::{self, Element};
    let (mut refs, mut at) = (Vec::new(), Vec::new());
    osm_pbf::read(path, |el| match el {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn xml(bytes: &[u8]) -> Result<Osm, String> {
        let mut osm = Osm::default();
        read_xml(bytes, &mut osm)?;
        Ok(osm)
    }

    const XML: &str = r#"<?xml version="1.0"?>
<osm version="0.6">
  <node id="1" lat="47.0" lon="8.0"/>
  <node id="2" lat="47.0" lon="8.01"/>
  <node id="3" lat="47.01" lon="8.01"/>
  <node id="4" lat="47.01" lon="8.02"/>
  <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="3"/>
    <tag k="highway" v="residential"/><tag k="maxspeed" v="30 mph"/></way>
  <way id="11"><nd ref="3"/><nd ref="4"/><tag k="highway" v="primary"/><tag k="oneway" v="-1"/></way>
  <way id="12"><nd ref="1"/><nd ref="4"/><tag k="highway" v="footway"/></way>
  <way id="13"><nd ref="2"/><nd ref="99"/><tag k="highway" v="service"/></way>
</osm>"#;

    #[test]
    fn osm_xml_gives_drivable_directed_roads() {
        let g = xml(XML.as_bytes()).unwrap().graph().unwrap();
        assert_eq!(g.len(), 4);
        // 1-2, 2-3 both ways; 3-4 backwards only; the footway and the dangling service road
        // add nothing.
        assert_eq!(g.edge_count(), 5);
        let first = g.out(0);
        assert_eq!(first.len(), 1);
        // 0.01 degree of longitude at 47 N: 759 m; 30 mph.
        assert!((first[0].length_m - 759.0).abs() < 3.0, "{first:?}");
        assert!((first[0].speed - 13.41).abs() < 0.01);
        assert!(g.out(2).iter().all(|e| e.to != 3));
        assert_eq!(g.out(3).len(), 1);
        assert_eq!(g.segments().count(), 3);
        assert_eq!(g.nearest([800.0, 10.0]), Some(1));
        assert!(
            xml(b"<osm><node id='1' lat='x'/></osm>")
                .unwrap()
                .graph()
                .is_err()
        );
        assert!(xml(b"<osm><way></nd></osm>").is_err());
    }

    /// Every element as a reader gives it, to compare the two readers.
    #[derive(Debug, Default)]
    struct Everything {
        nodes: Vec<(i64, LatLon)>,
        ways: Vec<(Vec<i64>, Vec<LatLon>, Vec<Tag>)>,
    }

    impl Extract for Everything {
        fn node(&mut self, id: i64, at: LatLon) {
            self.nodes.push((id, at));
        }

        fn way(
            &mut self,
            refs: &[i64],
            at: &[LatLon],
            tags: &mut dyn Iterator<Item = (&str, &str)>,
        ) {
            let mut tags: Vec<_> = tags.map(|(k, v)| (k.into(), v.into())).collect();
            tags.sort();
            self.ways.push((refs.to_vec(), at.to_vec(), tags));
        }
    }

    fn data(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/osm")
            .join(name)
    }

    fn everything(name: &str) -> Everything {
        let mut all = Everything::default();
        read_extract(&data(name), &mut all).unwrap_or_else(|e| panic!("{e}"));
        all
    }

    /// Within 1e-7 degree: the PBF stores the XML's coordinates in steps of 100 nanodegrees
    /// (the files' granularity), so rounded by half a step at most.
    fn near(a: LatLon, b: LatLon) -> bool {
        (a.lat - b.lat).abs() < 1e-7 && (a.lon - b.lon).abs() < 1e-7
    }

    #[test]
    fn pbf_reads_as_the_xml_of_the_same_data() {
        let xml = everything("test.osm");
        assert_eq!(xml.nodes.len(), 3);
        assert_eq!(xml.ways.len(), 1);
        let xml_error = RoadGraph::load(&data("test.osm")).unwrap_err();
        // zlib and dense nodes, raw and dense, raw and plain nodes.
        for name in [
            "test.osm.pbf",
            "test_nozlib.osm.pbf",
            "test_nozlib_nodense.osm.pbf",
        ] {
            let pbf = everything(name);
            let ids = |e: &Everything| e.nodes.iter().map(|n| n.0).collect::<Vec<_>>();
            assert_eq!(ids(&pbf), ids(&xml), "{name}");
            for ((id, p), (_, x)) in pbf.nodes.iter().zip(&xml.nodes) {
                assert!(near(*p, *x), "{name}: node {id} at {p:?}, XML {x:?}");
            }
            assert_eq!(pbf.ways, xml.ways, "{name}");
            // No road in either (the way is a building): the same graph, none, the same words.
            let pbf_error = RoadGraph::load(&data(name)).unwrap_err();
            assert_eq!(
                pbf_error.replace(name, "FILE"),
                xml_error.replace("test.osm", "FILE")
            );
        }
    }

    #[test]
    fn locations_on_ways_stand_for_the_missing_nodes() {
        let xml = everything("test.osm");
        let pbf = everything("loc_on_ways.osm.pbf");
        assert!(pbf.nodes.is_empty(), "{:?}", pbf.nodes);
        let [(refs, at, tags)] = &pbf.ways[..] else {
            panic!("one way: {:?}", pbf.ways)
        };
        assert_eq!((refs, tags), (&xml.ways[0].0, &xml.ways[0].2));
        assert_eq!(at.len(), refs.len());
        for (id, p) in refs.iter().zip(at) {
            let x = xml
                .nodes
                .iter()
                .find(|n| n.0 == *id)
                .expect("the XML's node")
                .1;
            assert!(near(*p, x), "node {id} at {p:?}, XML {x:?}");
        }
        // A drivable way so written makes its graph from those locations alone.
        let mut osm = Osm::default();
        osm.way(refs, at, &mut [("highway", "residential")].into_iter());
        let g = osm.graph().unwrap();
        assert_eq!((g.len(), g.edge_count()), (3, 6));
        assert!(near(g.geodetic(0).unwrap(), at[0]));
    }

    #[test]
    fn history_files_are_refused() {
        let e = RoadGraph::load(&data("deleted_nodes.osh.pbf")).unwrap_err();
        assert!(
            e.contains("deleted_nodes.osh.pbf") && e.contains("history") && !e.contains('\n'),
            "{e}"
        );
    }

    #[test]
    fn speeds_parse() {
        assert_eq!(max_speed("50"), Some(50.0 / 3.6));
        assert!((max_speed("30 mph").unwrap() - 13.41).abs() < 0.01);
        assert_eq!(max_speed("none"), None);
        assert!(class_speed("motorway_link").is_some() && class_speed("footway").is_none());
    }
}
