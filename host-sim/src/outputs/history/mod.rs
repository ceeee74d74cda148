//! The history of a run (`--db FILE`, docs/src/history.md): every bearing taken and every fix
//! published, in an SQLite file that outlives the worker. A worker started again on the file
//! resumes its channels from it; `locate --db FILE --since T` replays a period; `foxhunt
//! history` exports it.
//!
//! A bearing is stored as the network's message ([`BearingMessage`]) and read back as one:
//! replayed, it takes the path a broker's bearing takes (its KrakenSDR record through the
//! bridge). It is its (channel, station, time), the table's unique key: a copy arriving again,
//! before or after a restart, is stored once and fused once.
//!
//! The file says it is foxhunt's (SQLite's application id) and which schema it holds (its user
//! version): any other file is refused before anything is read or written. One worker writes
//! a file at a time (an advisory lock on it); readers (a replay, an export) may read it while
//! the worker writes (write-ahead log). Each bearing is committed before the broker is told it
//! arrived, so a killed worker loses none.

pub mod export;
pub mod recorder;

use crate::inputs::mqtt::{BearingMessage, channel_name};
use crate::locate::report::{Located, NoFix};
use crate::outputs::terminal::Stop;
use rusqlite::{Connection, ErrorCode, OpenFlags, params};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// SQLite's application id of a foxhunt history: `FoxH` in ASCII.
pub const APPLICATION_ID: i32 = 0x466f_7848;
/// The schema this build reads and writes (docs/src/history.md).
pub const SCHEMA_VERSION: i32 = 1;
/// How long a statement waits for another program's lock before the file counts as locked.
const BUSY_WAIT: Duration = Duration::from_secs(2);

/// The schema, version 1.
const SCHEMA: &str = "
CREATE TABLE bearings (
    id INTEGER PRIMARY KEY,
    channel TEXT NOT NULL,
    station TEXT NOT NULL,
    time_ms INTEGER NOT NULL,
    lat REAL NOT NULL,
    lon REAL NOT NULL,
    bearing_deg REAL NOT NULL,
    sigma_deg REAL NOT NULL,
    freq_mhz REAL,
    quality REAL NOT NULL,
    kind TEXT NOT NULL,
    UNIQUE (channel, station, time_ms)
);
CREATE INDEX bearings_by_time ON bearings (time_ms);
CREATE TABLE fixes (
    id INTEGER PRIMARY KEY,
    update_id INTEGER NOT NULL,
    time_ms INTEGER,
    written_ms INTEGER NOT NULL,
    channel TEXT,
    outcome TEXT NOT NULL,
    method TEXT NOT NULL,
    bearings INTEGER NOT NULL,
    used INTEGER,
    lat REAL,
    lon REAL,
    major_m REAL,
    minor_m REAL,
    orientation_deg REAL,
    confidence REAL,
    sigma_deg REAL,
    report TEXT
);
CREATE INDEX fixes_by_time ON fixes (time_ms);
";

/// A period of the history: `since <= time_ms < until`, ms since 1970 UTC.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Window {
    /// From (inclusive); `None`: the beginning.
    pub since_ms: Option<i64>,
    /// To (exclusive); `None`: the end.
    pub until_ms: Option<i64>,
}

impl Window {
    /// The bounds for SQL (the open ends as the extremes).
    fn bounds(&self) -> (i64, i64) {
        (
            self.since_ms.unwrap_or(i64::MIN),
            self.until_ms.unwrap_or(i64::MAX),
        )
    }
}

/// A time on the command line: RFC 3339 (`2026-06-01T10:00:00Z`) or ms since 1970 UTC.
pub fn parse_time(text: &str) -> Result<i64, String> {
    if let Ok(ms) = text.parse::<i64>() {
        return Ok(ms);
    }
    time::OffsetDateTime::parse(text, &time::format_description::well_known::Rfc3339)
        .map(|t| (t.unix_timestamp_nanos() / 1_000_000) as i64)
        .map_err(|_| {
            format!(
                "`{text}` is no time: give RFC 3339 (2026-06-01T10:00:00Z) or ms since 1970 UTC"
            )
        })
}

/// Why a file cannot be used as a history, as the command's stop: the wrong file is a usage
/// error (nothing was read or written), a busy one an error (try again).
fn refused(path: &Path, e: &rusqlite::Error) -> Stop {
    let name = path.display();
    match e.sqlite_error_code() {
        Some(ErrorCode::NotADatabase) => Stop::Usage(format!(
            "{name} is not a foxhunt history: not an SQLite database"
        )),
        Some(ErrorCode::DatabaseBusy | ErrorCode::DatabaseLocked) => Stop::Error(format!(
            "{name} is locked by another program: try again when it is done"
        )),
        _ => Stop::Error(format!("{name}: {e}")),
    }
}

/// Check that `conn` holds a foxhunt history of this schema; `Ok(false)` for an empty database
/// (a new file), to be made one.
fn check(conn: &Connection, path: &Path) -> Result<bool, Stop> {
    let name = path.display();
    let pragma = |p: &str| -> Result<i32, Stop> {
        conn.pragma_query_value(None, p, |r| r.get(0))
            .map_err(|e| refused(path, &e))
    };
    let app = pragma("application_id")?;
    let version = pragma("user_version")?;
    let objects: i64 = conn
        .query_row("SELECT count(*) FROM sqlite_schema", [], |r| r.get(0))
        .map_err(|e| refused(path, &e))?;
    if app == 0 && version == 0 && objects == 0 {
        return Ok(false);
    }
    if app != APPLICATION_ID {
        return Err(Stop::Usage(format!(
            "{name} is an SQLite database of another program, not a foxhunt history: refusing \
             to use it"
        )));
    }
    if version != SCHEMA_VERSION {
        return Err(Stop::Usage(format!(
            "{name} is a foxhunt history of schema version {version}; this foxhunt reads \
             version {SCHEMA_VERSION}"
        )));
    }
    Ok(true)
}

/// A history being written by a worker: bearings as they arrive, fixes as they are published.
pub struct History {
    conn: Connection,
    path: PathBuf,
    /// The one-writer lock, held while this is open (dropped after the connection).
    _lock: File,
    /// The newest bearing stored, ms since 1970: a fix's time.
    newest_ms: Option<i64>,
    /// The next update's number.
    next_update: i64,
}

impl std::fmt::Debug for History {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("History")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl Drop for History {
    /// Back to one file (no `-wal` and `-shm` beside it, which a reader would otherwise make
    /// again) when no reader has it open; otherwise it stays as it is, as after a kill.
    fn drop(&mut self) {
        let _ = self.conn.busy_timeout(Duration::ZERO);
        let _ = self.conn.execute_batch("PRAGMA journal_mode = DELETE;");
    }
}

impl History {
    /// Open `path` to write, made a history if it is new (absent or empty); refused (nothing
    /// written) when it is another file, or another worker's.
    pub fn open(path: &Path) -> Result<Self, Stop> {
        let name = path.display();
        match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => {
                return Err(Stop::Usage(format!(
                    "{name} is not a foxhunt history: not a file"
                )));
            }
            _ => {}
        }
        let conn = Connection::open_with_flags(
            path,
            OpenFlags::SQLITE_OPEN_READ_WRITE
                | OpenFlags::SQLITE_OPEN_CREATE
                | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(|e| refused(path, &e))?;
        let lock = File::open(path).map_err(|e| Stop::Error(format!("{name}: {e}")))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(Stop::Error(format!(
                    "{name} is in use by another foxhunt worker: one worker writes a history"
                )));
            }
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(Stop::Error(format!("cannot lock {name}: {e}")));
            }
        }
        conn.busy_timeout(BUSY_WAIT)
            .map_err(|e| refused(path, &e))?;
        if !check(&conn, path)? {
            conn.execute_batch(&format!(
                "BEGIN IMMEDIATE; {SCHEMA} \
                 PRAGMA application_id = {APPLICATION_ID}; \
                 PRAGMA user_version = {SCHEMA_VERSION}; COMMIT;"
            ))
            .map_err(|e| refused(path, &e))?;
        }
        // WAL while the worker writes: readers go on beside it (back to a single file when it
        // closes, below). NORMAL: a commit survives the process being killed (a power cut may
        // lose the last ones).
        conn.execute_batch("PRAGMA journal_mode = WAL; PRAGMA synchronous = NORMAL;")
            .map_err(|e| refused(path, &e))?;
        let (newest_ms, last_update): (Option<i64>, Option<i64>) = conn
            .query_row(
                "SELECT (SELECT max(time_ms) FROM bearings), (SELECT max(update_id) FROM fixes)",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .map_err(|e| refused(path, &e))?;
        Ok(Self {
            conn,
            path: path.to_path_buf(),
            _lock: lock,
            newest_ms,
            next_update: last_update.unwrap_or(0) + 1,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Store bearing `m`, committed at once; whether it is new (a copy of one stored is not).
    pub fn keep(&mut self, m: &BearingMessage) -> Result<bool, String> {
        let n = self
            .conn
            .prepare_cached(
                "INSERT OR IGNORE INTO bearings (channel, station, time_ms, lat, lon, \
                 bearing_deg, sigma_deg, freq_mhz, quality, kind) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
            )
            .and_then(|mut s| {
                s.execute(params![
                    m.channel(),
                    m.station,
                    m.time_ms,
                    m.lat,
                    m.lon,
                    m.bearing_deg,
                    m.sigma_deg,
                    m.freq_mhz,
                    f64::from(m.quality),
                    m.kind,
                ])
            })
            .map_err(|e| format!("{}: {e}", self.path.display()))?;
        if n > 0 {
            self.newest_ms = Some(self.newest_ms.map_or(m.time_ms, |t| t.max(m.time_ms)));
        }
        Ok(n > 0)
    }

    /// Store an update's outcome: a row per channel (its emitter, its region, or why it has
    /// neither), or one row without a channel when none got that far.
    pub fn keep_update(&mut self, located: &Result<Located, Box<NoFix>>) -> Result<(), String> {
        let update = self.next_update;
        self.next_update += 1;
        let written = crate::inputs::messages::now_ms();
        let rows = update_rows(located).map_err(|e| e.to_string())?;
        let tx = self
            .conn
            .transaction()
            .map_err(|e| format!("{}: {e}", self.path.display()))?;
        {
            let mut s = tx
                .prepare_cached(
                    "INSERT INTO fixes (update_id, time_ms, written_ms, channel, outcome, \
                     method, bearings, used, lat, lon, major_m, minor_m, orientation_deg, \
                     confidence, sigma_deg, report) \
                     VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)",
                )
                .map_err(|e| format!("{}: {e}", self.path.display()))?;
            for r in rows {
                s.execute(params![
                    update,
                    self.newest_ms,
                    written,
                    r.channel,
                    r.outcome,
                    r.method,
                    r.bearings,
                    r.used,
                    r.lat,
                    r.lon,
                    r.major_m,
                    r.minor_m,
                    r.orientation_deg,
                    r.confidence,
                    r.sigma_deg,
                    r.report,
                ])
                .map_err(|e| format!("{}: {e}", self.path.display()))?;
            }
        }
        tx.commit()
            .map_err(|e| format!("{}: {e}", self.path.display()))
    }

    /// Every bearing stored, in the order they arrived (a worker resuming).
    pub fn bearings(&self, each: impl FnMut(BearingMessage)) -> Result<u64, Stop> {
        each_bearing(&self.conn, &self.path, Window::default(), each)
    }
}

/// One row of the fixes table, as written and as read back.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FixRow {
    /// The update it belongs to (rows of one update share it).
    pub update_id: i64,
    /// The newest bearing's time when it was computed, ms since 1970 UTC.
    pub time_ms: Option<i64>,
    /// When it was written, ms since 1970 UTC (the worker's clock).
    pub written_ms: i64,
    /// The channel (`145.500`, `none`); `None` for an update where no channel got that far.
    pub channel: Option<String>,
    /// `emitter`, `region`, or why there is neither.
    pub outcome: String,
    /// The method's registry name.
    pub method: String,
    /// Bearings on the channel (the update's, without one).
    pub bearings: i64,
    /// Bearings the emitter's fix used.
    pub used: Option<i64>,
    /// The emitter's latitude, degrees (a region's apex).
    pub lat: Option<f64>,
    /// Its longitude, degrees.
    pub lon: Option<f64>,
    /// The ellipse's semi-major axis, metres.
    pub major_m: Option<f64>,
    /// Its semi-minor axis, metres.
    pub minor_m: Option<f64>,
    /// Its major axis' direction, degrees clockwise from north.
    pub orientation_deg: Option<f64>,
    /// The probability inside it.
    pub confidence: Option<f64>,
    /// The bearing noise the fix used, degrees.
    pub sigma_deg: Option<f64>,
    /// The emitter (or region) as `--json` prints it.
    pub report: Option<String>,
}

/// An update's rows (without their update number and times).
fn update_rows(located: &Result<Located, Box<NoFix>>) -> Result<Vec<FixRow>, serde_json::Error> {
    let (report, error, used) = match located {
        Ok(l) => (Some(&l.report), None, l.report.used),
        Err(e) => (e.located.as_deref().map(|l| &l.report), Some(e), e.used),
    };
    let method = report.map_or("", |r| r.method).to_string();
    let channels: &[crate::locate::report::ChannelSummary] = match (report, error) {
        (Some(r), _) => &r.channels,
        (None, Some(e)) => &e.channels,
        (None, None) => &[],
    };
    let mut rows = Vec::new();
    for c in channels {
        let name = channel_name(c.freq_mhz.map(f64::from));
        let emitter = report.and_then(|r| {
            r.emitters
                .iter()
                .find(|e| channel_name(e.freq_mhz.map(f64::from)) == name)
        });
        let mut row = FixRow {
            channel: Some(name),
            outcome: c.outcome.clone(),
            method: method.clone(),
            bearings: i64::from(c.bearings),
            ..FixRow::default()
        };
        if let Some(e) = emitter {
            row.used = Some(i64::from(e.used));
            row.lat = Some(e.lat);
            row.lon = Some(e.lon);
            row.major_m = Some(f64::from(e.ellipse.major_m));
            row.minor_m = Some(f64::from(e.ellipse.minor_m));
            row.orientation_deg = Some(f64::from(e.ellipse.orientation_deg));
            row.confidence = Some(f64::from(e.ellipse.confidence));
            row.sigma_deg = Some(f64::from(e.sigma_deg));
            row.report = Some(serde_json::to_string(e)?);
        } else if let Some(r) = &c.region {
            row.used = Some(i64::from(r.used));
            row.lat = Some(r.lat);
            row.lon = Some(r.lon);
            row.sigma_deg = Some(f64::from(r.sigma_deg));
            row.report = Some(serde_json::to_string(r)?);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        rows.push(FixRow {
            outcome: error.map_or_else(|| "no channel".to_string(), |e| e.error.clone()),
            method,
            bearings: i64::from(used),
            ..FixRow::default()
        });
    }
    Ok(rows)
}

/// Stream the bearings of `window` in the order they arrived to `each`; how many.
fn each_bearing(
    conn: &Connection,
    path: &Path,
    window: Window,
    mut each: impl FnMut(BearingMessage),
) -> Result<u64, Stop> {
    let (since, until) = window.bounds();
    let mut s = conn
        .prepare(
            "SELECT station, time_ms, lat, lon, bearing_deg, sigma_deg, freq_mhz, quality, kind \
             FROM bearings WHERE time_ms >= ?1 AND time_ms < ?2 ORDER BY id",
        )
        .map_err(|e| refused(path, &e))?;
    let mut rows = s
        .query(params![since, until])
        .map_err(|e| refused(path, &e))?;
    let mut n = 0u64;
    while let Some(r) = rows.next().map_err(|e| refused(path, &e))? {
        let m = (|| {
            Ok::<_, rusqlite::Error>(BearingMessage {
                station: r.get(0)?,
                time_ms: r.get(1)?,
                lat: r.get(2)?,
                lon: r.get(3)?,
                bearing_deg: r.get(4)?,
                sigma_deg: r.get(5)?,
                freq_mhz: r.get(6)?,
                quality: r.get::<_, f64>(7)? as f32,
                kind: r.get(8)?,
            })
        })()
        .map_err(|e| refused(path, &e))?;
        each(m);
        n += 1;
    }
    Ok(n)
}

/// A history opened to read (a replay, an export): never written.
pub struct Reader {
    conn: Connection,
    path: PathBuf,
}

impl std::fmt::Debug for Reader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reader")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

/// What a history holds, in a period.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Summary {
    /// Bearings.
    pub bearings: i64,
    /// Distinct stations.
    pub stations: i64,
    /// Distinct channels.
    pub channels: i64,
    /// The first and last bearing's time, ms since 1970 UTC.
    pub span_ms: Option<(i64, i64)>,
    /// Fix rows.
    pub fixes: i64,
    /// Updates.
    pub updates: i64,
}

impl Reader {
    /// Open `path` to read; refused when it is not a foxhunt history of this schema.
    pub fn open(path: &Path) -> Result<Self, Stop> {
        let name = path.display();
        match std::fs::metadata(path) {
            Ok(m) if m.is_file() => {}
            Ok(_) => {
                return Err(Stop::Usage(format!(
                    "{name} is not a foxhunt history: not a file"
                )));
            }
            Err(e) => return Err(Stop::Error(format!("cannot read {name}: {e}"))),
        }
        let conn = Connection::open_with_flags(
            path,
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(|e| refused(path, &e))?;
        conn.busy_timeout(BUSY_WAIT)
            .map_err(|e| refused(path, &e))?;
        if !check(&conn, path)? {
            return Err(Stop::Usage(format!(
                "{name} is not a foxhunt history: an empty file"
            )));
        }
        Ok(Self {
            conn,
            path: path.to_path_buf(),
        })
    }

    /// Stream the bearings of `window`, in the order they arrived; how many.
    pub fn bearings(&self, window: Window, each: impl FnMut(BearingMessage)) -> Result<u64, Stop> {
        each_bearing(&self.conn, &self.path, window, each)
    }

    /// Stream the fix rows of `window` (by their time), in the order they were written; how
    /// many.
    pub fn fixes(
        &self,
        window: Window,
        mut each: impl FnMut(FixRow) -> Result<(), Stop>,
    ) -> Result<u64, Stop> {
        let (since, until) = window.bounds();
        let path = &self.path;
        let mut s = self
            .conn
            .prepare(
                "SELECT update_id, time_ms, written_ms, channel, outcome, method, bearings, \
                 used, lat, lon, major_m, minor_m, orientation_deg, confidence, sigma_deg, \
                 report FROM fixes WHERE coalesce(time_ms, written_ms) >= ?1 \
                 AND coalesce(time_ms, written_ms) < ?2 ORDER BY id",
            )
            .map_err(|e| refused(path, &e))?;
        let mut rows = s
            .query(params![since, until])
            .map_err(|e| refused(path, &e))?;
        let mut n = 0u64;
        while let Some(r) = rows.next().map_err(|e| refused(path, &e))? {
            let row = (|| {
                Ok::<_, rusqlite::Error>(FixRow {
                    update_id: r.get(0)?,
                    time_ms: r.get(1)?,
                    written_ms: r.get(2)?,
                    channel: r.get(3)?,
                    outcome: r.get(4)?,
                    method: r.get(5)?,
                    bearings: r.get(6)?,
                    used: r.get(7)?,
                    lat: r.get(8)?,
                    lon: r.get(9)?,
                    major_m: r.get(10)?,
                    minor_m: r.get(11)?,
                    orientation_deg: r.get(12)?,
                    confidence: r.get(13)?,
                    sigma_deg: r.get(14)?,
                    report: r.get(15)?,
                })
            })()
            .map_err(|e| refused(path, &e))?;
            each(row)?;
            n += 1;
        }
        Ok(n)
    }

    /// What the history holds in `window`.
    pub fn summary(&self, window: Window) -> Result<Summary, Stop> {
        let (since, until) = window.bounds();
        let path = &self.path;
        let (bearings, stations, channels, first, last): (i64, i64, i64, Option<i64>, Option<i64>) =
            self.conn
                .query_row(
                    "SELECT count(*), count(DISTINCT station), count(DISTINCT channel), \
                     min(time_ms), max(time_ms) FROM bearings \
                     WHERE time_ms >= ?1 AND time_ms < ?2",
                    params![since, until],
                    |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?)),
                )
                .map_err(|e| refused(path, &e))?;
        let (fixes, updates): (i64, i64) = self
            .conn
            .query_row(
                "SELECT count(*), count(DISTINCT update_id) FROM fixes \
                 WHERE coalesce(time_ms, written_ms) >= ?1 AND coalesce(time_ms, written_ms) < ?2",
                params![since, until],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .map_err(|e| refused(path, &e))?;
        Ok(Summary {
            bearings,
            stations,
            channels,
            span_ms: first.zip(last),
            fixes,
            updates,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(station: &str, time_ms: i64) -> BearingMessage {
        BearingMessage {
            station: station.into(),
            time_ms,
            lat: 47.0,
            lon: 8.0,
            bearing_deg: 45.0,
            sigma_deg: 1.0,
            freq_mhz: Some(433.92),
            quality: 80.0,
            kind: "kraken-xml".into(),
        }
    }

    #[test]
    fn a_bearing_is_stored_once_and_read_back_in_the_order_it_came() {
        let dir = std::env::temp_dir().join(format!("foxhunt-history-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("h.db");
        let mut h = History::open(&path).expect("open");
        // Out of time order, as a network's stations deliver them.
        for (s, t) in [("b", 2_000), ("a", 1_000), ("a", 3_000)] {
            assert!(h.keep(&message(s, t)).expect("keep"));
        }
        assert!(!h.keep(&message("a", 1_000)).expect("keep"), "a copy");
        let other_channel = BearingMessage {
            freq_mhz: Some(145.5),
            ..message("a", 1_000)
        };
        assert!(h.keep(&other_channel).expect("keep"), "another channel");
        let mut seen = Vec::new();
        h.bearings(|m| seen.push((m.station, m.time_ms)))
            .expect("read");
        assert_eq!(
            seen,
            [("b", 2_000), ("a", 1_000), ("a", 3_000), ("a", 1_000)]
                .map(|(s, t)| (s.to_string(), t))
        );
        assert_eq!(h.newest_ms, Some(3_000));
        drop(h);
        let r = Reader::open(&path).expect("reader");
        let mut n = 0;
        let window = Window {
            since_ms: Some(1_000),
            until_ms: Some(3_000),
        };
        r.bearings(window, |m| {
            assert!((1_000..3_000).contains(&m.time_ms));
            assert_eq!(
                m,
                if m.station == "b" {
                    message("b", 2_000)
                } else {
                    m.clone()
                }
            );
            n += 1;
        })
        .expect("read");
        assert_eq!(n, 3);
        let s = r.summary(Window::default()).expect("summary");
        assert_eq!((s.bearings, s.stations, s.channels), (4, 2, 2));
        assert_eq!(s.span_ms, Some((1_000, 3_000)));
        let _ = std::fs::remove_dir_all(&dir);
    }

    proptest::proptest! {
        /// Any text: a time or one line saying why not, never a panic.
        #[test]
        fn any_text_is_a_time_or_an_error(text in ".{0,40}") {
            let _ = parse_time(&text);
        }
    }
}
