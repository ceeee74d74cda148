//! `foxhunt history`: what a run's history holds (`locate --db FILE`, docs/src/history.md),
//! and its bearings and fixes exported as CSV and GeoJSON.

use crate::outputs::files::Outputs;
use crate::outputs::history::export::{self, rfc3339};
use crate::outputs::history::{Reader, Window, parse_time};
use crate::outputs::terminal::{Out, Outcome, Stop, note};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Options of `foxhunt history`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The history (`foxhunt locate --db FILE`); only read.
    pub file: PathBuf,
    /// Write the bearings to PREFIX.bearings.csv and the fixes to PREFIX.fixes.csv.
    #[arg(long, value_name = "PREFIX")]
    pub csv: Option<PathBuf>,
    /// Write the bearings (points at their stations) and the fixes (points and ellipses) as
    /// one GeoJSON FeatureCollection.
    #[arg(long, value_name = "FILE")]
    pub geojson: Option<PathBuf>,
    /// Only what was taken at or after T: RFC 3339 (2026-06-01T10:00:00Z) or ms since 1970
    /// UTC (a fix by the newest bearing it had).
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub since: Option<i64>,
    /// Only what was taken before T (RFC 3339 or ms since 1970 UTC).
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub until: Option<i64>,
}

/// `PREFIX.EXT`.
fn with_suffix(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_owned();
    s.push(format!(".{ext}"));
    PathBuf::from(s)
}

/// Write `path` row by row with `fill`, after `outputs`' check; say so on stderr.
fn write_file<T>(
    outputs: &Outputs,
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<T, Stop>,
) -> Result<T, Stop> {
    outputs.check(path, true)?;
    let f = File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut w = BufWriter::new(f);
    let n = fill(&mut w)?;
    w.flush()
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    note(&format!("wrote {}", path.display()));
    Ok(n)
}

/// Run `foxhunt history`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let window = Window {
        since_ms: a.since,
        until_ms: a.until,
    };
    if let (Some(s), Some(u)) = (a.since, a.until)
        && s >= u
    {
        return Err(Stop::usage("--since must come before --until"));
    }
    let outputs = Outputs::new([a.file.as_path()], false);
    let targets: Vec<PathBuf> = a
        .csv
        .iter()
        .flat_map(|p| [with_suffix(p, "bearings.csv"), with_suffix(p, "fixes.csv")])
        .chain(a.geojson.clone())
        .collect();
    for t in &targets {
        outputs.check(t, true)?;
    }
    let h = Reader::open(&a.file)?;
    if let Some(prefix) = &a.csv {
        write_file(&outputs, &with_suffix(prefix, "bearings.csv"), |w| {
            export::bearings_csv(&h, window, w)
        })?;
        write_file(&outputs, &with_suffix(prefix, "fixes.csv"), |w| {
            export::fixes_csv(&h, window, w)
        })?;
    }
    if let Some(path) = &a.geojson {
        write_file(&outputs, path, |w| export::geojson(&h, window, w))?;
    }
    let s = h.summary(window)?;
    let span = s.span_ms.map_or(String::new(), |(a, b)| {
        format!(", from {} to {}", rfc3339(a), rfc3339(b))
    });
    out.line(&format!(
        "bearings {} (stations {}, channels {}){span}; fixes {} in {} updates",
        s.bearings, s.stations, s.channels, s.fixes, s.updates
    ))?;
    Ok(())
}
