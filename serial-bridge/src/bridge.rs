//! The bridge: decoded frames in, core measurements out.
//!
//! GPS fixes (GGA, RMC, GLL, GNS) become vehicle positions in the local frame (origin: the
//! configured reference, or the first valid fix). A bearing (PFOXB, Agrelo, KrakenSDR CSV or
//! XML) is placed at its own position when the record carries one (Kraken), else where the
//! vehicle was at the bearing's time, interpolated between the fixes around it, so a DF unit
//! that reports half a second after the GPS does not smear the fix along the route; a bearing
//! newer than the latest fix waits for the next one, and one with no fix within the configured
//! gap is rejected. Link-quality frames from known anchors become RSSI readings. Everything
//! rejected is counted by reason.
//!
//! Times: the bridge's clock is UTC time of day from the sentences, unwrapped across midnight.
//! An Agrelo record has no time: it takes the clock's time when it arrives (the latest GPS
//! sentence's). A Kraken record's epoch milliseconds (the unit's clock) are taken modulo a day.
//!
//! Relative bearings are turned to true by one rule, [`Bridge::heading_at`]: a fresh true
//! heading (HDT, THS) > the record's own heading (Kraken) > a fresh magnetic heading (HDG,
//! HDM) corrected to true by its own variation, else the configured declination > the course
//! over ground once the speed has stayed above a gate for a time (KrakenSDR's 2 m/s for 3 s by
//! default) > none: the bearing is rejected and counted "no heading". The mounting offset of
//! the DF antenna is added in the same place; each bearing records which source turned it.
//!
//! Geometry and time (FIELD.md): a true azimuth is measured from north at the vehicle, which
//! is not the local frame's north once the vehicle is kilometres from the origin (the
//! meridians converge by about Δλ·sin φ), so every bearing is carried into the frame exactly
//! ([`LocalFrame::azimuth_to_local`]) at the vehicle's own latitude and longitude. The fixes
//! are kept by time span, [`BridgeConfig::fix_span_ms`] behind the newest, in a history of
//! [`FIX_HISTORY`] fixes, so a DF unit reporting seconds behind a 10 Hz GPS is still placed
//! where the vehicle was; a bearing older than the fixes kept is counted `late`, never
//! placed at the wrong spot. A bearing the bridge turned by a heading is rejected (counted
//! `turning`) while the vehicle turns faster than [`BridgeConfig::yaw_gate_deg_s`]: a
//! GPS-DF delay δ turns into a bearing error ω·δ at yaw rate ω, and a DF unit averaging over
//! a turn mixes bearings taken at different headings.

use crate::agrelo::Agrelo;
use crate::geo::{GeoError, LocalFrame};
use crate::kraken::CsvConvention;
use crate::mt::{AfIncomingMsg, LinkQualityMap, MtError};
use crate::nmea::{KNOT_MPS, LatLon, NmeaError, Reference, Sentence, UtcTime};
use crate::stream::{DEFAULT_CAPACITY, Demux, Frame, StreamCounters};
use foxhunt_core::Bearing;
use foxhunt_core::preprocess::{DEFAULT_MIN_QUALITY, error_weight};
use heapless::Deque;

const DAY_MS: i64 = 86_400_000;

/// Degrees to [0, 360), for sums of a few angles (no fmod linked).
fn wrap_deg(x: f64) -> f64 {
    let mut a = x;
    for _ in 0..4 {
        if a >= 360.0 {
            a -= 360.0;
        } else if a < 0.0 {
            a += 360.0;
        }
    }
    if (0.0..360.0).contains(&a) { a } else { 0.0 }
}

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
    /// placed (within the [`FIX_HISTORY`] capacity, see [`Bridge`]).
    pub fix_span_ms: u32,
    /// Bearings turned by a heading are rejected while the vehicle turns faster than this,
    /// degrees per second (`None`: no gate). FIELD.md: 2 deg/s cut a 0.5 s latency's 42 m
    /// shift of the fix to 7.6 m.
    pub yaw_gate_deg_s: Option<f32>,
    /// The yaw rate is the heading's change over at least this long, ms.
    pub yaw_window_ms: u32,
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
        }
    }
}

/// What turned a bearing to true.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HeadingSource {
    /// The bearing came true: nothing turned it.
    TrueBearing,
    /// A fresh true heading sentence (HDT, THS).
    TrueHeading,
    /// The record's own heading (KrakenSDR).
    Record,
    /// A fresh magnetic heading (HDG, HDM) corrected to true.
    Magnetic,
    /// Course over ground above the speed gate.
    Course,
}

/// Which kind of record a bearing came in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BearingKind {
    /// `$PFOXB`.
    Pfoxb,
    /// Agrelo `%BBB/Q`.
    Agrelo,
    /// KrakenSDR CSV.
    KrakenCsv,
    /// KrakenSDR / KerberosSDR XML.
    KrakenXml,
}

/// A vehicle fix in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleFix {
    /// Milliseconds on the bridge's continuous UTC clock (days counted from the first time).
    pub time_ms: i64,
    /// Position as received.
    pub position: LatLon,
    /// Position in the local frame (east, north), metres.
    pub local: [f32; 2],
    /// Speed over ground, m/s (RMC only).
    pub speed_mps: Option<f32>,
    /// Course over ground, degrees true (RMC only).
    pub course_deg: Option<f32>,
}

/// A bearing ready for the core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BearingMeasurement {
    /// Time of the bearing on the bridge's clock, ms.
    pub time_ms: i64,
    /// The bearing in the local frame.
    pub bearing: Bearing,
    /// DF quality, 0-100.
    pub quality: f32,
    /// Frequency, MHz (0 when the format has none: Agrelo).
    pub freq_mhz: f64,
    /// The record kind.
    pub kind: BearingKind,
    /// What turned it to true.
    pub heading: HeadingSource,
}

/// An RSSI reading from a known anchor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RssiReading {
    /// Index of the anchor in the bridge's table.
    pub anchor: usize,
    /// The anchor's short address.
    pub src_addr: u16,
    /// Link quality as received.
    pub link_quality: u8,
    /// RSSI, dBm.
    pub dbm: f32,
    /// The receiver's timestamp.
    pub timestamp: u32,
}

/// What the bridge hands on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// A new vehicle fix (one per GPS epoch: GGA and RMC of the same second merge).
    Fix(VehicleFix),
    /// A bearing placed in the local frame.
    Bearing(BearingMeasurement),
    /// An RSSI reading.
    Rssi(RssiReading),
}

/// Frames and measurements the bridge rejected, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BridgeCounters {
    /// Vehicle fixes accepted (epochs).
    pub fixes: u32,
    /// Bearings handed on.
    pub bearings: u32,
    /// RSSI readings handed on.
    pub rssi: u32,
    /// Sentences of types the bridge does not read (GSV, VTG, ...).
    pub unsupported_sentences: u32,
    /// GGA/RMC saying the receiver has no fix.
    pub no_fix_sentences: u32,
    /// Sentences or records with a missing or malformed field.
    pub bad_field: u32,
    /// Heading sentences taken (HDT, THS, HDG, HDM).
    pub headings: u32,
    /// Positions outside the valid range.
    pub bad_position: u32,
    /// Bearings at or below the quality gate (PFOXB quality, Agrelo digit, Kraken CONF).
    pub low_quality: u32,
    /// Agrelo records saying "no bearing" (`0`).
    pub no_bearing: u32,
    /// Relative bearings with no fresh heading, magnetic heading or gated course.
    pub no_heading: u32,
    /// Bearings with no fix at all.
    pub no_fix: u32,
    /// Bearings whose nearest fix is further than the allowed gap.
    pub stale_fix: u32,
    /// Bearings older than the fixes kept (further behind the newest fix than
    /// [`BridgeConfig::fix_span_ms`], or than the history holds).
    pub late: u32,
    /// Bearings turned by a heading while the vehicle turned faster than the yaw gate.
    pub turning: u32,
    /// Valid MT frames of other commands.
    pub other_mt: u32,
    /// AF_INCOMING_MSG frames too short for their fields.
    pub short_mt: u32,
    /// RSSI frames from addresses not in the anchor table.
    pub unknown_anchor: u32,
}

/// A bearing waiting for the fix after it.
#[derive(Debug, Clone, Copy)]
struct Pending {
    time_ms: i64,
    azimuth_deg: f64,
    quality: f32,
    freq_mhz: f64,
    kind: BearingKind,
    heading: HeadingSource,
}

/// A bearing as it arrives, before the heading rule and the placement.
#[derive(Debug, Clone, Copy)]
struct Incoming {
    time_ms: i64,
    /// Degrees, clockwise from true north or (relative) from the vehicle's front.
    azimuth_deg: f64,
    relative: bool,
    /// The record's own true heading, if it has one.
    record_heading: Option<f32>,
    quality: f32,
    freq_mhz: f64,
    position: Option<LatLon>,
    kind: BearingKind,
}

/// A heading and the clock time it arrived.
#[derive(Debug, Clone, Copy)]
struct Stamped {
    deg: f32,
    time_ms: i64,
}

const DAY_MS_U64: u64 = 86_400_000;

/// Fixes the bridge holds for placing bearings (48 bytes each): 64 fixes cover the default
/// 5 s span up to a 12 Hz GPS. A faster receiver fills the history before the span: then the
/// fix whose removal widens the spacing least is dropped (never the oldest), so the span
/// holds at a coarser spacing (20 Hz: one fix in 80 ms).
pub const FIX_HISTORY: usize = 64;
/// Bearings that may wait for a fix at once.
const WAITING: usize = 16;
/// Heading samples kept for the yaw rate (16 bytes each), at most one per
/// [`TURN_SPACING_MS`]: 6.4 s or more, the fix span and a window.
pub const TURN_HISTORY: usize = 64;
/// Heading samples closer than this to the one before are skipped, ms.
pub const TURN_SPACING_MS: i64 = 100;

/// Degrees to (-180, 180].
fn wrap_half(x: f32) -> f32 {
    let mut a = x;
    for _ in 0..4 {
        if a > 180.0 {
            a -= 360.0;
        } else if a <= -180.0 {
            a += 360.0;
        }
    }
    a
}

/// Which heading sources the yaw rate prefers: the heading rule's order.
fn rank(s: HeadingSource) -> u8 {
    match s {
        HeadingSource::TrueBearing | HeadingSource::TrueHeading => 0,
        HeadingSource::Record => 1,
        HeadingSource::Magnetic => 2,
        HeadingSource::Course => 3,
    }
}

/// `p` and `q` mixed by `w` (0: `p`), the longitude the short way round.
fn lerp_position(p: LatLon, q: LatLon, w: f64) -> LatLon {
    let mut d = q.lon - p.lon;
    if d > 180.0 {
        d -= 360.0;
    } else if d < -180.0 {
        d += 360.0;
    }
    let mut lon = p.lon + w * d;
    if lon > 180.0 {
        lon -= 360.0;
    } else if lon < -180.0 {
        lon += 360.0;
    }
    LatLon {
        lat: p.lat + w * (q.lat - p.lat),
        lon,
    }
}

/// Frames to measurements, with `A` anchors for RSSI (0 for a bearing-only vehicle).
///
/// Fixed memory: [`FIX_HISTORY`] fixes, [`TURN_HISTORY`] heading samples and 16 bearings
/// waiting for their next fix, about 5 KB in all.
#[derive(Debug, Clone)]
pub struct Bridge<const A: usize = 0> {
    config: BridgeConfig,
    anchors: [(u16, [f32; 2]); A],
    frame: Option<LocalFrame>,
    clock: Option<i64>,
    /// The fixes of the last `fix_span_ms`, oldest first.
    fixes: heapless::Vec<VehicleFix, FIX_HISTORY>,
    /// The first fix's time, and whether fixes have left the history since.
    first_fix_ms: Option<i64>,
    dropped: bool,
    /// Heading samples of one source (the best fresh one), oldest first, for the yaw rate.
    turns: heapless::Vec<Stamped, TURN_HISTORY>,
    turn_source: HeadingSource,
    /// Latest course over ground.
    course: Option<Stamped>,
    /// Since when the speed has stayed at or above the gate.
    fast_since: Option<i64>,
    true_heading: Option<Stamped>,
    /// Latest magnetic heading, and the true one its own variation gives.
    magnetic: Option<(Stamped, Option<f32>)>,
    waiting: Deque<Pending, WAITING>,
    counters: BridgeCounters,
}

impl<const A: usize> Bridge<A> {
    /// A bridge with an anchor table: short address and position (east, north) of each anchor.
    pub fn new(config: BridgeConfig, anchors: [(u16, [f32; 2]); A]) -> Self {
        Self {
            config,
            anchors,
            frame: None,
            clock: None,
            fixes: heapless::Vec::new(),
            first_fix_ms: None,
            dropped: false,
            turns: heapless::Vec::new(),
            turn_source: HeadingSource::Course,
            course: None,
            fast_since: None,
            true_heading: None,
            magnetic: None,
            waiting: Deque::new(),
            counters: BridgeCounters::default(),
        }
    }

    /// Counters so far.
    pub fn counters(&self) -> &BridgeCounters {
        &self.counters
    }

    /// The local frame, once the reference is known.
    pub fn local_frame(&self) -> Option<&LocalFrame> {
        self.frame.as_ref()
    }

    /// The latest vehicle fix.
    pub fn latest_fix(&self) -> Option<&VehicleFix> {
        self.fixes.last()
    }

    /// The fixes held for placing bearings, oldest first.
    pub fn fix_history(&self) -> &[VehicleFix] {
        &self.fixes
    }

    /// Place a time of day on the continuous clock: the representative nearest the last time
    /// seen, so a drive across midnight keeps counting.
    fn unwrap_time(&mut self, ms_of_day: u32) -> i64 {
        let t = i64::from(ms_of_day);
        let unwrapped = match self.clock {
            None => t,
            Some(last) => {
                let day = last.div_euclid(DAY_MS);
                [day - 1, day, day + 1]
                    .map(|d| d * DAY_MS + t)
                    .into_iter()
                    .min_by_key(|c| (c - last).abs())
                    .unwrap_or(t)
            }
        };
        self.clock = Some(unwrapped);
        unwrapped
    }

    fn local(&mut self, p: LatLon) -> Result<[f32; 2], GeoError> {
        let frame = match self.frame {
            Some(f) => f,
            None => {
                let f = LocalFrame::new(self.config.reference.unwrap_or(p), 0.0)?;
                self.frame = Some(f);
                f
            }
        };
        frame.to_local(p).map(|en| [en[0] as f32, en[1] as f32])
    }

    /// Take one frame; hand what it yields to `sink`.
    pub fn push(&mut self, frame: &Frame<'_>, sink: &mut impl FnMut(Event)) {
        match frame {
            Frame::Nmea(text) => self.sentence(text, sink),
            Frame::Mt(m) => match AfIncomingMsg::parse(m) {
                Ok(msg) => self.rssi(&msg, sink),
                Err(MtError::Unsupported) => self.counters.other_mt += 1,
                Err(_) => self.counters.short_mt += 1,
            },
            Frame::Agrelo(text) => match Agrelo::parse(text) {
                Ok(a) => self.agrelo(&a, sink),
                Err(_) => self.counters.bad_field += 1,
            },
            Frame::KrakenCsv(k) => {
                let r = &k.record;
                let conf = r.confidence * 100.0;
                if !(conf >= self.config.kraken_min_conf) {
                    self.counters.low_quality += 1;
                    return;
                }
                let time_ms = self.unwrap_time((r.epoch_ms % DAY_MS_U64) as u32);
                self.bearing_in(
                    Incoming {
                        time_ms,
                        azimuth_deg: f64::from(r.relative_deg(self.config.kraken_convention)),
                        relative: true,
                        record_heading: r.position.map(|_| r.heading_deg),
                        quality: conf.clamp(0.0, 100.0),
                        freq_mhz: r.freq_hz as f64 / 1e6,
                        position: r.position,
                        kind: BearingKind::KrakenCsv,
                    },
                    sink,
                );
            }
            Frame::KrakenXml(r) => {
                if r.conf.is_some_and(|c| !(c >= self.config.kraken_min_conf)) {
                    self.counters.low_quality += 1;
                    return;
                }
                let Some(time_ms) = r
                    .time_ms
                    .map(|t| self.unwrap_time((t % DAY_MS_U64) as u32))
                    .or(self.clock)
                else {
                    self.counters.no_fix += 1;
                    return;
                };
                self.bearing_in(
                    Incoming {
                        time_ms,
                        azimuth_deg: f64::from(r.relative_deg()),
                        relative: true,
                        record_heading: r.position.and(r.heading_deg),
                        quality: r.conf.unwrap_or(100.0).clamp(0.0, 100.0),
                        freq_mhz: r.freq_mhz.unwrap_or(0.0),
                        position: r.position,
                        kind: BearingKind::KrakenXml,
                    },
                    sink,
                );
            }
        }
    }

    fn sentence(&mut self, text: &str, sink: &mut impl FnMut(Event)) {
        let knots = |k: f64| (k * KNOT_MPS) as f32;
        match Sentence::parse(text) {
            Ok(Sentence::Gga(g)) => self.fix(g.time, g.position, None, None, sink),
            Ok(Sentence::Rmc(r)) => self.fix(
                r.time,
                r.position,
                r.speed_kn.map(knots),
                r.course_deg.map(|c| c as f32),
                sink,
            ),
            Ok(Sentence::Gll(g)) => match g.time.map(|t| t.ms_of_day).or(self.clock_of_day()) {
                Some(ms_of_day) => self.fix(UtcTime { ms_of_day }, g.position, None, None, sink),
                None => self.counters.no_fix_sentences += 1,
            },
            Ok(Sentence::Gns(g)) => self.fix(g.time, g.position, None, None, sink),
            Ok(Sentence::Vtg(v)) => {
                if let Some(t) = self.clock {
                    self.motion(
                        t,
                        v.speed_mps().map(|s| s as f32),
                        v.course_deg.map(|c| c as f32),
                    );
                }
            }
            Ok(Sentence::Hdt(h)) => self.true_heading(h.heading_deg),
            Ok(Sentence::Ths(h)) => self.true_heading(h.heading_deg),
            Ok(Sentence::Hdg(h)) => {
                self.magnetic_heading(h.magnetic_deg(), h.true_deg().map(|t| t as f32))
            }
            Ok(Sentence::Hdm(h)) => self.magnetic_heading(h.heading_deg, None),
            Ok(Sentence::Pfoxb(b)) => {
                if !(b.quality > self.config.min_quality) {
                    self.counters.low_quality += 1;
                    return;
                }
                let time_ms = self.unwrap_time(b.time.ms_of_day);
                self.bearing_in(
                    Incoming {
                        time_ms,
                        azimuth_deg: b.azimuth_deg,
                        relative: b.reference == Reference::Relative,
                        record_heading: None,
                        quality: b.quality,
                        freq_mhz: b.freq_mhz,
                        position: b.position,
                        kind: BearingKind::Pfoxb,
                    },
                    sink,
                );
            }
            Err(NmeaError::Unsupported) => self.counters.unsupported_sentences += 1,
            Err(NmeaError::NoFix) => {
                // The receiver's clock runs on while it has no fix: a later bearing then sees
                // how old the last fix is.
                if let Some(t) = Sentence::time_of(text) {
                    self.unwrap_time(t.ms_of_day);
                }
                self.counters.no_fix_sentences += 1;
            }
            Err(NmeaError::BadField(_)) => self.counters.bad_field += 1,
        }
    }

    fn clock_of_day(&self) -> Option<u32> {
        self.clock.map(|c| c.rem_euclid(DAY_MS) as u32)
    }

    fn true_heading(&mut self, deg: f64) {
        self.counters.headings += 1;
        let time_ms = self.clock.unwrap_or(i64::MIN / 2);
        self.true_heading = Some(Stamped {
            deg: deg as f32,
            time_ms,
        });
        self.turn_sample(HeadingSource::TrueHeading, deg as f32, time_ms);
    }

    fn magnetic_heading(&mut self, magnetic_deg: f64, true_deg: Option<f32>) {
        self.counters.headings += 1;
        let stamped = Stamped {
            deg: magnetic_deg as f32,
            time_ms: self.clock.unwrap_or(i64::MIN / 2),
        };
        self.magnetic = Some((stamped, true_deg));
        // The rate of a magnetic heading is the rate of the true one.
        self.turn_sample(HeadingSource::Magnetic, stamped.deg, stamped.time_ms);
    }

    /// A heading sample for the yaw rate. The samples hold one source at a time, the best
    /// the heading rule knows: a better source takes over at once, a lesser one only when the
    /// current one has gone stale (two sources differ by the crab angle, which is no turn).
    fn turn_sample(&mut self, source: HeadingSource, deg: f32, time_ms: i64) {
        if self.clock.is_none() && source != HeadingSource::Record {
            return;
        }
        if let Some(last) = self.turns.last() {
            let age = i64::from(self.config.heading_max_age_ms);
            let fresh = (time_ms - last.time_ms).abs() <= age;
            if source != self.turn_source {
                if fresh && rank(source) > rank(self.turn_source) {
                    return;
                }
                self.turns.clear();
            } else if time_ms < last.time_ms {
                self.turns.clear();
            } else if time_ms - last.time_ms < TURN_SPACING_MS {
                return;
            }
        }
        self.turn_source = source;
        if self.turns.is_full() && !self.turns.is_empty() {
            self.turns.remove(0);
        }
        let _ = self.turns.push(Stamped { deg, time_ms });
    }

    /// The vehicle's yaw rate at `time_ms`, degrees per second, from the heading samples: the
    /// heading's total change (summed sample to sample, so a fast spin is not aliased) from
    /// the last sample at least [`BridgeConfig::yaw_window_ms`] before the first sample at or
    /// after `time_ms` (the newest if none is yet) to that one. `None` when the samples do
    /// not tell: none fresh at `time_ms`, or none a window before, or a gap between them.
    pub fn yaw_rate_at(&self, time_ms: i64) -> Option<f32> {
        let age = i64::from(self.config.heading_max_age_ms);
        let window = i64::from(self.config.yaw_window_ms).max(1);
        let last = self.turns.len().checked_sub(1)?;
        let bi = self
            .turns
            .iter()
            .position(|s| s.time_ms >= time_ms)
            .unwrap_or(last);
        let b = self.turns.get(bi)?;
        if (b.time_ms - time_ms).abs() > age {
            return None;
        }
        let ai = self
            .turns
            .get(..bi)?
            .iter()
            .rposition(|s| s.time_ms <= b.time_ms - window)?;
        let a = self.turns.get(ai)?;
        let span = b.time_ms - a.time_ms;
        if span > window + age {
            return None;
        }
        let turn: f32 = self
            .turns
            .get(ai..=bi)?
            .windows(2)
            .map(|w| match w {
                [p, q] => wrap_half(q.deg - p.deg),
                _ => 0.0,
            })
            .sum();
        Some(libm::fabsf(turn) * 1000.0 / span as f32)
    }

    /// Speed and course at `time_ms`: the speed gate's state and the latest course.
    fn motion(&mut self, time_ms: i64, speed_mps: Option<f32>, course_deg: Option<f32>) {
        if let Some(v) = speed_mps {
            if v >= self.config.course_min_speed_mps {
                self.fast_since.get_or_insert(time_ms);
            } else {
                self.fast_since = None;
            }
        }
        if let Some(deg) = course_deg {
            self.course = Some(Stamped { deg, time_ms });
            // Course over ground is a heading only while moving.
            if self.fast_since.is_some() {
                self.turn_sample(HeadingSource::Course, deg, time_ms);
            }
        }
    }

    /// The heading rule (see the module doc): the true heading of the vehicle at `time_ms`
    /// and its source, given the record's own heading.
    pub fn heading_at(&self, time_ms: i64, record: Option<f32>) -> Option<(f32, HeadingSource)> {
        let fresh =
            |s: &Stamped| (time_ms - s.time_ms).abs() <= i64::from(self.config.heading_max_age_ms);
        if let Some(h) = self.true_heading.filter(fresh) {
            return Some((h.deg, HeadingSource::TrueHeading));
        }
        if let Some(h) = record {
            return Some((h, HeadingSource::Record));
        }
        if let Some((m, own)) = self.magnetic.filter(|(m, _)| fresh(m)) {
            let t = own.or(self.config.declination_deg.map(|d| m.deg + d));
            if let Some(t) = t {
                return Some((t, HeadingSource::Magnetic));
            }
        }
        let gap = i64::from(self.config.max_fix_gap_ms);
        let held = self
            .fast_since
            .is_some_and(|s| time_ms - s >= i64::from(self.config.course_hold_ms));
        match self.course {
            Some(c) if held && (time_ms - c.time_ms).abs() <= gap => {
                Some((c.deg, HeadingSource::Course))
            }
            _ => None,
        }
    }

    fn agrelo(&mut self, a: &Agrelo, sink: &mut impl FnMut(Event)) {
        let Some(bearing) = a.bearing() else {
            self.counters.no_bearing += 1;
            return;
        };
        if a.quality < self.config.agrelo_min_quality {
            self.counters.low_quality += 1;
            return;
        }
        let Some(time_ms) = self.clock else {
            self.counters.no_fix += 1;
            return;
        };
        self.bearing_in(
            Incoming {
                time_ms,
                azimuth_deg: f64::from(bearing),
                relative: true,
                record_heading: None,
                quality: a.quality_percent(),
                freq_mhz: 0.0,
                position: None,
                kind: BearingKind::Agrelo,
            },
            sink,
        );
    }

    fn fix(
        &mut self,
        time: UtcTime,
        position: LatLon,
        speed_mps: Option<f32>,
        course_deg: Option<f32>,
        sink: &mut impl FnMut(Event),
    ) {
        let Ok(local) = self.local(position) else {
            self.counters.bad_position += 1;
            return;
        };
        let time_ms = self.unwrap_time(time.ms_of_day);
        self.motion(time_ms, speed_mps, course_deg);
        if let Some(last) = self.fixes.last_mut()
            && last.time_ms == time_ms
        {
            // The sentences of one epoch: one fix, with the RMC's speed and course.
            last.speed_mps = speed_mps.or(last.speed_mps);
            last.course_deg = course_deg.or(last.course_deg);
            return;
        }
        if self.fixes.last().is_some_and(|l| l.time_ms > time_ms) {
            // Time went backwards (a new capture, a receiver reset): the old fixes say
            // nothing about the new times.
            self.fixes.clear();
            self.dropped = true;
        }
        let fix = VehicleFix {
            time_ms,
            position,
            local,
            speed_mps,
            course_deg,
        };
        self.keep(fix);
        self.first_fix_ms.get_or_insert(time_ms);
        self.counters.fixes += 1;
        sink(Event::Fix(fix));
        while let Some(p) = self.waiting.front().copied() {
            if p.time_ms > time_ms {
                break;
            }
            self.waiting.pop_front();
            self.place(&p, sink);
        }
    }

    /// Add `fix` to the history: fixes more than the span behind it leave (the last one at or
    /// before the span's start stays, to interpolate there); a full history drops the fix
    /// whose neighbours are closest in time (never the oldest, so the span holds).
    fn keep(&mut self, fix: VehicleFix) {
        let start = fix.time_ms - i64::from(self.config.fix_span_ms);
        let old = self
            .fixes
            .iter()
            .rposition(|f| f.time_ms <= start)
            .unwrap_or(0);
        if old > 0 {
            self.dropped = true;
            let kept = self.fixes.len() - old;
            for i in 0..kept {
                if let Some(&f) = self.fixes.get(i + old)
                    && let Some(slot) = self.fixes.get_mut(i)
                {
                    *slot = f;
                }
            }
            self.fixes.truncate(kept);
        }
        if self.fixes.is_full() {
            // Among the fixes with a neighbour on each side (the newest has none yet: the new
            // fix is its later neighbour), the one whose loss leaves the smallest gap.
            let thin = (1..self.fixes.len())
                .filter_map(|i| {
                    let before = self.fixes.get(i - 1)?.time_ms;
                    let after = self.fixes.get(i + 1).map_or(fix.time_ms, |f| f.time_ms);
                    Some((after - before, i))
                })
                .min()
                .map_or(0, |(_, i)| i);
            if thin == 0 {
                self.dropped = true;
            }
            if thin < self.fixes.len() {
                self.fixes.remove(thin);
            }
        }
        // Room was made above, so this cannot fail.
        let _ = self.fixes.push(fix);
    }

    /// Every bearing kind ends here: the heading rule, the mounting offset, the placement.
    fn bearing_in(&mut self, b: Incoming, sink: &mut impl FnMut(Event)) {
        if let Some(h) = b.record_heading {
            self.turn_sample(HeadingSource::Record, h, b.time_ms);
        }
        let (azimuth_deg, heading) = if b.relative {
            match self.heading_at(b.time_ms, b.record_heading) {
                Some((h, source)) => {
                    let a = b.azimuth_deg + f64::from(self.config.mount_offset_deg) + f64::from(h);
                    (wrap_deg(a), source)
                }
                None => {
                    self.counters.no_heading += 1;
                    return;
                }
            }
        } else {
            (b.azimuth_deg, HeadingSource::TrueBearing)
        };
        let pending = Pending {
            time_ms: b.time_ms,
            azimuth_deg,
            quality: b.quality,
            freq_mhz: b.freq_mhz,
            kind: b.kind,
            heading,
        };
        if let Some(p) = b.position {
            match self.local(p) {
                Ok(v) => self.emit(&pending, v, p, sink),
                Err(_) => self.counters.bad_position += 1,
            }
            return;
        }
        let newest = self.fixes.last().map(|f| f.time_ms);
        if newest.is_some_and(|t| t >= b.time_ms) {
            self.place(&pending, sink);
            return;
        }
        if self.waiting.is_full()
            && let Some(oldest) = self.waiting.pop_front()
        {
            self.place(&oldest, sink);
        }
        let _ = self.waiting.push_back(pending);
    }

    /// Place a bearing at the vehicle's position at its time.
    fn place(&mut self, p: &Pending, sink: &mut impl FnMut(Event)) {
        let gap = i64::from(self.config.max_fix_gap_ms);
        let before = self.fixes.iter().rev().find(|f| f.time_ms <= p.time_ms);
        let after = self.fixes.iter().find(|f| f.time_ms >= p.time_ms);
        if before.is_none() && self.dropped && self.first_fix_ms.is_some_and(|t| t <= p.time_ms) {
            // The fixes before it have left the history: placing it at the oldest kept fix
            // would put it where the vehicle was later.
            self.counters.late += 1;
            return;
        }
        let near = |f: &&VehicleFix| (f.time_ms - p.time_ms).abs() <= gap;
        let position = match (before.filter(near), after.filter(near)) {
            (Some(a), Some(b)) if b.time_ms > a.time_ms => {
                let w = (p.time_ms - a.time_ms) as f64 / (b.time_ms - a.time_ms) as f64;
                let wf = w as f32;
                Some((
                    [
                        a.local[0] + wf * (b.local[0] - a.local[0]),
                        a.local[1] + wf * (b.local[1] - a.local[1]),
                    ],
                    lerp_position(a.position, b.position, w),
                ))
            }
            (Some(a), _) => Some((a.local, a.position)),
            (None, Some(b)) => Some((b.local, b.position)),
            (None, None) => None,
        };
        match position {
            Some((v, at)) => self.emit(p, v, at, sink),
            None if self.fixes.is_empty() => self.counters.no_fix += 1,
            None => self.counters.stale_fix += 1,
        }
    }

    /// Hand on a placed bearing at local `vehicle`, geodetic `at`: the yaw gate, then the
    /// azimuth carried from north at `at` into the local frame.
    fn emit(&mut self, p: &Pending, vehicle: [f32; 2], at: LatLon, sink: &mut impl FnMut(Event)) {
        if p.heading != HeadingSource::TrueBearing
            && let Some(gate) = self.config.yaw_gate_deg_s
            && self.yaw_rate_at(p.time_ms).is_some_and(|r| r > gate)
        {
            self.counters.turning += 1;
            return;
        }
        let scale = match self.config.weighting {
            QualityWeighting::Uniform => 1.0,
            QualityWeighting::ErrorWeight => 1.0 + error_weight(p.quality),
        };
        let Some(local_deg) = self
            .frame
            .and_then(|f| f.azimuth_to_local(at, p.azimuth_deg).ok())
        else {
            self.counters.bad_position += 1;
            return;
        };
        // In (-180, 180] before the cast: f32 keeps 0.03 millidegrees near 360, far more
        // near 0.
        let signed = if local_deg > 180.0 {
            local_deg - 360.0
        } else {
            local_deg
        };
        let azimuth = signed.to_radians() as f32;
        self.counters.bearings += 1;
        sink(Event::Bearing(BearingMeasurement {
            time_ms: p.time_ms,
            bearing: Bearing::from_azimuth(vehicle, azimuth, self.config.sigma_rad * scale),
            quality: p.quality,
            freq_mhz: p.freq_mhz,
            kind: p.kind,
            heading: p.heading,
        }));
    }

    fn rssi(&mut self, msg: &AfIncomingMsg<'_>, sink: &mut impl FnMut(Event)) {
        let Some(anchor) = self.anchors.iter().position(|a| a.0 == msg.src_addr) else {
            self.counters.unknown_anchor += 1;
            return;
        };
        self.counters.rssi += 1;
        sink(Event::Rssi(RssiReading {
            anchor,
            src_addr: msg.src_addr,
            link_quality: msg.link_quality,
            dbm: self.config.link_quality.rssi_dbm(msg.link_quality),
            timestamp: msg.timestamp,
        }));
    }

    /// The stream ended: place the bearings still waiting with the fixes there are.
    pub fn finish(&mut self, sink: &mut impl FnMut(Event)) {
        while let Some(p) = self.waiting.pop_front() {
            self.place(&p, sink);
        }
    }
}

/// A serial line end to end: the demultiplexer and the bridge.
#[derive(Debug, Clone)]
pub struct Receiver<const A: usize = 0> {
    /// The byte-stream demultiplexer.
    pub demux: Demux<DEFAULT_CAPACITY>,
    /// The bridge.
    pub bridge: Bridge<A>,
}

impl<const A: usize> Receiver<A> {
    /// A receiver with these settings and anchors.
    pub fn new(config: BridgeConfig, anchors: [(u16, [f32; 2]); A]) -> Self {
        Self {
            demux: Demux::new(),
            bridge: Bridge::new(config, anchors),
        }
    }

    /// Feed bytes as they arrive, in any chunking.
    pub fn feed(&mut self, bytes: &[u8], sink: &mut impl FnMut(Event)) {
        let bridge = &mut self.bridge;
        self.demux.feed(bytes, &mut |f| bridge.push(&f, sink));
    }

    /// The line went quiet (a read timed out): settle frames waiting on look-ahead.
    pub fn idle(&mut self, sink: &mut impl FnMut(Event)) {
        self.demux.idle();
        let bridge = &mut self.bridge;
        while let Some(f) = self.demux.next_frame() {
            bridge.push(&f, sink);
        }
    }

    /// End of the stream.
    pub fn finish(&mut self, sink: &mut impl FnMut(Event)) {
        let bridge = &mut self.bridge;
        self.demux.finish_into(&mut |f| bridge.push(&f, sink));
        self.bridge.finish(sink);
    }

    /// Both sets of counters.
    pub fn counters(&self) -> (&StreamCounters, &BridgeCounters) {
        (self.demux.counters(), self.bridge.counters())
    }
}
