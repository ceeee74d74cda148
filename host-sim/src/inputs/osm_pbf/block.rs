//! A `PrimitiveBlock` read: its string table, its coordinate grid and its groups of nodes,
//! dense nodes and ways, given as elements whose tags and refs are views into the block
//! (checked when the element is read, so their iterators cannot fail).

use super::wire::{self, DeltaError, Deltas, Fields, Packed, Value, WireError};
use super::{MAX_BLOB, Problem};

/// A block's coordinate grid: degrees = 1e-9 (offset + granularity x stored value).
#[derive(Debug, Clone, Copy)]
struct Grid {
    granularity: i64,
    lat_offset: i64,
    lon_offset: i64,
}

impl Default for Grid {
    fn default() -> Self {
        Self {
            granularity: 100,
            lat_offset: 0,
            lon_offset: 0,
        }
    }
}

impl Grid {
    /// In i128: no stored value can overflow it.
    fn degrees(&self, offset: i64, stored: i64) -> f64 {
        1e-9 * (i128::from(offset) + i128::from(self.granularity) * i128::from(stored)) as f64
    }

    fn lat(&self, stored: i64) -> f64 {
        self.degrees(self.lat_offset, stored)
    }

    fn lon(&self, stored: i64) -> f64 {
        self.degrees(self.lon_offset, stored)
    }
}

/// A block's strings: spans of the table's bytes (8 bytes a string, not a copy of each),
/// checked UTF-8 when the table is read.
#[derive(Debug)]
struct StringTable<'a> {
    table: &'a [u8],
    spans: Vec<(u32, u32)>,
}

impl<'a> StringTable<'a> {
    fn parse(table: &'a [u8]) -> Result<Self, Problem> {
        let what = "a StringTable";
        let mut spans = Vec::new();
        for f in Fields::new(table) {
            match f.map_err(|e| Problem::Wire(what, e))? {
                (1, Value::Bytes(s)) => {
                    if std::str::from_utf8(s).is_err() {
                        return Err(Problem::NotUtf8(spans.len()));
                    }
                    // `s` lies inside `table` (at most 32 MiB): its offset there.
                    let start = s.as_ptr() as usize - table.as_ptr() as usize;
                    let span = (u32::try_from(start), u32::try_from(start + s.len()));
                    let (Ok(start), Ok(end)) = span else {
                        return Err(Problem::TooLarge {
                            what: "a StringTable",
                            size: table.len() as u64,
                            limit: MAX_BLOB,
                        });
                    };
                    spans.push((start, end));
                }
                (1, _) => return Err(Problem::Field(what, 1)),
                _ => {}
            }
        }
        Ok(Self { table, spans })
    }

    fn get(&self, index: u64) -> Result<&'a str, Problem> {
        self.str(index).ok_or(Problem::StringIndex {
            index,
            strings: self.spans.len(),
        })
    }

    fn str(&self, index: u64) -> Option<&'a str> {
        let (s, e) = *self.spans.get(usize::try_from(index).ok()?)?;
        std::str::from_utf8(self.table.get(s as usize..e as usize)?).ok()
    }
}

/// An element's tags, as (key, value). Checked when the element is read: every index is in the
/// string table.
#[derive(Debug, Clone)]
pub struct Tags<'a> {
    strings: &'a StringTable<'a>,
    keys: Packed<'a>,
    /// None: the values are interleaved with the keys (dense nodes' `keys_vals`).
    vals: Option<Packed<'a>>,
}

impl<'a> Tags<'a> {
    fn paired(strings: &'a StringTable<'a>, keys: &'a [u8], vals: &'a [u8]) -> Self {
        Self {
            strings,
            keys: Packed::new(keys),
            vals: Some(Packed::new(vals)),
        }
    }

    fn interleaved(strings: &'a StringTable<'a>, keys_vals: &'a [u8]) -> Self {
        Self {
            strings,
            keys: Packed::new(keys_vals),
            vals: None,
        }
    }

    /// The next pair of string indices.
    fn next_indices(&mut self) -> Option<Result<(u64, u64), Problem>> {
        let what = "keys and values";
        let k = self.keys.next();
        let v = match &mut self.vals {
            Some(vals) => vals.next(),
            None => k.as_ref().and_then(|_| self.keys.next()),
        };
        Some(match (k, v) {
            (None, None) => return None,
            (Some(Ok(k)), Some(Ok(v))) => Ok((k, v)),
            (Some(Err(e)), _) | (_, Some(Err(e))) => Err(Problem::Wire(what, e)),
            _ => Err(Problem::Columns(what)),
        })
    }

    /// Every pair read, every index in the table.
    fn check(&self) -> Result<(), Problem> {
        let mut t = self.clone();
        while let Some(pair) = t.next_indices() {
            let (k, v) = pair?;
            self.strings.get(k)?;
            self.strings.get(v)?;
        }
        Ok(())
    }
}

impl<'a> Iterator for Tags<'a> {
    type Item = (&'a str, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        let (k, v) = self.next_indices()?.ok()?;
        Some((self.strings.str(k)?, self.strings.str(v)?))
    }
}

/// A node: id, latitude and longitude (degrees) and tags.
#[derive(Debug, Clone)]
pub struct Node<'a> {
    /// OSM id.
    pub id: i64,
    /// Latitude, degrees (as stored: not checked against +-90).
    pub lat: f64,
    /// Longitude, degrees (as stored).
    pub lon: f64,
    tags: Tags<'a>,
}

impl<'a> Node<'a> {
    /// Its tags.
    pub fn tags(&self) -> Tags<'a> {
        self.tags.clone()
    }
}

/// A way: id, the nodes it runs through, tags, and in files written with locations on ways
/// (`LocationsOnWays`, whose nodes may be left out) each node's latitude and longitude.
#[derive(Debug, Clone)]
pub struct Way<'a> {
    /// OSM id.
    pub id: i64,
    refs: &'a [u8],
    lats: &'a [u8],
    lons: &'a [u8],
    grid: Grid,
    tags: Tags<'a>,
}

impl<'a> Way<'a> {
    /// The ids of its nodes, in order.
    pub fn refs(&self) -> impl Iterator<Item = i64> + 'a {
        Deltas::new(self.refs).map_while(Result::ok)
    }

    /// Its nodes' (latitude, longitude), degrees, when the file carries them; else none.
    pub fn locations(&self) -> impl Iterator<Item = (f64, f64)> + 'a {
        let grid = self.grid;
        Deltas::new(self.lats)
            .zip(Deltas::new(self.lons))
            .map_while(move |(a, o)| Some((grid.lat(a.ok()?), grid.lon(o.ok()?))))
    }

    /// Its tags.
    pub fn tags(&self) -> Tags<'a> {
        self.tags.clone()
    }
}

/// What a PBF file holds that is read: nodes and ways.
#[derive(Debug, Clone)]
pub enum Element<'a> {
    /// A node, plain or dense.
    Node(Node<'a>),
    /// A way.
    Way(Way<'a>),
}

/// The one piece of a packed repeated field into `slot`.
fn packed<'a>(
    slot: &mut &'a [u8],
    v: Value<'a>,
    what: &'static str,
    field: u32,
) -> Result<(), Problem> {
    match v {
        Value::Bytes(b) if slot.is_empty() => {
            *slot = b;
            Ok(())
        }
        // An empty piece changes nothing.
        Value::Bytes([]) => Ok(()),
        _ => Err(Problem::Field(what, field)),
    }
}

/// A `PrimitiveBlock`: its nodes and ways through `each`.
pub(super) fn primitive_block(
    block: &[u8],
    each: &mut dyn FnMut(Element<'_>),
) -> Result<(), Problem> {
    let what = "a PrimitiveBlock";
    let mut table = None;
    let mut grid = Grid::default();
    // The block's own fields first: they may follow its groups.
    for f in Fields::new(block) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Bytes(b)) => table = Some(b),
            (17, Value::Varint(n)) => grid.granularity = super::int32(n, what, 17)?,
            (19, Value::Varint(n)) => grid.lat_offset = n as i64,
            (20, Value::Varint(n)) => grid.lon_offset = n as i64,
            // The groups, read below.
            (2, Value::Bytes(_)) => {}
            (n @ (1 | 2 | 17 | 19 | 20), _) => return Err(Problem::Field(what, n)),
            _ => {}
        }
    }
    if grid.granularity <= 0 {
        return Err(Problem::Granularity(grid.granularity));
    }
    let table = table.ok_or(Problem::Missing("a PrimitiveBlock's string table"))?;
    let strings = StringTable::parse(table)?;
    for f in Fields::new(block) {
        if let (2, Value::Bytes(g)) = f.map_err(|e| Problem::Wire(what, e))? {
            primitive_group(g, &strings, grid, each)?;
        }
    }
    Ok(())
}

/// A `PrimitiveGroup`: nodes, dense nodes and ways (relations and changesets are skipped).
fn primitive_group<'a>(
    group: &'a [u8],
    strings: &'a StringTable<'a>,
    grid: Grid,
    each: &mut dyn FnMut(Element<'_>),
) -> Result<(), Problem> {
    let what = "a PrimitiveGroup";
    for f in Fields::new(group) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Bytes(b)) => each(Element::Node(node(b, strings, grid)?)),
            (2, Value::Bytes(b)) => dense_nodes(b, strings, grid, each)?,
            (3, Value::Bytes(b)) => each(Element::Way(way(b, strings, grid)?)),
            (n @ 1..=3, _) => return Err(Problem::Field(what, n)),
            _ => {}
        }
    }
    Ok(())
}

/// A plain `Node`.
fn node<'a>(
    bytes: &'a [u8],
    strings: &'a StringTable<'a>,
    grid: Grid,
) -> Result<Node<'a>, Problem> {
    let what = "a Node";
    let (mut id, mut lat, mut lon) = (None, None, None);
    let (mut keys, mut vals): (&[u8], &[u8]) = (&[], &[]);
    for f in Fields::new(bytes) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Varint(n)) => id = Some(wire::zigzag(n)),
            (2, v) => packed(&mut keys, v, what, 2)?,
            (3, v) => packed(&mut vals, v, what, 3)?,
            (8, Value::Varint(n)) => lat = Some(wire::zigzag(n)),
            (9, Value::Varint(n)) => lon = Some(wire::zigzag(n)),
            (n @ (1 | 8 | 9), _) => return Err(Problem::Field(what, n)),
            _ => {}
        }
    }
    let tags = Tags::paired(strings, keys, vals);
    tags.check()?;
    Ok(Node {
        id: id.ok_or(Problem::Missing("a Node's id"))?,
        lat: grid.lat(lat.ok_or(Problem::Missing("a Node's lat"))?),
        lon: grid.lon(lon.ok_or(Problem::Missing("a Node's lon"))?),
        tags,
    })
}

/// The next value of a delta-coded column.
fn delta(d: Option<Result<i64, DeltaError>>, what: &'static str) -> Result<Option<i64>, Problem> {
    match d {
        None => Ok(None),
        Some(Ok(v)) => Ok(Some(v)),
        Some(Err(DeltaError::Wire(e))) => Err(Problem::Wire(what, e)),
        Some(Err(DeltaError::Overflow)) => Err(Problem::Overflow(what)),
    }
}

/// `DenseNodes`: columns of delta-coded ids, latitudes and longitudes, and the nodes' tags
/// run together (`keys_vals`: key, value, ..., 0 after each node's).
fn dense_nodes<'a>(
    bytes: &'a [u8],
    strings: &'a StringTable<'a>,
    grid: Grid,
    each: &mut dyn FnMut(Element<'_>),
) -> Result<(), Problem> {
    let what = "a DenseNodes";
    let [mut ids, mut lats, mut lons, mut keys_vals]: [&[u8]; 4] = [&[]; 4];
    for f in Fields::new(bytes) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, v) => packed(&mut ids, v, what, 1)?,
            (8, v) => packed(&mut lats, v, what, 8)?,
            (9, v) => packed(&mut lons, v, what, 9)?,
            (10, v) => packed(&mut keys_vals, v, what, 10)?,
            _ => {}
        }
    }
    let (mut ids, mut lats, mut lons) = (Deltas::new(ids), Deltas::new(lats), Deltas::new(lons));
    let mut rest = keys_vals;
    loop {
        let id = delta(ids.next(), "dense node ids")?;
        let lat = delta(lats.next(), "dense node latitudes")?;
        let lon = delta(lons.next(), "dense node longitudes")?;
        let (id, lat, lon) = match (id, lat, lon) {
            (None, None, None) => break,
            (Some(id), Some(lat), Some(lon)) => (id, lat, lon),
            _ => {
                return Err(Problem::Columns(
                    "dense nodes' ids, latitudes and longitudes",
                ));
            }
        };
        // With `keys_vals` at all, each node has its run of pairs and a 0.
        let tags = if keys_vals.is_empty() {
            &[][..]
        } else {
            let (tags, after) = next_run(rest)?;
            rest = after;
            tags
        };
        let tags = Tags::interleaved(strings, tags);
        tags.check()?;
        each(Element::Node(Node {
            id,
            lat: grid.lat(lat),
            lon: grid.lon(lon),
            tags,
        }));
    }
    if !rest.is_empty() {
        return Err(Problem::Columns("dense nodes and their keys_vals"));
    }
    Ok(())
}

/// One node's run of `keys_vals` (its pairs, without the 0 that ends it) and what follows.
fn next_run(keys_vals: &[u8]) -> Result<(&[u8], &[u8]), Problem> {
    let mut pos = 0;
    loop {
        let start = pos;
        let key = wire::varint(keys_vals, &mut pos).map_err(|e| Problem::Wire("keys_vals", e))?;
        if key == 0 {
            let run = keys_vals.get(..start).unwrap_or_default();
            return Ok((run, keys_vals.get(pos..).unwrap_or_default()));
        }
        wire::varint(keys_vals, &mut pos).map_err(|e| match e {
            WireError::PastEnd => Problem::Columns("dense nodes and their keys_vals"),
            e => Problem::Wire("keys_vals", e),
        })?;
    }
}

/// A `Way`.
fn way<'a>(bytes: &'a [u8], strings: &'a StringTable<'a>, grid: Grid) -> Result<Way<'a>, Problem> {
    let what = "a Way";
    let mut id = None;
    let [mut keys, mut vals, mut refs, mut lats, mut lons]: [&[u8]; 5] = [&[]; 5];
    for f in Fields::new(bytes) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Varint(n)) => id = Some(n as i64),
            (1, _) => return Err(Problem::Field(what, 1)),
            (2, v) => packed(&mut keys, v, what, 2)?,
            (3, v) => packed(&mut vals, v, what, 3)?,
            (8, v) => packed(&mut refs, v, what, 8)?,
            (9, v) => packed(&mut lats, v, what, 9)?,
            (10, v) => packed(&mut lons, v, what, 10)?,
            _ => {}
        }
    }
    let id = id.ok_or(Problem::Missing("a Way's id"))?;
    let tags = Tags::paired(strings, keys, vals);
    tags.check()?;
    // Every column read whole once, so the element's iterators cannot fail.
    let count = |bytes, what| -> Result<usize, Problem> {
        let mut d = Deltas::new(bytes);
        let mut n = 0;
        while delta(d.next(), what)?.is_some() {
            n += 1;
        }
        Ok(n)
    };
    let n = count(refs, "way refs")?;
    let located = (
        count(lats, "way latitudes")?,
        count(lons, "way longitudes")?,
    );
    if located != (0, 0) && located != (n, n) {
        return Err(Problem::Columns("a way's refs, latitudes and longitudes"));
    }
    Ok(Way {
        id,
        refs,
        lats,
        lons,
        grid,
        tags,
    })
}
