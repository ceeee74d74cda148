//! The stations of a drive as `locate` reports them (the `--json` `stations` array; field
//! names are stable): who each is, where it stood, and its offset with where that came from.

use crate::estimate::direction::FoundDirection;
use crate::estimate::stations::{PriorOrigin, ReferenceFix, StationSetup};
use crate::inputs::capture::Decoded;
use crate::inputs::stations::{Network, Reference};
use foxhunt_core::fix::locate::StationOffset;
use serde::Serialize;
use std::fmt::Write;

/// A station's offset measured on a reference transmitter's channel.
#[derive(Debug, Clone, Serialize)]
pub struct ReferenceReport {
    /// The reference's name.
    pub reference: String,
    /// The offset measured, degrees.
    pub offset_deg: f32,
    /// Its standard deviation, degrees.
    pub offset_sd_deg: f32,
    /// The bearings' noise there, degrees.
    pub noise_deg: f32,
    /// Bearings used.
    pub bearings: u32,
    /// Its direction-dependent error measured there, coefficients a1, b1, a2, b2, degrees
    /// (null: its bearings did not span enough directions relative to its antenna).
    pub direction_deg: Option<[f32; 4]>,
    /// One sd for the four, degrees.
    pub direction_error_deg: Option<f32>,
    /// How evenly its bearings spanned the directions (0.5 an even full turn; the harmonics
    /// are measured from 0.1).
    pub direction_span: Option<f32>,
}

/// A direction-dependent error no one stated, found in the station's residuals about a fix
/// and modelled in the fix reported (docs/src/field.md, "Direction-dependent error").
#[derive(Debug, Clone, Serialize)]
pub struct FoundReport {
    /// The coefficients a1, b1, a2, b2 the residuals showed, degrees (zero along the
    /// combinations the drive did not determine).
    pub direction_deg: [f32; 4],
    /// The first and second harmonic's amplitudes, degrees.
    pub amplitudes_deg: [f32; 2],
    /// The test's statistic: chi-square with `tested` degrees of freedom where there is no
    /// such error.
    pub chi2: f32,
    /// Combinations of the coefficients the drive determined, and so tested.
    pub tested: usize,
    /// The prior sd of each coefficient the fix then modelled them with, degrees.
    pub modelled_sd_deg: f32,
    /// The channel of the fix whose residuals showed it (its lowest frequency, MHz; null for
    /// bearings without one).
    pub channel_mhz: Option<f32>,
}

impl From<&FoundDirection> for FoundReport {
    fn from(f: &FoundDirection) -> Self {
        Self {
            direction_deg: f.coefficients.map(f32::to_degrees),
            amplitudes_deg: f.amplitudes().map(f32::to_degrees),
            chi2: f.chi2,
            tested: f.rank,
            modelled_sd_deg: f.prior_sd.to_degrees(),
            channel_mhz: f.channel_mhz,
        }
    }
}

/// One station (field names are stable).
#[derive(Debug, Clone, Serialize)]
pub struct StationReport {
    /// Its id: a KrakenSDR's STATION_ID, or a unit's record kind (`INPUT:KIND` with several
    /// capture files).
    pub id: String,
    /// Whether its records name it.
    pub named: bool,
    /// Whether it never moved (or stands at a surveyed position).
    pub fixed: bool,
    /// Where it stood (its first bearing, or its surveyed position), degrees.
    pub lat: Option<f64>,
    /// Longitude, degrees.
    pub lon: Option<f64>,
    /// Bearings decoded.
    pub bearings: u32,
    /// Its noise as the stations file states it, degrees.
    pub noise_deg: Option<f32>,
    /// Its device class as the stations file states it.
    pub antenna: Option<&'static str>,
    /// Sd of its unmodelled systematic error (its class's or the file's), degrees.
    pub unmodelled_deg: f32,
    /// The prior its offset had, degrees, and where that came from.
    pub prior_deg: f32,
    /// The prior's standard deviation, degrees.
    pub prior_sd_deg: f32,
    /// Where the prior came from: default, calibration, stations-file, station-calibration or
    /// reference.
    pub prior_from: PriorOrigin,
    /// Its offset as the fix holding most of its bearings estimated it, degrees (the prior's
    /// where no fix used it).
    pub offset_deg: f32,
    /// Its standard deviation, degrees.
    pub offset_sd_deg: f32,
    /// Share of the offset's information that fix's bearings gave (null: no fix used it).
    pub measured: Option<f32>,
    /// Where the offset came from: `estimated` (the fix's bearings measured most of it),
    /// else the prior's origin.
    pub offset_from: &'static str,
    /// Its measurements on reference transmitters' channels.
    pub references: Vec<ReferenceReport>,
    /// A direction-dependent error no one stated that its residuals showed (null: none
    /// stated and none found, or one stated).
    pub direction_found: Option<FoundReport>,
}

/// The word for where an offset came from.
fn origin_word(o: PriorOrigin) -> &'static str {
    match o {
        PriorOrigin::Default => "default",
        PriorOrigin::Calibration => "calibration",
        PriorOrigin::StationsFile => "stations-file",
        PriorOrigin::StationCalibration => "station-calibration",
        PriorOrigin::Reference => "reference",
    }
}

/// What the fixes found of the stations: each one's offset among `offsets` (every
/// emitter's), and the direction-dependent errors no one stated (`found`).
#[derive(Debug, Clone, Copy, Default)]
pub struct Found<'a> {
    /// Every emitter's per-station offsets.
    pub offsets: &'a [StationOffset],
    /// The direction-dependent errors found.
    pub directions: &'a [FoundDirection],
}

/// Every station of `d` with the priors of `setup`, each station's offset from the fix
/// holding most of its bearings among `found`'s offsets, the direction-dependent error found
/// in its residuals, and its reference measurements among `fixes`.
pub fn station_reports(
    d: &Decoded,
    network: Option<&Network>,
    setup: &StationSetup,
    found: Found<'_>,
    fixes: &[ReferenceFix],
    references: &[Reference],
) -> Vec<StationReport> {
    d.stations
        .iter()
        .enumerate()
        .filter(|(_, s)| s.bearings > 0)
        .map(|(i, s)| {
            let spec = network.and_then(|n| n.station(&s.id));
            let prior = setup.priors.of(i);
            let from = setup
                .origins
                .get(i)
                .copied()
                .unwrap_or(PriorOrigin::Default);
            let best = found
                .offsets
                .iter()
                .filter(|o| usize::from(o.station) == i)
                .max_by_key(|o| o.used);
            let (offset, sd, measured) = match best {
                Some(o) => (o.bias, o.sd, Some(o.measured)),
                None => (prior.mean, prior.sd, None),
            };
            let offset_from = if measured.is_some_and(|m| m >= 0.5) {
                "estimated"
            } else {
                origin_word(from)
            };
            StationReport {
                id: s.id.clone(),
                named: s.named,
                fixed: s.fixed,
                lat: s.position.map(|p| p.lat),
                lon: s.position.map(|p| p.lon),
                bearings: s.bearings,
                noise_deg: setup.noise.get(i).copied().flatten().map(f32::to_degrees),
                antenna: spec
                    .and_then(|s| s.antenna)
                    .or(network.and_then(|n| n.default_antenna))
                    .map(|c| c.name()),
                unmodelled_deg: setup.priors.unmodelled_of(i).to_degrees(),
                prior_deg: prior.mean.to_degrees(),
                prior_sd_deg: prior.sd.to_degrees(),
                prior_from: from,
                offset_deg: offset.to_degrees(),
                offset_sd_deg: sd.to_degrees(),
                measured,
                offset_from,
                references: fixes
                    .iter()
                    .filter(|f| usize::from(f.station) == i)
                    .map(|f| ReferenceReport {
                        reference: references
                            .get(f.reference)
                            .map_or_else(String::new, |r| r.name.clone()),
                        offset_deg: f.calibration.bias.to_degrees(),
                        offset_sd_deg: f.calibration.sd.to_degrees(),
                        noise_deg: f.calibration.sigma.to_degrees(),
                        bearings: f.calibration.used,
                        direction_deg: f.direction.map(|d| d.mean.map(f32::to_degrees)),
                        direction_error_deg: f.direction.map(|d| d.sd.to_degrees()),
                        direction_span: f.span,
                    })
                    .collect(),
                direction_found: found
                    .directions
                    .iter()
                    .find(|f| usize::from(f.station) == i)
                    .map(FoundReport::from),
            }
        })
        .collect()
}

impl StationReport {
    /// The station in one line of the text report.
    pub fn line(&self, out: &mut String) {
        let place = match (self.lat, self.lon) {
            (Some(lat), Some(lon)) => format!(" at {lat:.5}, {lon:.5}"),
            _ => String::new(),
        };
        let motion = if self.fixed { "fixed" } else { "mobile" };
        let measured = self
            .measured
            .map(|m| format!(", {:.0} % measured by the fix", 100.0 * m))
            .unwrap_or_default();
        let _ = write!(
            out,
            "  {} ({motion}{place}): {} bearings; offset {:.2} +- {:.2} deg ({}{measured})",
            self.id,
            self.bearings,
            self.offset_deg,
            self.offset_sd_deg,
            self.offset_from.replace('-', " ")
        );
        for r in &self.references {
            let _ = write!(
                out,
                "; on {}: {:.2} +- {:.2} deg, {} bearings",
                r.reference, r.offset_deg, r.offset_sd_deg, r.bearings
            );
            match (r.direction_deg, r.direction_error_deg) {
                (Some(c), Some(sd)) => {
                    let _ = write!(
                        out,
                        ", direction-dependent a1 {:.2} b1 {:.2} a2 {:.2} b2 {:.2} +- {sd:.2} deg",
                        c[0], c[1], c[2], c[3]
                    );
                }
                _ => out.push_str(", offset only"),
            }
        }
        if let Some(f) = &self.direction_found {
            let _ = write!(
                out,
                "; its bearings follow their direction relative to it (harmonics of {:.1} and \
                 {:.1} deg, chi-square {:.0} on {}): a direction-dependent error, modelled \
                 at {:.1} deg a coefficient; calibrate it (`locate --calibrate`)",
                f.amplitudes_deg[0], f.amplitudes_deg[1], f.chi2, f.tested, f.modelled_sd_deg
            );
        }
        out.push('\n');
    }
}
