use super::extract::Extract;
use super::osm::*;
use super::osm_xml::{MarkupRuns, Tag, read_xml};
use super::*;
use std::io::Read;

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
fn a_tag_that_never_closes_is_refused_before_it_fills_memory() {
    for endless in [b'<', b'a'] {
        let text = Read::chain(&b"<osm><node "[..], std::io::repeat(endless));
        let reader = std::io::BufReader::new(MarkupRuns::new(text));
        let e = read_xml(reader, &mut Osm::default()).expect_err("endless");
        assert!(e.contains("not OSM XML (a tag"), "{e}");
    }
}

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

    fn way(&mut self, refs: &[i64], at: &[LatLon], tags: &mut dyn Iterator<Item = (&str, &str)>) {
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
