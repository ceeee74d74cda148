//! A KrakenSDR on the network: its web server's DoA pages polled about twice a second, as
//! df-aggregator does (docs/src/formats/bearings.md, "KrakenSDR over HTTP").
//!
//! `http://HOST:8081` alone reads `DOA_value.html` (the "Kraken App" CSV, one line per
//! channel) and falls back to `doa.xml` when the unit has no such page; a URL naming either
//! page reads that one. The DSP rewrites the page about 2.3 times a second, so a poll may
//! read an empty file, a half-written one, or the very records of the poll before: only
//! whole records are handed on (a CSV line ended by its newline, or at the end of the page
//! with all 377 fields; an XML record with its `</DATA>`), and a record already handed on is
//! not handed on again, so no bearing counts twice. The records then go through the same
//! demultiplexer and bridge as a serial line's bytes.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Duration;

/// The KrakenSDR's DoA page (CSV).
pub const CSV_PAGE: &str = "DOA_value.html";
/// The KrakenSDR's XML page.
pub const XML_PAGE: &str = "doa.xml";
/// Between polls: df-aggregator's half second.
pub const POLL: Duration = Duration::from_millis(500);
/// Records remembered as already seen: many polls' worth of channels.
const REMEMBERED: usize = 512;
/// Fields of a whole "Kraken App" CSV line.
const CSV_FIELDS: usize = foxhunt_bridge::kraken::CSV_FIELDS as usize;

/// Which page to read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KrakenUrl {
    /// `http://host:port` without a trailing slash.
    pub base: String,
    /// The page named in the URL, or `None`: the CSV page, else the XML one.
    pub page: Option<String>,
}

impl KrakenUrl {
    /// `http://HOST[:PORT][/DOA_value.html|/doa.xml]`; nonsense refused on one line naming it.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = |why: &str| format!("--kraken wants http://HOST:8081 ({why}), not `{text}`");
        let rest = if let Some(r) = text.strip_prefix("http://") {
            r
        } else if text.starts_with("https://") {
            return Err(bad("the unit serves plain http"));
        } else {
            return Err(bad("an http:// URL"));
        };
        let (authority, path) = rest.split_once('/').unwrap_or((rest, ""));
        let host = match authority.split_once(':') {
            Some((h, p)) => {
                if !p.parse::<u16>().is_ok_and(|n| n > 0) {
                    return Err(bad("a port from 1 to 65535"));
                }
                h
            }
            None => authority,
        };
        if host.is_empty() || host.chars().any(|c| c.is_whitespace() || c == '@') {
            return Err(bad("a host"));
        }
        let page = match path.trim_end_matches('/') {
            "" => None,
            p if p.ends_with(CSV_PAGE) || p.ends_with(XML_PAGE) => Some(p.to_string()),
            _ => {
                return Err(bad(
                    "the unit's DOA_value.html or doa.xml, or no page at all",
                ));
            }
        };
        Ok(Self {
            base: format!("http://{authority}"),
            page,
        })
    }
}

/// What one poll gave.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Poll {
    /// The new whole records, each with its line end, for the demultiplexer.
    pub records: Vec<u8>,
    /// New whole records.
    pub new: u32,
    /// Records seen in an earlier poll.
    pub repeated: u32,
    /// Half-written records left for a later poll.
    pub partial: u32,
    /// The page was empty.
    pub empty: bool,
}

/// The records already handed on (their hashes).
pub type Seen = crate::inputs::seen::Seen<u64, REMEMBERED>;

/// A record's key in [`Seen`].
fn record_key(record: &str) -> u64 {
    let mut h = DefaultHasher::new();
    record.hash(&mut h);
    h.finish()
}

/// The new whole records of one reply.
pub fn new_records(page: &str, seen: &mut Seen) -> Poll {
    let mut poll = Poll {
        empty: page.trim().is_empty(),
        ..Poll::default()
    };
    let mut take = |record: &str, poll: &mut Poll| {
        if seen.first_time(record_key(record)) {
            poll.new += 1;
            poll.records.extend_from_slice(record.as_bytes());
            poll.records.push(b'\n');
        } else {
            poll.repeated += 1;
        }
    };
    if page.contains("<DATA") {
        let mut rest = page;
        while let Some(start) = rest.find("<DATA") {
            let from = &rest[start..];
            match from.find("</DATA>") {
                Some(end) => {
                    take(&from[..end + "</DATA>".len()], &mut poll);
                    rest = &from[end + "</DATA>".len()..];
                }
                None => {
                    poll.partial += 1;
                    break;
                }
            }
        }
        return poll;
    }
    let ends_whole = page.ends_with('\n');
    let lines: Vec<&str> = page.split('\n').collect();
    for (i, line) in lines.iter().enumerate() {
        let record = line.trim_end_matches(['\r', ' ']);
        if record.trim().is_empty() {
            continue;
        }
        let last = i + 1 == lines.len();
        if last && !ends_whole && record.split(',').count() < CSV_FIELDS {
            poll.partial += 1;
            continue;
        }
        take(record, &mut poll);
    }
    poll
}

/// Poll the unit every [`POLL`] until `each` returns false, handing it each poll's new
/// records; `note` hears of trouble (each kind once until a poll succeeds again). A unit that
/// does not answer is polled on: it may be rebooting.
pub fn poll(url: &KrakenUrl, mut each: impl FnMut(Poll) -> bool, mut note: impl FnMut(&str)) {
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_global(Some(Duration::from_secs(2)))
        .http_status_as_error(false)
        .build()
        .into();
    let mut page = url.page.clone().unwrap_or_else(|| CSV_PAGE.to_string());
    let mut seen = Seen::default();
    let mut trouble: Option<String> = None;
    loop {
        let started = std::time::Instant::now();
        let target = format!("{}/{page}", url.base);
        let outcome = agent.get(&target).call().map_err(|e| e.to_string());
        let text = match outcome {
            Ok(r) if r.status().as_u16() == 404 && url.page.is_none() && page == CSV_PAGE => {
                // No CSV page on this unit: its XML one.
                page = XML_PAGE.to_string();
                continue;
            }
            Ok(mut r) if r.status().is_success() => r
                .body_mut()
                .with_config()
                .limit(4 << 20)
                .read_to_string()
                .map_err(|e| format!("reading {target}: {e}")),
            Ok(r) => Err(format!("{target} answered {}", r.status())),
            Err(e) => Err(format!("polling {target}: {e}")),
        };
        match text {
            Ok(t) => {
                trouble = None;
                if !each(new_records(&t, &mut seen)) {
                    return;
                }
            }
            Err(e) => {
                if trouble.as_deref() != Some(e.as_str()) {
                    note(&e);
                    trouble = Some(e);
                }
                // Let the caller stop (or time out) even while the unit is away.
                if !each(Poll::default()) {
                    return;
                }
            }
        }
        if let Some(rest) = POLL.checked_sub(started.elapsed()) {
            std::thread::sleep(rest);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_and_their_refusals() {
        let u = KrakenUrl::parse("http://192.0.2.7:8081").expect("base");
        assert_eq!((u.base.as_str(), u.page), ("http://192.0.2.7:8081", None));
        let u = KrakenUrl::parse("http://kraken.local:8081/doa.xml").expect("xml");
        assert_eq!(u.page.as_deref(), Some("doa.xml"));
        assert!(
            KrakenUrl::parse("http://kraken/")
                .expect("no port")
                .page
                .is_none()
        );
        for bad in [
            "kraken:8081",
            "https://kraken:8081",
            "http://:8081",
            "http://kraken:0",
            "http://kraken:port",
            "http://kraken:8081/index.html",
        ] {
            let e = KrakenUrl::parse(bad).expect_err(bad);
            assert!(e.contains(bad) && !e.contains('\n'), "{e}");
        }
    }

    fn csv_line(epoch: u64) -> String {
        let mut s = format!(
            "{epoch}, 134, 0.41, -48.5, 151880000, UCA, 100, dingus, 66.961348, -66.4438057, 0, 0, GPS, R, R, R, R"
        );
        for _ in 0..360 {
            s.push_str(", 0.07");
        }
        s
    }

    #[test]
    fn only_whole_new_records_are_handed_on() {
        let mut seen = Seen::default();
        assert!(new_records("", &mut seen).empty);
        let (a, b) = (csv_line(1), csv_line(2));
        // One whole line and half of the next (no newline, fewer fields).
        let half = &b[..b.len() / 2];
        let p = new_records(&format!("{a}\n{half}"), &mut seen);
        assert_eq!((p.new, p.partial, p.repeated), (1, 1, 0));
        assert_eq!(p.records, format!("{a}\n").into_bytes());
        // The page again, now whole, without its final newline: only b is new.
        let p = new_records(&format!("{a}\n{b}"), &mut seen);
        assert_eq!((p.new, p.partial, p.repeated), (1, 0, 1));
        let p = new_records(&format!("{a}\n{b}\n"), &mut seen);
        assert_eq!((p.new, p.repeated), (0, 2));
        // XML: a whole record and a cut one.
        let x = "<DATA><STATION_ID>k</STATION_ID><TIME>1</TIME><DOA>20</DOA></DATA>";
        let p = new_records(&format!("{x}<DATA><STATION_ID>k</STA"), &mut seen);
        assert_eq!((p.new, p.partial), (1, 1));
        assert_eq!(new_records(x, &mut seen).repeated, 1);
    }
}
