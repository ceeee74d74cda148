//! The bridge's settings.

use crate::kraken::CsvConvention;
use crate::mt::LinkQualityMap;
use crate::nmea::LatLon;
use foxhunt_core::preprocess::DEFAULT_MIN_QUALITY;

/// How a bearing's DF quality sets its noise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum QualityWeighting {
    /// Every bearing that passes the gate gets the configured sigma.
    #[default]
    Uniform,
    /// Seed 002's error weight W(Q) (eq. 20, reconstructed in the core) widens the noise:
    /// sigma (1 + W(Q)), up to 1.4 sigma near the gate.
    ErrorWeight,
}

/// Bridge settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeConfig {
    /// Local origin; `None` takes the first valid fix.
    pub reference: Option<LatLon>,
    /// A bearing needs a fix within this many milliseconds of its time.
    pub max_fix_gap_ms: u32,
    /// Bearings with quality at or below this are rejected.
    pub min_quality: f32,
    /// Bearing noise standard deviation, radians.
    pub sigma_rad: f32,
    /// Quality weighting.
    pub weighting: QualityWeighting,
    /// Link quality to dBm.
    pub link_quality: LinkQualityMap,
    /// Magnetic declination, degrees east, for HDG without a variation and for HDM; `None`:
    /// such headings are not used.
    pub declination_deg: Option<f32>,
    /// The DF antenna's mounting offset, degrees clockwise from the vehicle's front, added to
    /// every relative bearing.
    pub mount_offset_deg: f32,
    /// A heading sentence (HDT, THS, HDG, HDM) is fresh for this long, ms.
    pub heading_max_age_ms: u32,
    /// Course over ground turns bearings only at this speed or more, m/s...
    pub course_min_speed_mps: f32,
    /// ...held for this long, ms.
    pub course_hold_ms: u32,
    /// Which way the Kraken CSV's bearing turns (the 2023-05 to 2024-07 builds differ).
    pub kraken_convention: CsvConvention,
    /// Kraken bearings need this confidence or more, in the XML's CONF units
    /// (int(confidence × 100); df-aggregator's default minimum is 10).
    pub kraken_min_conf: f32,
    /// Agrelo bearings need this quality digit or more (0 is "unusable").
    pub agrelo_min_quality: u8,
    /// Fixes are kept this long behind the newest, ms, so a bearing this late is still
    /// placed (within the [`FIX_HISTORY`](super::FIX_HISTORY) capacity, see [`Bridge`](super::Bridge)).
    pub fix_span_ms: u32,
    /// Bearings turned by a heading are rejected while the vehicle turns faster than this,
    /// degrees per second (`None`: no gate). docs/src/formats/bridge.md: 2 deg/s cut a 0.5 s latency's 42 m
    /// shift of the fix to 7.6 m.
    pub yaw_gate_deg_s: Option<f32>,
    /// The yaw rate is the heading's change over at least this long, ms.
    pub yaw_window_ms: u32,
    /// The records' times were already judged on their source's clock by the station's own
    /// bridge (a broker's bearings, which `foxhunt publish` decoded): each passes at once, in
    /// whatever order the broker delivers them (a bearing redelivered after an outage comes
    /// after later ones), instead of waiting for its source's next record (the bridge's `clock`).
    pub judged_clocks: bool,
}

impl Default for BridgeConfig {
    fn default() -> Self {
        Self {
            reference: None,
            max_fix_gap_ms: 2000,
            min_quality: DEFAULT_MIN_QUALITY,
            sigma_rad: 1.0f32.to_radians(),
            weighting: QualityWeighting::Uniform,
            link_quality: LinkQualityMap::default(),
            declination_deg: None,
            mount_offset_deg: 0.0,
            heading_max_age_ms: 2000,
            course_min_speed_mps: 2.0,
            course_hold_ms: 3000,
            kraken_convention: CsvConvention::Clockwise,
            kraken_min_conf: 10.0,
            agrelo_min_quality: 1,
            fix_span_ms: 5000,
            yaw_gate_deg_s: Some(2.0),
            yaw_window_ms: 1000,
            judged_clocks: false,
        }
    }
}
