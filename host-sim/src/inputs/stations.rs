//! The stations file (`--stations FILE`, docs/src/formats/files.md): what is known of each DF
//! station of a network before the drive (where it stands, its offset's prior or calibration,
//! its noise, its antenna) and the reference transmitters it hears. Read with a size cap and
//! checked whole when loaded; every error is one line naming the file and the entry.

use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::bias::{BiasPrior, DEFAULT_BIAS_SD, DirectionPrior, HARMONICS};
use foxhunt_core::fix::device::DeviceClass;
use serde::Deserialize;
use std::collections::HashSet;
use std::io::Read;
use std::path::Path;

/// A stations file is refused past this many bytes (ten thousand stations fit in a few
/// hundred kilobytes).
pub const MAX_FILE_BYTES: u64 = 1 << 20;
/// Stations a file may list at most.
pub const MAX_STATIONS: usize = 10_000;
/// Reference transmitters a network may have at most.
pub const MAX_REFERENCES: usize = 64;
/// Longest station id: a KrakenSDR's STATION_ID is kept to this many bytes, so a longer id
/// could never match a record.
pub const MAX_ID_BYTES: usize = foxhunt_bridge::kraken::STATION_LEN;

/// A station's device class by its name in the file (`antenna = "uca"`, ...).
fn class_of(name: Option<&str>, what: &str) -> Result<Option<DeviceClass>, String> {
    let Some(name) = name else { return Ok(None) };
    DeviceClass::from_name(name).map(Some).ok_or_else(|| {
        let names: Vec<&str> = DeviceClass::ALL.iter().map(|c| c.name()).collect();
        format!(
            "{what}: antenna must be one of {}, not `{name}`",
            names.join(", ")
        )
    })
}

/// An unmodelled error's sd from the key (degrees), checked.
fn unmodelled_of(sd: Option<f32>, what: &str) -> Result<Option<f32>, String> {
    match sd {
        None => Ok(None),
        Some(d) if (0.0..=45.0).contains(&d) => Ok(Some(d.to_radians())),
        Some(d) => Err(format!(
            "{what}: unmodelled_deg must lie in [0, 45] degrees, not {d}"
        )),
    }
}

/// One station as the file describes it (the TOML keys).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct StationEntry {
    id: String,
    position: Option<[f64; 2]>,
    offset_deg: Option<f32>,
    offset_sd_deg: Option<f32>,
    calibration_file: Option<String>,
    noise_deg: Option<f32>,
    antenna: Option<String>,
    unmodelled_deg: Option<f32>,
    direction_deg: Option<[f32; HARMONICS]>,
    direction_error_deg: Option<f32>,
    boresight_deg: Option<f32>,
}

/// What applies to every station the file does not list.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct DefaultEntry {
    offset_deg: Option<f32>,
    offset_sd_deg: Option<f32>,
    noise_deg: Option<f32>,
    antenna: Option<String>,
    unmodelled_deg: Option<f32>,
    direction_deg: Option<[f32; HARMONICS]>,
    direction_error_deg: Option<f32>,
    boresight_deg: Option<f32>,
}

/// A reference transmitter as the file describes it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct ReferenceEntry {
    name: Option<String>,
    position: [f64; 2],
    freq_mhz: f64,
}

/// The file's TOML.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FileToml {
    #[serde(default)]
    default: DefaultEntry,
    #[serde(default)]
    station: Vec<StationEntry>,
    #[serde(default)]
    reference: Vec<ReferenceEntry>,
}

/// Where a station's offset prior came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PriorFrom {
    /// The default of an uncalibrated unit (or `--calibration`'s, for every station).
    Default,
    /// The stations file's prior for it (or its `[default]`).
    StationsFile,
    /// A calibration file the stations file names for it.
    Calibration,
}

/// One station: what the file says of it, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct StationSpec {
    /// Its id: a KrakenSDR's STATION_ID, or a unit's `INPUT:KIND` label.
    pub id: String,
    /// Where it stands (replaces its records' positions).
    pub position: Option<LatLon>,
    /// Its offset's prior.
    pub prior: BiasPrior,
    /// Where the prior came from.
    pub from: PriorFrom,
    /// Its bearing noise, radians (replaces the bearings' own sigma; else its class's).
    pub noise: Option<f32>,
    /// Its device class (the file's `antenna`): its noise, ceiling and floor.
    pub antenna: Option<DeviceClass>,
    /// Sd of its unmodelled systematic error, radians (else its class's).
    pub unmodelled: Option<f32>,
    /// Its direction-dependent error's prior (`None`: not modelled).
    pub direction: Option<DirectionPrior>,
    /// Where its antenna faces when it stands still, theta (the file's `boresight_deg`;
    /// `None`: north).
    pub front: Option<f32>,
}

/// A reference transmitter: a known emitter whose bearings calibrate the stations.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Its name in the report.
    pub name: String,
    /// Where it is.
    pub position: LatLon,
    /// Its frequency, MHz: bearings of its channel are calibration, not an emitter to find.
    pub freq_mhz: f64,
}

/// What is known of a network's stations before the drive: the stations file with the
/// `--reference` transmitters added.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Network {
    /// The listed stations.
    pub stations: Vec<StationSpec>,
    /// Prior of a station the file does not list, and where it came from.
    pub default_prior: Option<BiasPrior>,
    /// Noise of a station the file does not list, radians.
    pub default_noise: Option<f32>,
    /// Device class of a station the file does not list.
    pub default_antenna: Option<DeviceClass>,
    /// Unmodelled error's sd of a station the file does not list, radians.
    pub default_unmodelled: Option<f32>,
    /// Direction-dependent error of a station the file does not list.
    pub default_direction: Option<DirectionPrior>,
    /// Antenna front of a station the file does not list, theta.
    pub default_front: Option<f32>,
    /// The reference transmitters.
    pub references: Vec<Reference>,
}

fn lat_lon(p: [f64; 2]) -> Option<LatLon> {
    (p[0].is_finite() && p[1].is_finite() && p[0].abs() <= 90.0 && p[1].abs() <= 180.0).then_some(
        LatLon {
            lat: p[0],
            lon: p[1],
        },
    )
}

/// A direction-dependent error's prior from the keys (coefficients a_1, b_1, a_2, b_2 and the
/// sd of each, degrees), checked; `None` when neither is given.
pub fn direction_of(
    mean: Option<[f32; HARMONICS]>,
    sd: Option<f32>,
    what: &str,
) -> Result<Option<DirectionPrior>, String> {
    if mean.is_none() && sd.is_none() {
        return Ok(None);
    }
    let mean = mean.unwrap_or([0.0; HARMONICS]);
    if !mean.iter().all(|c| c.is_finite() && c.abs() <= 45.0) {
        return Err(format!(
            "{what}: direction_deg wants four coefficients in [-45, 45] degrees (a1, b1, a2, b2), not {mean:?}"
        ));
    }
    let sd = sd.unwrap_or(0.0);
    if !(0.0..=45.0).contains(&sd) {
        return Err(format!(
            "{what}: direction_error_deg must lie in [0, 45] degrees (0: the table is known), not {sd}"
        ));
    }
    Ok(Some(DirectionPrior {
        mean: mean.map(f32::to_radians),
        sd: sd.to_radians(),
    }))
}

/// A fixed antenna's front from `boresight_deg` (true, clockwise from north), as theta.
fn front_of(boresight: Option<f32>, what: &str) -> Result<Option<f32>, String> {
    match boresight {
        None => Ok(None),
        Some(b) if b.is_finite() && (-360.0..=360.0).contains(&b) => {
            Ok(Some(std::f32::consts::FRAC_PI_2 - b.to_radians()))
        }
        Some(b) => Err(format!(
            "{what}: boresight_deg must lie in [-360, 360] degrees, not {b}"
        )),
    }
}

/// An offset prior from the keys (degrees), checked; `None` when neither is given.
fn prior_of(mean: Option<f32>, sd: Option<f32>, what: &str) -> Result<Option<BiasPrior>, String> {
    if mean.is_none() && sd.is_none() {
        return Ok(None);
    }
    let mean = mean.unwrap_or(0.0);
    let sd = sd.unwrap_or(DEFAULT_BIAS_SD.to_degrees());
    if !(mean.is_finite() && mean.abs() <= 180.0) {
        return Err(format!(
            "{what}: offset_deg must lie in [-180, 180], not {mean}"
        ));
    }
    if !(sd >= 0.0) {
        return Err(format!(
            "{what}: offset_sd_deg must be >= 0 (0: calibrated; inf: no prior), not {sd}"
        ));
    }
    Ok(Some(BiasPrior {
        mean: mean.to_radians(),
        sd: sd.to_radians(),
    }))
}

fn noise_of(noise: Option<f32>, what: &str) -> Result<Option<f32>, String> {
    match noise {
        None => Ok(None),
        Some(n) if n > 0.0 && n < 90.0 => Ok(Some(n.to_radians())),
        Some(n) => Err(format!(
            "{what}: noise_deg must lie between 0 and 90 degrees, not {n}"
        )),
    }
}

/// Parse `LAT,LON@MHZ` (a `--reference`).
pub fn parse_reference(text: &str) -> Result<Reference, String> {
    // Echoed escaped: an error is one line, whatever the value held.
    let bad = || {
        format!(
            "--reference wants LAT,LON@MHZ in decimal degrees and MHz, not `{}`",
            text.escape_debug()
        )
    };
    let (at, mhz) = text.split_once('@').ok_or_else(bad)?;
    let (lat, lon) = at.split_once(',').ok_or_else(bad)?;
    let p = [
        lat.trim().parse::<f64>().map_err(|_| bad())?,
        lon.trim().parse::<f64>().map_err(|_| bad())?,
    ];
    let freq_mhz: f64 = mhz.trim().parse().map_err(|_| bad())?;
    let position = lat_lon(p).ok_or_else(bad)?;
    if !(freq_mhz > 0.0 && freq_mhz.is_finite()) {
        return Err(format!(
            "--reference: the frequency must be a positive number of MHz, not {}",
            mhz.escape_debug()
        ));
    }
    Ok(Reference {
        name: format!("{:.5},{:.5}@{freq_mhz}", p[0], p[1]),
        position,
        freq_mhz,
    })
}

impl Network {
    /// Load and check a stations file; errors name the file.
    pub fn load(path: &Path) -> Result<Self, String> {
        let name = path.display();
        let file = std::fs::File::open(path).map_err(|e| format!("cannot read {name}: {e}"))?;
        if !file.metadata().is_ok_and(|m| m.is_file()) {
            return Err(format!("{name}: a stations file must be a regular file"));
        }
        let mut text = String::new();
        file.take(MAX_FILE_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(|e| format!("cannot read {name}: {e}"))?;
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(format!(
                "{name}: a stations file holds at most {MAX_FILE_BYTES} bytes"
            ));
        }
        let toml: FileToml =
            crate::inputs::files::parse_toml(&text).map_err(|e| format!("{name}: {e}"))?;
        Self::from_toml(toml, path.parent().unwrap_or(Path::new(".")))
            .map_err(|e| format!("{name}: {e}"))
    }

    /// The network of a stations file's `text` (calibration files relative to the working
    /// directory): the tests' stations files, without a file.
    #[cfg(test)]
    pub(crate) fn from_text(text: &str) -> Result<Self, String> {
        Self::from_toml(crate::inputs::files::parse_toml(text)?, Path::new("."))
    }

    /// The checked network of a parsed file (calibration files relative to `dir`).
    fn from_toml(t: FileToml, dir: &Path) -> Result<Self, String> {
        if t.station.len() > MAX_STATIONS {
            return Err(format!("more than {MAX_STATIONS} stations"));
        }
        if t.reference.len() > MAX_REFERENCES {
            return Err(format!("more than {MAX_REFERENCES} reference transmitters"));
        }
        let mut seen = HashSet::new();
        let mut stations = Vec::with_capacity(t.station.len());
        for (k, s) in t.station.into_iter().enumerate() {
            let what = format!("station {} (`{}`)", k + 1, s.id);
            if s.id.is_empty() || s.id.len() > MAX_ID_BYTES {
                return Err(format!(
                    "{what}: an id has 1 to {MAX_ID_BYTES} bytes (KrakenSDR ids are cut there)"
                ));
            }
            if !seen.insert(s.id.clone()) {
                return Err(format!("{what}: listed twice"));
            }
            let position = match s.position {
                None => None,
                Some(p) => Some(lat_lon(p).ok_or_else(|| {
                    format!("{what}: position wants [latitude, longitude] in degrees, not {p:?}")
                })?),
            };
            let given = prior_of(s.offset_deg, s.offset_sd_deg, &what)?;
            // A calibration file's direction-dependent error, where it measured one.
            let mut calibrated_direction = None;
            let (prior, from) = match (&s.calibration_file, given) {
                (Some(_), Some(_)) => {
                    return Err(format!(
                        "{what}: give offset_deg/offset_sd_deg or calibration_file, not both"
                    ));
                }
                (Some(f), None) => {
                    let c = crate::inputs::calibration::Calibration::load(&dir.join(f))
                        .map_err(|e| format!("{what}: {e}"))?;
                    calibrated_direction = c.direction();
                    (c.prior(), PriorFrom::Calibration)
                }
                (None, Some(p)) => (p, PriorFrom::StationsFile),
                (None, None) => {
                    match prior_of(t.default.offset_deg, t.default.offset_sd_deg, "default")? {
                        Some(p) => (p, PriorFrom::StationsFile),
                        None => (BiasPrior::default(), PriorFrom::Default),
                    }
                }
            };
            stations.push(StationSpec {
                id: s.id,
                position,
                prior,
                from,
                noise: noise_of(s.noise_deg, &what)?,
                antenna: class_of(s.antenna.as_deref(), &what)?,
                unmodelled: unmodelled_of(s.unmodelled_deg, &what)?,
                direction: match (
                    direction_of(s.direction_deg, s.direction_error_deg, &what)?,
                    calibrated_direction,
                ) {
                    (Some(_), Some(_)) => {
                        return Err(format!(
                            "{what}: its calibration_file measured the direction-dependent \
                             error; give direction_deg/direction_error_deg or that file, not both"
                        ));
                    }
                    (stated, measured) => stated.or(measured),
                },
                front: front_of(s.boresight_deg, &what)?,
            });
        }
        let mut references = Vec::with_capacity(t.reference.len());
        for (k, r) in t.reference.into_iter().enumerate() {
            let what = format!("reference {}", k + 1);
            let position = lat_lon(r.position).ok_or_else(|| {
                format!(
                    "{what}: position wants [latitude, longitude] in degrees, not {:?}",
                    r.position
                )
            })?;
            if !(r.freq_mhz > 0.0 && r.freq_mhz.is_finite()) {
                return Err(format!(
                    "{what}: freq_mhz must be a positive number, not {}",
                    r.freq_mhz
                ));
            }
            references.push(Reference {
                name: r.name.unwrap_or_else(|| format!("reference {}", k + 1)),
                position,
                freq_mhz: r.freq_mhz,
            });
        }
        Ok(Self {
            stations,
            default_prior: prior_of(t.default.offset_deg, t.default.offset_sd_deg, "default")?,
            default_noise: noise_of(t.default.noise_deg, "default")?,
            default_antenna: class_of(t.default.antenna.as_deref(), "default")?,
            default_unmodelled: unmodelled_of(t.default.unmodelled_deg, "default")?,
            default_direction: direction_of(
                t.default.direction_deg,
                t.default.direction_error_deg,
                "default",
            )?,
            default_front: front_of(t.default.boresight_deg, "default")?,
            references,
        })
    }

    /// What the file says of station `id`, if it lists it.
    pub fn station(&self, id: &str) -> Option<&StationSpec> {
        self.stations.iter().find(|s| s.id == id)
    }

    /// Add a `--reference`; errors past [`MAX_REFERENCES`].
    pub fn add_reference(&mut self, r: Reference) -> Result<(), String> {
        if self.references.len() >= MAX_REFERENCES {
            return Err(format!("more than {MAX_REFERENCES} reference transmitters"));
        }
        self.references.push(r);
        Ok(())
    }

    /// The file's text for a network (what `foxhunt simulate --condition network-*` writes
    /// beside its capture).
    pub fn to_toml(&self) -> String {
        use std::fmt::Write;
        let mut out = String::new();
        let deg = |r: f32| r.to_degrees();
        let mut default = String::new();
        if let Some(p) = self.default_prior {
            let _ = writeln!(
                default,
                "offset_deg = {}\noffset_sd_deg = {}",
                deg(p.mean),
                deg(p.sd)
            );
        }
        if let Some(n) = self.default_noise {
            let _ = writeln!(default, "noise_deg = {:.3}", deg(n));
        }
        if let Some(a) = self.default_antenna {
            let _ = writeln!(default, "antenna = {:?}", a.name());
        }
        if let Some(u) = self.default_unmodelled {
            let _ = writeln!(default, "unmodelled_deg = {}", deg(u));
        }
        write_direction(&mut default, self.default_direction, self.default_front);
        if !default.is_empty() {
            let _ = writeln!(out, "[default]\n{default}");
        }
        for s in &self.stations {
            let _ = writeln!(out, "[[station]]\nid = {:?}", s.id);
            if let Some(p) = s.position {
                let _ = writeln!(out, "position = [{:.7}, {:.7}]", p.lat, p.lon);
            }
            let _ = writeln!(
                out,
                "offset_deg = {}\noffset_sd_deg = {}",
                deg(s.prior.mean),
                deg(s.prior.sd)
            );
            if let Some(n) = s.noise {
                let _ = writeln!(out, "noise_deg = {:.3}", deg(n));
            }
            if let Some(a) = s.antenna {
                let _ = writeln!(out, "antenna = {:?}", a.name());
            }
            if let Some(u) = s.unmodelled {
                let _ = writeln!(out, "unmodelled_deg = {}", deg(u));
            }
            write_direction(&mut out, s.direction, s.front);
            out.push('\n');
        }
        for r in &self.references {
            let _ = writeln!(
                out,
                "[[reference]]\nname = {:?}\nposition = [{:.7}, {:.7}]\nfreq_mhz = {}\n",
                r.name, r.position.lat, r.position.lon, r.freq_mhz
            );
        }
        out
    }
}

/// The direction-dependent error's keys of a station (or the default) into `out`.
pub fn write_direction(out: &mut String, direction: Option<DirectionPrior>, front: Option<f32>) {
    use std::fmt::Write;
    if let Some(d) = direction {
        let c = d.mean.map(f32::to_degrees);
        let _ = writeln!(
            out,
            "direction_deg = [{}, {}, {}, {}]\ndirection_error_deg = {}",
            c[0],
            c[1],
            c[2],
            c[3],
            d.sd.to_degrees()
        );
    }
    if let Some(f) = front {
        let _ = writeln!(
            out,
            "boresight_deg = {}",
            (std::f32::consts::FRAC_PI_2 - f).to_degrees()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Network, String> {
        Network::from_text(text)
    }

    #[test]
    fn a_direction_dependent_error_reads_back_and_bad_values_are_one_line() {
        let text = r#"
[default]
direction_error_deg = 2.0

[[station]]
id = "mast"
direction_deg = [1.0, -0.5, 0.25, 0.0]
direction_error_deg = 0.0
boresight_deg = 90.0

[[station]]
id = "car"
"#;
        let n = parse(text).expect("a network");
        let mast = n.station("mast").expect("mast");
        let d = mast.direction.expect("stated");
        assert!((d.mean[0].to_degrees() - 1.0).abs() < 1e-5 && d.sd == 0.0);
        // Boresight east: theta 0.
        assert!(mast.front.expect("stated").abs() < 1e-6);
        assert_eq!(n.station("car").and_then(|s| s.direction), None);
        let default = n.default_direction.expect("default");
        assert!((default.sd.to_degrees() - 2.0).abs() < 1e-5);
        let again = parse(&n.to_toml()).expect("its own text");
        assert_eq!(again.station("mast").and_then(|s| s.direction), Some(d));
        assert_eq!(again.default_direction, Some(default));
        assert!(
            again
                .station("mast")
                .and_then(|s| s.front)
                .expect("front")
                .abs()
                < 1e-5
        );
        for bad in [
            "[[station]]\nid = \"a\"\ndirection_error_deg = -1.0\n",
            "[[station]]\nid = \"a\"\ndirection_deg = [90.0, 0.0, 0.0, 0.0]\n",
            "[[station]]\nid = \"a\"\nboresight_deg = 1000.0\n",
        ] {
            let e = parse(bad).expect_err(bad);
            assert!(!e.contains('\n') && e.contains("station 1"), "{e}");
        }
    }

    #[test]
    fn a_network_reads_back_what_it_writes() {
        let text = r#"
[default]
offset_sd_deg = 4.0

[[station]]
id = "north"
position = [47.07, 8.0]
offset_deg = 1.0
offset_sd_deg = 3.0
noise_deg = 2.0
antenna = "uca"

[[station]]
id = "car-1"

[[station]]
id = "hall"
antenna = "indoor-aoa"
unmodelled_deg = 0.5

[[reference]]
name = "tower"
position = [47.05, 8.03]
freq_mhz = 145.5
"#;
        let n = parse(text).expect("a network");
        assert_eq!(n.stations.len(), 3);
        let hall = n.station("hall").expect("hall");
        assert_eq!(hall.antenna, Some(DeviceClass::IndoorAoa));
        assert!((hall.unmodelled.unwrap_or(0.0).to_degrees() - 0.5).abs() < 1e-5);
        let north = n.station("north").expect("north");
        assert_eq!(north.from, PriorFrom::StationsFile);
        assert!((north.prior.sd.to_degrees() - 3.0).abs() < 1e-5);
        assert!((north.noise.unwrap_or(0.0).to_degrees() - 2.0).abs() < 1e-5);
        // An entry without a prior takes the file's default.
        let car = n.station("car-1").expect("car");
        assert!((car.prior.sd.to_degrees() - 4.0).abs() < 1e-5);
        assert_eq!(n.references[0].freq_mhz, 145.5);
        let again = parse(&n.to_toml()).expect("its own text");
        assert_eq!(again.stations.len(), 3);
        assert_eq!(again.station("hall"), n.station("hall"));
        assert_eq!(again.references, n.references);
    }

    #[test]
    fn bad_entries_are_one_line_errors_naming_them() {
        for (text, says) in [
            ("[[station]]\nid = \"\"", "1 to 16 bytes"),
            (
                "[[station]]\nid = \"a\"\n[[station]]\nid = \"a\"",
                "listed twice",
            ),
            (
                "[[station]]\nid = \"a\"\noffset_sd_deg = -1.0",
                "offset_sd_deg",
            ),
            ("[[station]]\nid = \"a\"\noffset_deg = 400.0", "offset_deg"),
            (
                "[[station]]\nid = \"a\"\nposition = [91.0, 0.0]",
                "position",
            ),
            ("[[station]]\nid = \"a\"\nnoise_deg = 0.0", "noise_deg"),
            ("[[station]]\nid = \"a\"\ncolour = 1", "unknown field"),
            ("[[station]]\nid = \"a\"\nantenna = \"dish\"", "indoor-aoa"),
            (
                "[[station]]\nid = \"a\"\nunmodelled_deg = -1.0",
                "unmodelled_deg",
            ),
            ("[default]\nantenna = \"dish\"", "antenna"),
            (
                "[[reference]]\nposition = [47.0, 8.0]\nfreq_mhz = -1.0",
                "freq_mhz",
            ),
            (
                "[[station]]\nid = \"a\"\noffset_deg = 1.0\ncalibration_file = \"x\"",
                "not both",
            ),
        ] {
            let e = parse(text).expect_err(text);
            assert!(e.contains(says) && !e.contains('\n'), "{text}: {e}");
        }
        assert!(parse_reference("47.0,8.0@145.5").is_ok());
        // A value holding a line break is echoed escaped: the error stays one line.
        for bad in [
            "47.0,8.0",
            "47.0@145",
            "95,8@1",
            "47,8@0",
            "47,8@x",
            "47,8@1\nx",
        ] {
            let e = parse_reference(bad).expect_err(bad);
            assert!(!e.contains('\n'), "{bad:?}: {e}");
        }
    }
}
