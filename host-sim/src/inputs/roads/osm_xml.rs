//! OSM XML through quick-xml, with a guard against files that are not markup.

use super::extract::Extract;
use foxhunt_bridge::nmea::LatLon;
use std::io::{BufRead, Read};

/// The longest run of bytes OSM XML has inside one piece: a tag with every attribute (from
/// `<` to its `>`), or the text between two tags. Far beyond any real one; a file without
/// markup (zeros, a binary), or a tag that never closes (`<node <node ...`), fails at the
/// first run this long instead of filling the XML reader's buffer with it.
const MAX_MARKUP_RUN: usize = 1 << 20;

/// A reader of OSM XML text that fails on a piece of [`MAX_MARKUP_RUN`] bytes, or when the
/// text does not start (after blanks) with `<`.
pub(super) struct MarkupRuns<R> {
    inner: R,
    /// Bytes since the piece began: since the last `>` outside a tag, the last `<` in one.
    run: usize,
    /// Inside a tag (after `<`, before its `>`).
    in_tag: bool,
    started: bool,
}

impl<R: Read> MarkupRuns<R> {
    pub(super) fn new(inner: R) -> Self {
        Self {
            inner,
            run: 0,
            in_tag: false,
            started: false,
        }
    }
}

impl<R: Read> Read for MarkupRuns<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for &b in buf.get(..n).unwrap_or_default() {
            if !self.started {
                // A UTF-8 byte-order mark and blanks may come first; then the markup.
                if b.is_ascii_whitespace() || [0xef, 0xbb, 0xbf].contains(&b) {
                    continue;
                }
                if b != b'<' {
                    return Err(std::io::Error::other(
                        "not OSM XML (it does not start with `<`; a .osm.pbf file must end in .pbf)",
                    ));
                }
                self.started = true;
            }
            // A tag ends only at its `>` (a `<` inside one is no new piece), text at a `<`.
            let ends = if self.in_tag { b == b'>' } else { b == b'<' };
            if ends {
                self.in_tag = !self.in_tag;
                self.run = 0;
            } else {
                self.run += 1;
            }
            if self.run > MAX_MARKUP_RUN {
                return Err(std::io::Error::other(format!(
                    "not OSM XML (a tag or a text of more than {MAX_MARKUP_RUN} bytes)"
                )));
            }
        }
        Ok(n)
    }
}

/// A tag as read from XML: key, value.
pub(super) type Tag = (String, String);

/// Read OSM XML (`<node id lat lon>`, `<way><nd ref/><tag k v/></way>`).
pub(super) fn read_xml(bytes: impl BufRead, into: &mut impl Extract) -> Result<(), String> {
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
        let ev = reader.read_event_into(&mut buf).map_err(|e| match e {
            // The cap's or the markup check's own words.
            quick_xml::Error::Io(io) => io.to_string(),
            // quick-xml quotes the text it found, line ends and all: on one line.
            e => format!("OSM XML at byte {}: {e}", reader.buffer_position())
                .replace(['\n', '\r'], " "),
        })?;
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
