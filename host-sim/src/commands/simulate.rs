//! `foxhunt simulate`: a capture byte for byte as the radios would send it.

use crate::outputs::files::Outputs;
use crate::outputs::terminal::{Outcome, Stop, note};
use crate::runs::field::Condition;
use crate::runs::moving;
use crate::runs::network::NetworkCondition;
use crate::runs::scenario::{NAMES, Scenario, ScenarioModel};
use crate::runs::simulate::indoor_capture;
use crate::runs::simulate::{CaptureFormat, CaptureOptions, drive_capture};
use foxhunt_bridge::nmea::{Date, LatLon, UtcTime};
use std::path::PathBuf;

/// Options of `foxhunt simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Canonical scenario name (a drive, or rssi-sim / rssi-lab for an indoor capture).
    #[arg(long, default_value = "aoa-drive", conflicts_with = "scenario_file",
          value_parser = super::one_of(NAMES.iter().map(|n| n.to_string()).collect()))]
    pub scenario: String,
    /// A scenario file (TOML).
    #[arg(long)]
    pub scenario_file: Option<PathBuf>,
    /// A field condition instead (see `bench --scenario field`): GGA fixes and $PFOXB
    /// bearings carrying their own position and frequency; or a network condition
    /// (`network-*`, see `bench --scenario network`): KrakenSDR XML records of every station
    /// with its STATION_ID, and the stations file beside them (OUT with the extension
    /// `.stations.toml`, which must not exist yet unless --force); or a moving emitter
    /// (`move-*`, see `bench --scenario moving`): the same, and the emitter's true track
    /// (OUT with the extension `.truth.csv`).
    #[arg(long, conflicts_with_all = ["scenario_file", "format", "wild", "bias_deg"],
          value_parser = super::one_of(condition_names()))]
    pub condition: Option<String>,
    /// Where to write the capture.
    #[arg(long)]
    pub out: PathBuf,
    /// RSSI scenarios: where to write the anchors file (default: OUT with the extension
    /// `.anchors.toml`, which must not exist yet unless --force).
    #[arg(long)]
    pub anchors_out: Option<PathBuf>,
    /// Overwrite a file the command line did not name (the default anchors file).
    #[arg(long)]
    pub force: bool,
    /// Latitude,longitude where the route's first point lies (the capture's local origin),
    /// decimal degrees (default 47.0,8.0).
    #[arg(long, allow_hyphen_values = true, value_name = "LAT,LON", value_parser = origin)]
    pub origin: Option<LatLon>,
    /// Which Monte Carlo run's noise to write.
    #[arg(long, default_value_t = 0)]
    pub run: usize,
    /// Drives: UTC time of the first fix, HH:MM:SS (default 10:00:00).
    #[arg(long, value_name = "HH:MM:SS", value_parser = start)]
    pub start: Option<UtcTime>,
    /// Drives: UTC date of the first fix, YYYY-MM-DD (default 2026-06-01).
    #[arg(long, value_name = "YYYY-MM-DD", value_parser = date)]
    pub date: Option<Date>,
    /// Drives: share of wild bearings, uniform over the circle (default: the scenario's).
    #[arg(long, value_parser = super::values::share())]
    pub wild: Option<f32>,
    /// Drives: a constant bias on every bearing, degrees (a mounting offset).
    #[arg(long, allow_hyphen_values = true,
          value_parser = super::values::f32_where(|d| d.abs() <= 180.0, "a number of degrees from -180 to 180"))]
    pub bias_deg: Option<f32>,
    /// Drives: share of bytes corrupted after writing (0.01 = 1 %).
    #[arg(long, value_parser = super::values::share())]
    pub corrupt: Option<f32>,
    /// Drives: share of bytes dropped after writing.
    #[arg(long, value_parser = super::values::share())]
    pub drop: Option<f32>,
    /// Drives: the DF unit's record format: pfoxb (GGA + RMC + $PFOXB, the default), agrelo
    /// (GGA + RMC + HDT + %BBB/Q relative bearings), kraken-csv or kraken-xml (KrakenSDR
    /// records with their own position and heading).
    #[arg(long, value_parser = format)]
    pub format: Option<CaptureFormat>,
}

fn format(text: &str) -> Result<CaptureFormat, String> {
    CaptureFormat::from_name(text).ok_or_else(|| {
        let names: Vec<&str> = CaptureFormat::ALL.iter().map(|f| f.name()).collect();
        format!("not one of {}", names.join(", "))
    })
}

fn start(text: &str) -> Result<UtcTime, String> {
    let bad = || "not HH:MM:SS (UTC)".to_string();
    let parts: Vec<u32> = text
        .split(':')
        .map(|p| p.parse().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match parts.as_slice() {
        [h, m, s] if *h < 24 && *m < 60 && *s < 60 => Ok(UtcTime {
            ms_of_day: ((h * 60 + m) * 60 + s) * 1000,
        }),
        _ => Err(bad()),
    }
}

fn date(text: &str) -> Result<Date, String> {
    let bad = || "not a date YYYY-MM-DD".to_string();
    let parts: Vec<&str> = text.split('-').collect();
    let [y, m, d] = parts.as_slice() else {
        return Err(bad());
    };
    let (y, m, d): (u16, u8, u8) = (
        y.parse().map_err(|_| bad())?,
        m.parse().map_err(|_| bad())?,
        d.parse().map_err(|_| bad())?,
    );
    let month = time::Month::try_from(m).map_err(|_| bad())?;
    time::Date::from_calendar_date(i32::from(y), month, d).map_err(|_| bad())?;
    if !(1980..2080).contains(&y) {
        return Err("not in 1980-2079 (RMC writes two-digit years)".into());
    }
    Ok(Date {
        year: y,
        month: m,
        day: d,
    })
}

fn origin(text: &str) -> Result<LatLon, String> {
    let [lat, lon] = super::values::lat_lon(text)?;
    Ok(LatLon { lat, lon })
}

/// The names `--condition` takes: the field conditions, the network ones, then the moving
/// emitters seen through bearings.
fn condition_names() -> Vec<String> {
    Condition::ALL
        .iter()
        .map(|c| c.name())
        .chain(NetworkCondition::ALL.iter().map(|c| c.name()))
        .map(str::to_string)
        .chain(
            moving::MovingScenario::all()
                .into_iter()
                .filter(|s| s.bearings)
                .map(|s| s.name),
        )
        .collect()
}

/// `simulate --condition move-*`: one run of a moving emitter, its capture, its stations
/// file and its truth.
fn moving(a: &Args, s: &moving::MovingScenario) -> Outcome {
    let origin = a.origin.unwrap_or(crate::runs::simulate::DEFAULT_ORIGIN);
    let stations_path = a.out.with_extension("stations.toml");
    let truth_path = a.out.with_extension("truth.csv");
    if stations_path == a.out || truth_path == a.out {
        return Err("the side files and the capture cannot be one file".into());
    }
    let outputs = Outputs::new(std::iter::empty(), a.force);
    let c = moving::capture(s, a.run, origin)?;
    outputs.write(&a.out, &c.bytes, true)?;
    outputs.write(&stations_path, c.stations.as_bytes(), false)?;
    outputs.write(&truth_path, c.truth.as_bytes(), false)?;
    note(&format!(
        "{} bytes; {} stations; the emitter's track in {}",
        c.bytes.len(),
        s.stations.len(),
        truth_path.display()
    ));
    Ok(())
}

/// `simulate --condition network-*`: one run of a network condition, its capture and its
/// stations file.
fn network(a: &Args, c: NetworkCondition) -> Outcome {
    let origin = a.origin.unwrap_or(crate::runs::simulate::DEFAULT_ORIGIN);
    let stations_path = a.out.with_extension("stations.toml");
    if stations_path == a.out {
        return Err("the stations file and the capture cannot be one file".into());
    }
    let outputs = Outputs::new(std::iter::empty(), a.force);
    let (bytes, stations, _) = crate::runs::network::capture(c, a.run, origin)?;
    outputs.write(&a.out, &bytes, true)?;
    outputs.write(&stations_path, stations.as_bytes(), false)?;
    note(&format!(
        "{} bytes; the emitter at {:.6}, {:.6}",
        bytes.len(),
        origin.lat,
        origin.lon
    ));
    Ok(())
}

/// Run `foxhunt simulate`.
pub fn run(a: &Args) -> Outcome {
    if let Some(name) = &a.condition {
        if let Some(c) = NetworkCondition::named(name) {
            return network(a, c);
        }
        if let Some(s) = moving::MovingScenario::named(name) {
            return moving(a, &s);
        }
        return field(a, name);
    }
    let scenario = match &a.scenario_file {
        Some(path) => Scenario::load(path)?,
        None => Scenario::named(&a.scenario).ok_or_else(|| {
            format!(
                "unknown scenario `{}`; known: {}",
                a.scenario,
                NAMES.join(", ")
            )
        })?,
    };
    let inputs = a.scenario_file.iter().map(PathBuf::as_path);
    let outputs = Outputs::new(inputs, a.force);
    outputs.check(&a.out, true)?;
    match &scenario.model {
        ScenarioModel::Rssi { .. } => {
            let drive_only = [
                ("wild", a.wild.is_some()),
                ("bias-deg", a.bias_deg.is_some()),
                ("corrupt", a.corrupt.is_some()),
                ("drop", a.drop.is_some()),
                ("origin", a.origin.is_some()),
                ("start", a.start.is_some()),
                ("date", a.date.is_some()),
                ("format", a.format.is_some()),
            ];
            if let Some((name, _)) = drive_only.iter().find(|(_, given)| *given) {
                return Err(Stop::usage(format!(
                    "--{name} applies to drives, not to the indoor scenario `{}`",
                    scenario.name
                )));
            }
            let named = a.anchors_out.is_some();
            let anchors_path = a
                .anchors_out
                .clone()
                .unwrap_or_else(|| a.out.with_extension("anchors.toml"));
            if anchors_path == a.out {
                return Err(Stop::usage(
                    "the anchors file and the capture cannot be one file",
                ));
            }
            outputs.check(&anchors_path, named)?;
            let (bytes, anchors, _) = indoor_capture(&scenario.name, a.run)?;
            let text = anchors.to_toml(&scenario.name)?;
            outputs.write(&a.out, &bytes, true)?;
            outputs.write(&anchors_path, text.as_bytes(), named)?;
        }
        ScenarioModel::Ungm { .. } => {
            return Err(Stop::usage(format!(
                "`{}` is a benchmark without a radio: nothing to capture",
                scenario.name
            )));
        }
        ScenarioModel::Bearing(d) => {
            let mut o = CaptureOptions {
                run: a.run,
                wild_fraction: a.wild,
                bias_deg: a.bias_deg.unwrap_or(0.0),
                corrupt_fraction: a.corrupt.unwrap_or(0.0),
                drop_fraction: a.drop.unwrap_or(0.0),
                ..CaptureOptions::default()
            };
            o.origin = a.origin.unwrap_or(o.origin);
            o.start = a.start.unwrap_or(o.start);
            o.date = a.date.unwrap_or(o.date);
            o.format = a.format.unwrap_or(o.format);
            let bytes = drive_capture(&scenario, &o)?;
            outputs.write(&a.out, &bytes, true)?;
            note(&format!(
                "{} bytes, {} {} bearings; the route's first point at {:.6},{:.6}",
                bytes.len(),
                d.route.len(),
                o.format.name(),
                o.origin.lat,
                o.origin.lon
            ));
        }
    }
    Ok(())
}

/// `simulate --condition NAME`: one run of a field condition as a capture.
fn field(a: &Args, name: &str) -> Outcome {
    let c = crate::runs::field::condition(name).ok_or_else(|| {
        let names: Vec<&str> = crate::runs::field::Condition::ALL
            .iter()
            .map(|c| c.name())
            .collect();
        format!(
            "unknown field condition `{name}`; known: {}",
            names.join(", ")
        )
    })?;
    let origin = a.origin.unwrap_or(crate::runs::simulate::DEFAULT_ORIGIN);
    let outputs = Outputs::new(std::iter::empty(), a.force);
    let (bytes, truths) = crate::runs::field::capture(c, a.run, origin)?;
    outputs.write(&a.out, &bytes, true)?;
    let at: Vec<String> = truths
        .iter()
        .map(|t| format!("({:.0}, {:.0}) m", t.position[0], t.position[1]))
        .collect();
    note(&format!(
        "{} bytes; {}",
        bytes.len(),
        if at.is_empty() {
            "no emitter (the bearings are noise)".to_string()
        } else {
            format!("emitters at {} from the route's first point", at.join(", "))
        }
    ));
    Ok(())
}
