//! The OSM PBF reader: files written here (dense and plain nodes, zlib and raw blobs, offset
//! grids) read back exactly; the street grid as PBF gives the graph and the `locate` report its
//! XML gives; and malformed files, random or corrupted, give one typed line each, never a
//! panic, with memory bounded by what the file holds (not by what its length fields claim).

use foxhunt_sim::inputs::osm_pbf::{
    self, Element, MAX_BLOB, PbfError, PbfReader, Problem, WireError,
};
use foxhunt_sim::inputs::roads::RoadGraph;
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::grid_osm;

/// Bytes allocated by the calling thread, to bound what a read takes.
mod counting {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        static NOW: Cell<usize> = const { Cell::new(0) };
        static PEAK: Cell<usize> = const { Cell::new(0) };
    }

    fn grew(n: usize) {
        let _ = NOW.try_with(|now| {
            let v = now.get() + n;
            now.set(v);
            let _ = PEAK.try_with(|p| p.set(p.get().max(v)));
        });
    }

    fn shrank(n: usize) {
        // A block freed by another thread than its own may take the count under 0.
        let _ = NOW.try_with(|now| now.set(now.get().saturating_sub(n)));
    }

    /// The system allocator, counting each thread's bytes.
    pub struct Counting;

    // A global allocator is unsafe by its trait; this one only counts and hands on.
    #[allow(unsafe_code)]
    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            let p = unsafe { System.alloc(layout) };
            if !p.is_null() {
                grew(layout.size());
            }
            p
        }

        unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
            let p = unsafe { System.alloc_zeroed(layout) };
            if !p.is_null() {
                grew(layout.size());
            }
            p
        }

        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            unsafe { System.dealloc(ptr, layout) };
            shrank(layout.size());
        }

        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            let p = unsafe { System.realloc(ptr, layout, new_size) };
            if !p.is_null() {
                shrank(layout.size());
                grew(new_size);
            }
            p
        }
    }

    /// `f`'s result and the most bytes this thread held at once during it, over what it
    /// held before.
    pub fn peak<T>(f: impl FnOnce() -> T) -> (T, usize) {
        let base = NOW.with(Cell::get);
        PEAK.with(|p| p.set(base));
        let r = f();
        (r, PEAK.with(Cell::get).saturating_sub(base))
    }
}

#[global_allocator]
static ALLOCATOR: counting::Counting = counting::Counting;

/// Tags as the tests hold them.
type Tags = Vec<(String, String)>;

/// What a test writes and reads back: nodes (id, latitude, longitude, tags), ways (id, refs,
/// tags).
#[derive(Debug, Clone, Default, PartialEq)]
struct Osm {
    nodes: Vec<(i64, f64, f64, Tags)>,
    ways: Vec<(i64, Vec<i64>, Tags)>,
}

/// How it is written: elements per block, the coordinate grid. Blocks take turns at zlib and
/// raw, and node blocks at dense and plain, so four node blocks hold every combination.
#[derive(Debug, Clone, Copy)]
struct Layout {
    per_block: usize,
    granularity: i64,
    lat_offset: i64,
    lon_offset: i64,
}

impl Default for Layout {
    fn default() -> Self {
        Self {
            per_block: 8000,
            granularity: 100,
            lat_offset: 0,
            lon_offset: 0,
        }
    }
}

/// The protobuf wire format, written.
mod pb {
    pub fn varint(out: &mut Vec<u8>, mut v: u64) {
        while v >= 0x80 {
            out.push(v as u8 | 0x80);
            v >>= 7;
        }
        out.push(v as u8);
    }

    pub fn zigzag(v: i64) -> u64 {
        ((v << 1) ^ (v >> 63)) as u64
    }

    pub fn int(out: &mut Vec<u8>, field: u32, v: u64) {
        varint(out, u64::from(field) << 3);
        varint(out, v);
    }

    pub fn bytes(out: &mut Vec<u8>, field: u32, b: &[u8]) {
        varint(out, u64::from(field) << 3 | 2);
        varint(out, b.len() as u64);
        out.extend_from_slice(b);
    }

    pub fn packed(values: impl IntoIterator<Item = u64>) -> Vec<u8> {
        let mut out = Vec::new();
        for v in values {
            varint(&mut out, v);
        }
        out
    }

    /// Delta-coded, zigzagged.
    pub fn deltas(values: impl IntoIterator<Item = i64>) -> Vec<u8> {
        let mut last = 0;
        packed(values.into_iter().map(|v| {
            let d = zigzag(v - last);
            last = v;
            d
        }))
    }
}

/// A blob of `kind` holding `data`, zlib-compressed or raw, with its header and length.
fn blob(out: &mut Vec<u8>, kind: &str, data: &[u8], zlib: bool) {
    use std::io::Write;
    let mut body = Vec::new();
    if zlib {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(data).expect("compress");
        pb::int(&mut body, 2, data.len() as u64);
        pb::bytes(&mut body, 3, &z.finish().expect("compress"));
    } else {
        pb::bytes(&mut body, 1, data);
    }
    let mut header = Vec::new();
    pb::bytes(&mut header, 1, kind.as_bytes());
    pb::int(&mut header, 3, body.len() as u64);
    out.extend_from_slice(&(header.len() as u32).to_be_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&body);
}

/// A block's string table as it is filled.
#[derive(Default)]
struct Strings(Vec<String>);

impl Strings {
    fn index(&mut self, s: &str) -> u64 {
        if self.0.is_empty() {
            self.0.push(String::new());
        }
        let i = self.0.iter().position(|t| t == s).unwrap_or_else(|| {
            self.0.push(s.to_string());
            self.0.len() - 1
        });
        i as u64
    }

    fn keys_vals(&mut self, tags: &Tags) -> (Vec<u8>, Vec<u8>) {
        let (k, v): (Vec<u64>, Vec<u64>) = tags
            .iter()
            .map(|(k, v)| (self.index(k), self.index(v)))
            .unzip();
        (pb::packed(k), pb::packed(v))
    }
}

/// A PrimitiveBlock of one group: the string table first, the grid after the group (as a
/// writer may), and two unknown fields (fixed64, fixed32) the reader must skip.
fn block(strings: &Strings, group: &[u8], layout: Layout) -> Vec<u8> {
    let mut table = Vec::new();
    for s in &strings.0 {
        pb::bytes(&mut table, 1, s.as_bytes());
    }
    let mut b = Vec::new();
    pb::bytes(&mut b, 1, &table);
    pb::bytes(&mut b, 2, group);
    pb::varint(&mut b, 99 << 3 | 1);
    b.extend_from_slice(&[1, 2, 3, 4, 5, 6, 7, 8]);
    pb::varint(&mut b, 98 << 3 | 5);
    b.extend_from_slice(&[1, 2, 3, 4]);
    pb::int(&mut b, 17, layout.granularity as u64);
    pb::int(&mut b, 19, layout.lat_offset as u64);
    pb::int(&mut b, 20, layout.lon_offset as u64);
    b
}

/// `osm` as a PBF file laid out as `layout` says, with a blob of an unknown type among the
/// data (which the reader skips).
fn write_pbf(osm: &Osm, layout: Layout) -> Vec<u8> {
    let mut out = Vec::new();
    let mut header = Vec::new();
    pb::bytes(&mut header, 4, b"OsmSchema-V0.6");
    pb::bytes(&mut header, 4, b"DenseNodes");
    pb::bytes(&mut header, 16, b"foxhunt tests");
    blob(&mut out, "OSMHeader", &header, false);
    blob(&mut out, "FoxhuntNote", b"skipped", true);
    let stored = |deg: f64, offset: i64| {
        ((deg * 1e9 - offset as f64) / layout.granularity as f64).round() as i64
    };
    let mut k = 0;
    for chunk in osm.nodes.chunks(layout.per_block) {
        let mut strings = Strings::default();
        let mut group = Vec::new();
        if k / 2 % 2 == 0 {
            let mut dense = Vec::new();
            pb::bytes(&mut dense, 1, &pb::deltas(chunk.iter().map(|n| n.0)));
            pb::bytes(
                &mut dense,
                8,
                &pb::deltas(chunk.iter().map(|n| stored(n.1, layout.lat_offset))),
            );
            pb::bytes(
                &mut dense,
                9,
                &pb::deltas(chunk.iter().map(|n| stored(n.2, layout.lon_offset))),
            );
            if chunk.iter().any(|n| !n.3.is_empty()) {
                let mut kv = Vec::new();
                for n in chunk {
                    for (key, val) in &n.3 {
                        kv.push(strings.index(key));
                        kv.push(strings.index(val));
                    }
                    kv.push(0);
                }
                pb::bytes(&mut dense, 10, &pb::packed(kv));
            }
            pb::bytes(&mut group, 2, &dense);
        } else {
            for n in chunk {
                let mut node = Vec::new();
                pb::int(&mut node, 1, pb::zigzag(n.0));
                let (keys, vals) = strings.keys_vals(&n.3);
                pb::bytes(&mut node, 2, &keys);
                pb::bytes(&mut node, 3, &vals);
                pb::int(&mut node, 8, pb::zigzag(stored(n.1, layout.lat_offset)));
                pb::int(&mut node, 9, pb::zigzag(stored(n.2, layout.lon_offset)));
                pb::bytes(&mut group, 1, &node);
            }
        }
        blob(
            &mut out,
            "OSMData",
            &block(&strings, &group, layout),
            k % 2 == 0,
        );
        k += 1;
    }
    for chunk in osm.ways.chunks(layout.per_block) {
        let mut strings = Strings::default();
        let mut group = Vec::new();
        for (id, refs, tags) in chunk {
            let mut way = Vec::new();
            pb::int(&mut way, 1, *id as u64);
            let (keys, vals) = strings.keys_vals(tags);
            pb::bytes(&mut way, 2, &keys);
            pb::bytes(&mut way, 3, &vals);
            pb::bytes(&mut way, 8, &pb::deltas(refs.iter().copied()));
            pb::bytes(&mut group, 3, &way);
        }
        blob(
            &mut out,
            "OSMData",
            &block(&strings, &group, layout),
            k % 2 == 0,
        );
        k += 1;
    }
    out
}

/// Everything `bytes` holds, read back as a PBF file named `name`.
fn read_back(bytes: &[u8], name: &str) -> Result<Osm, PbfError> {
    let mut osm = Osm::default();
    let tags = |t: osm_pbf::Tags<'_>| t.map(|(k, v)| (k.to_string(), v.to_string())).collect();
    PbfReader::new(bytes, name).read_all(|el| match el {
        Element::Node(n) => osm.nodes.push((n.id, n.lat, n.lon, tags(n.tags()))),
        Element::Way(w) => osm.ways.push((w.id, w.refs().collect(), tags(w.tags()))),
    })?;
    Ok(osm)
}

/// `read` equals `written`, coordinates within `tolerance` degrees.
fn assert_same(read: &Osm, written: &Osm, tolerance: f64) {
    assert_eq!(read.ways, written.ways);
    assert_eq!(read.nodes.len(), written.nodes.len());
    for (r, w) in read.nodes.iter().zip(&written.nodes) {
        assert_eq!((r.0, &r.3), (w.0, &w.3));
        assert!(
            (r.1 - w.1).abs() < tolerance && (r.2 - w.2).abs() < tolerance,
            "node {} at {}, {}: written {}, {}",
            r.0,
            r.1,
            r.2,
            w.1,
            w.2
        );
    }
}

/// A small extract: tagged and untagged nodes, negative and large ids, both hemispheres.
fn sample() -> Osm {
    let tags = |t: &[(&str, &str)]| {
        t.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let mut osm = Osm::default();
    for i in 0..40i64 {
        let id = if i % 7 == 3 { -i } else { 1 << 40 | i };
        let t = match i % 5 {
            0 => tags(&[("highway", "traffic_signals")]),
            1 => tags(&[("name", "Zürich \"HB\""), ("amenity", "fuel")]),
            _ => Vec::new(),
        };
        osm.nodes.push((
            id,
            -33.9 + 0.001_234_5 * i as f64,
            151.2 - 0.3 * i as f64,
            t,
        ));
    }
    let ids: Vec<i64> = osm.nodes.iter().map(|n| n.0).collect();
    osm.ways.push((
        7,
        ids[..10].to_vec(),
        tags(&[
            ("highway", "primary"),
            ("maxspeed", "50"),
            ("oneway", "yes"),
        ]),
    ));
    osm.ways.push((
        1 << 35,
        ids[5..30].iter().rev().copied().collect(),
        Vec::new(),
    ));
    osm.ways
        .push((9, vec![ids[0], ids[39]], tags(&[("highway", "service")])));
    osm
}

#[test]
fn a_written_pbf_reads_back_exactly() {
    let osm = sample();
    // Granularity 100 stores the degrees in steps of 1e-7, rounded: 5e-8 off at most, so 6e-8
    // allows for the f64 arithmetic; granularity 10 (and offsets), a tenth of that.
    for (layout, tolerance) in [
        (Layout::default(), 6e-8),
        (
            Layout {
                per_block: 7,
                ..Layout::default()
            },
            6e-8,
        ),
        (
            Layout {
                per_block: 3,
                granularity: 10,
                lat_offset: -33_000_000_000,
                lon_offset: 123_456_789,
            },
            6e-9,
        ),
    ] {
        let bytes = write_pbf(&osm, layout);
        let read = read_back(&bytes, "sample.osm.pbf").unwrap_or_else(|e| panic!("{e}"));
        assert_same(&read, &osm, tolerance);
    }
}

/// The extract `grid_osm` writes, read as a test reads XML.
fn parse_grid(text: &str) -> Osm {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut osm = Osm::default();
    let attr = |e: &quick_xml::events::BytesStart<'_>, k: &[u8]| -> String {
        let a = e.attributes().flatten().find(|a| a.key.as_ref() == k);
        String::from_utf8(a.expect("attribute").value.to_vec()).expect("UTF-8")
    };
    loop {
        match reader.read_event().expect("XML") {
            Event::Empty(e) | Event::Start(e) => match e.name().as_ref() {
                b"node" => osm.nodes.push((
                    attr(&e, b"id").parse().expect("id"),
                    attr(&e, b"lat").parse().expect("lat"),
                    attr(&e, b"lon").parse().expect("lon"),
                    Vec::new(),
                )),
                b"way" => {
                    osm.ways
                        .push((attr(&e, b"id").parse().expect("id"), Vec::new(), Vec::new()))
                }
                b"nd" => {
                    let w = osm.ways.last_mut().expect("a way");
                    w.1.push(attr(&e, b"ref").parse().expect("ref"));
                }
                b"tag" => {
                    let w = osm.ways.last_mut().expect("a way");
                    w.2.push((attr(&e, b"k"), attr(&e, b"v")));
                }
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    osm
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("osm-pbf-{name}"));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// The street grid as OSM XML and as PBF (blobs of 25 elements: dense and plain, zlib and
/// raw).
fn grid_both(dir: &Path) -> (PathBuf, PathBuf) {
    let xml = dir.join("grid.osm");
    grid_osm(&xml);
    let osm = parse_grid(&std::fs::read_to_string(&xml).expect("the grid"));
    let pbf = dir.join("grid.osm.pbf");
    let layout = Layout {
        per_block: 25,
        ..Layout::default()
    };
    std::fs::write(&pbf, write_pbf(&osm, layout)).expect("write the PBF");
    (xml, pbf)
}

#[test]
fn the_grid_as_pbf_gives_the_graph_of_its_xml() {
    let (xml, pbf) = grid_both(&scratch("graph"));
    let (a, b) = (
        RoadGraph::load(&xml).expect("the XML"),
        RoadGraph::load(&pbf).expect("the PBF"),
    );
    assert_eq!((b.len(), b.edge_count()), (a.len(), a.edge_count()));
    // 10 rows of 11 blocks, 12 columns of 9, both ways.
    assert_eq!((a.len(), a.edge_count()), (120, 436));
    for n in 0..a.len() as u32 {
        let (ga, gb) = (a.geodetic(n).expect("a"), b.geodetic(n).expect("b"));
        // The XML's 6 decimals are whole steps of the PBF's 1e-7: the same to f64 rounding.
        assert!(
            (ga.lat - gb.lat).abs() < 1e-9 && (ga.lon - gb.lon).abs() < 1e-9,
            "node {n}: {ga:?} against {gb:?}"
        );
        let (ea, eb) = (a.out(n), b.out(n));
        assert_eq!(ea.len(), eb.len(), "node {n}");
        for (x, y) in ea.iter().zip(eb) {
            assert_eq!((x.to, x.speed), (y.to, y.speed), "node {n}");
            assert!(
                (x.length_m - y.length_m).abs() < 1e-3,
                "node {n}: {x:?} {y:?}"
            );
        }
    }
}

#[test]
fn locate_reports_the_same_with_the_grid_as_pbf() {
    let dir = scratch("locate");
    let (xml, pbf) = grid_both(&dir);
    // The first half of the sample drive: a fix not yet good enough, so road advice.
    let capture =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../serial-bridge/captures/aoa-drive.nmea");
    let text = std::fs::read_to_string(capture).expect("capture");
    let half: String = text.lines().take(90).map(|l| format!("{l}\n")).collect();
    let drive = dir.join("half.nmea");
    std::fs::write(&drive, half).expect("write");
    let run = |roads: &Path, json: bool| {
        let out = Command::new(env!("CARGO_BIN_EXE_foxhunt"))
            .arg("locate")
            .arg(&drive)
            .arg("--roads")
            .arg(roads)
            .args(json.then_some("--json"))
            .output()
            .expect("run foxhunt");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).expect("UTF-8")
    };
    for json in [false, true] {
        let (a, b) = (run(&xml, json), run(&pbf, json));
        assert!(a.contains("next junction"), "{a}");
        assert_eq!(a, b);
    }
}

/// The sample as PBF, zlib and raw blobs, dense and plain nodes.
fn sample_bytes() -> Vec<u8> {
    let layout = Layout {
        per_block: 10,
        ..Layout::default()
    };
    write_pbf(&sample(), layout)
}

/// A blob header's length prefix and the header itself, claiming `datasize` bytes follow.
fn header_claiming(kind: &str, datasize: u64) -> Vec<u8> {
    let mut header = Vec::new();
    pb::bytes(&mut header, 1, kind.as_bytes());
    pb::int(&mut header, 3, datasize);
    let mut out = (header.len() as u32).to_be_bytes().to_vec();
    out.extend_from_slice(&header);
    out
}

/// A valid header blob, then `data` as one raw OSMData blob.
fn with_data(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    blob(&mut out, "OSMHeader", &[], false);
    blob(&mut out, "OSMData", data, false);
    out
}

/// One line naming the file: the problem, and the bytes held at most by the read.
fn problem_of(bytes: &[u8]) -> (Problem, usize) {
    let (r, peak) = counting::peak(|| read_back(bytes, "bad.osm.pbf"));
    let e = r.expect_err("an error");
    let line = e.to_string();
    assert!(
        line.starts_with("bad.osm.pbf: ") && !line.contains('\n'),
        "{line}"
    );
    (e.problem, peak)
}

#[test]
fn each_malformed_file_gives_its_problem() {
    let mut strings = Strings::default();
    strings.index("");
    let good = sample_bytes();
    let mut lzma = Vec::new();
    pb::bytes(&mut lzma, 4, b"whatever");
    let mut zlib_junk = Vec::new();
    pb::bytes(&mut zlib_junk, 3, b"not zlib at all");
    let mut lying = Vec::new();
    {
        use std::io::Write;
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(b"\x0a\x00").expect("compress");
        pb::int(&mut lying, 2, 5);
        pb::bytes(&mut lying, 3, &z.finish().expect("compress"));
    }
    let with_blob = |body: &[u8]| {
        let mut out = Vec::new();
        blob(&mut out, "OSMHeader", &[], false);
        out.extend(header_claiming("OSMData", body.len() as u64));
        out.extend_from_slice(body);
        out
    };
    let with_feature = |name: &str| {
        let mut h = Vec::new();
        pb::bytes(&mut h, 4, name.as_bytes());
        let mut out = Vec::new();
        blob(&mut out, "OSMHeader", &h, true);
        out
    };
    // A way naming string 9 of a table of 1.
    let mut way = Vec::new();
    pb::int(&mut way, 1, 5);
    pb::bytes(&mut way, 2, &[9]);
    pb::bytes(&mut way, 3, &[0]);
    let mut group = Vec::new();
    pb::bytes(&mut group, 3, &way);
    let out_of_range = with_data(&block(&strings, &group, Layout::default()));
    // Dense nodes with two ids and one latitude and longitude.
    let mut dense = Vec::new();
    pb::bytes(&mut dense, 1, &[2, 2]);
    pb::bytes(&mut dense, 8, &[2]);
    pb::bytes(&mut dense, 9, &[2]);
    let mut group = Vec::new();
    pb::bytes(&mut group, 2, &dense);
    let short_column = with_data(&block(&strings, &group, Layout::default()));
    // An 11-byte varint where a way's id should be.
    let mut group = Vec::new();
    pb::bytes(
        &mut group,
        3,
        &[
            0x08, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x01,
        ],
    );
    let bad_varint = with_data(&block(&strings, &group, Layout::default()));
    let mut no_header = Vec::new();
    blob(&mut no_header, "OSMData", &[], false);
    // Each case: its name, its bytes, whether the problem is the one expected.
    type Expected = fn(&Problem) -> bool;
    let cases: Vec<(&str, Vec<u8>, Expected)> = vec![
        ("empty", Vec::new(), |p| *p == Problem::NoHeader),
        ("truncated blob", good[..good.len() - 3].to_vec(), |p| {
            *p == Problem::Truncated("a blob")
        }),
        ("truncated length", good[..2].to_vec(), |p| {
            *p == Problem::Truncated("a blob's length")
        }),
        ("bad varint", bad_varint, |p| matches!(p, Problem::Wire(..))),
        ("lzma", with_blob(&lzma), |p| {
            *p == Problem::Compression("lzma")
        }),
        ("bad zlib", with_blob(&zlib_junk), |p| {
            matches!(p, Problem::Zlib(_))
        }),
        ("raw_size lies", with_blob(&lying), |p| {
            *p == Problem::RawSize {
                declared: 5,
                inflated: 2,
            }
        }),
        ("string index", out_of_range, |p| {
            *p == Problem::StringIndex {
                index: 9,
                strings: 1,
            }
        }),
        ("short column", short_column, |p| {
            matches!(p, Problem::Columns(_))
        }),
        ("history", with_feature("HistoricalInformation"), |p| {
            *p == Problem::History
        }),
        (
            "unknown feature",
            with_feature("Sort.Geographic.Hilbert"),
            |p| matches!(p, Problem::Feature(f) if f == "Sort.Geographic.Hilbert"),
        ),
        ("no header", no_header, |p| *p == Problem::NoHeader),
    ];
    for (what, bytes, expected) in cases {
        let (p, _) = problem_of(&bytes);
        println!("{what}: {p}");
        assert!(expected(&p), "{what}: {p:?}");
    }
}

#[test]
fn lengths_claiming_gigabytes_allocate_nothing_of_the_kind() {
    // Claims of 4 GiB and 2 GiB, and of 32 MiB in a file of a few bytes: refused, or read as
    // far as the file goes. A few KiB are what the read holds (its buffers); 64 KiB is ample
    // and a thousandth of the smallest claim.
    let mut header = Vec::new();
    blob(&mut header, "OSMHeader", &[], false);
    let mut huge_field = header.clone();
    huge_field.extend(header_claiming("OSMData", 8));
    huge_field.extend_from_slice(&[0x0a, 0xff, 0xff, 0xff, 0xff, 0x0f, 0x00, 0x00]);
    let mut huge_raw_size = header.clone();
    let mut body = Vec::new();
    pb::int(&mut body, 2, 0x7fff_ffff);
    pb::bytes(&mut body, 3, b"x");
    huge_raw_size.extend(header_claiming("OSMData", body.len() as u64));
    huge_raw_size.extend(body);
    let cases: [(&str, Vec<u8>, Problem); 5] = [
        (
            "BlobHeader length",
            vec![0xff, 0xff, 0xff, 0xff, 0x0a],
            Problem::TooLarge {
                what: "a BlobHeader",
                size: 0xffff_ffff,
                limit: 64 * 1024,
            },
        ),
        (
            "datasize",
            header_claiming("OSMHeader", 0x7fff_ffff),
            Problem::TooLarge {
                what: "a blob",
                size: 0x7fff_ffff,
                limit: MAX_BLOB,
            },
        ),
        (
            "datasize within the cap, past the file",
            header_claiming("OSMHeader", MAX_BLOB),
            Problem::Truncated("a blob"),
        ),
        (
            "a field's length",
            huge_field,
            Problem::Wire("a Blob", WireError::PastEnd),
        ),
        (
            "raw_size",
            huge_raw_size,
            Problem::TooLarge {
                what: "an inflated blob",
                size: 0x7fff_ffff,
                limit: MAX_BLOB,
            },
        ),
    ];
    for (what, bytes, expected) in cases {
        let (p, peak) = problem_of(&bytes);
        println!("{what}: {p}; {peak} bytes held at most");
        assert_eq!(p, expected, "{what}");
        assert!(peak < 64 * 1024, "{what}: {peak} bytes");
    }
}

/// The most bytes a read of a file of `len` bytes may hold: its blobs, their inflated data
/// (zlib inflates 1032:1 at most) and the string table's spans (8 bytes for a string of 2
/// bytes or more, so 4 times the inflated data), each buffer up to twice its length as it
/// grows: under 10 x 1032 x `len`, plus 64 KiB of small buffers. What it catches is a claimed
/// length allocated whole (32 MiB, or the gigabytes of a 4-byte length).
fn bound(len: usize) -> usize {
    64 * 1024 + 10 * 1032 * len
}

/// A valid file damaged: bytes overwritten, a length made huge, cut short, bytes inserted.
fn corrupted() -> impl Strategy<Value = Vec<u8>> {
    let files: Vec<Vec<u8>> = [
        "test.osm.pbf",
        "test_nozlib.osm.pbf",
        "test_nozlib_nodense.osm.pbf",
        "loc_on_ways.osm.pbf",
    ]
    .iter()
    .map(|n| {
        std::fs::read(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/data/osm")
                .join(n),
        )
        .expect("test file")
    })
    .chain([sample_bytes()])
    .collect();
    (
        proptest::sample::select(files),
        proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0..4u8), 1..6),
    )
        .prop_map(|(mut bytes, edits)| {
            for (at, byte, how) in edits {
                let i = at.index(bytes.len().max(1)).min(bytes.len());
                match how {
                    0 if i < bytes.len() => bytes[i] = byte,
                    1 => {
                        let end = (i + 4).min(bytes.len());
                        bytes[i..end].fill(0xff);
                    }
                    2 => bytes.truncate(i),
                    _ => bytes.insert(i, byte),
                }
            }
            bytes
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 2000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_bytes_give_an_error_line_not_a_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        let (r, peak) = counting::peak(|| read_back(&bytes, "random.osm.pbf"));
        if let Err(e) = r {
            let line = e.to_string();
            prop_assert!(line.starts_with("random.osm.pbf: ") && !line.contains('\n'), "{}", line);
        }
        prop_assert!(peak < bound(bytes.len()), "{} bytes", peak);
    }

    #[test]
    fn corrupted_files_give_an_error_line_not_a_panic(bytes in corrupted()) {
        let (r, peak) = counting::peak(|| read_back(&bytes, "corrupt.osm.pbf"));
        if let Err(e) = r {
            let line = e.to_string();
            prop_assert!(line.starts_with("corrupt.osm.pbf: ") && !line.contains('\n'), "{}", line);
        }
        prop_assert!(peak < bound(bytes.len()), "{} bytes", peak);
    }
}
