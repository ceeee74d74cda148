//! The bridge: decoded frames in, core measurements out.
//!
//! GPS fixes become vehicle positions in the local frame (origin: the configured reference, or
//! the first valid fix). A bearing is placed where the vehicle was at the bearing's own time,
//! interpolated between the fixes around it, so a DF unit that reports half a second after the
//! GPS does not smear the fix along the route; a bearing newer than the latest fix waits for
//! the next one. Relative bearings are turned by the latest valid course. Link-quality frames
//! from known anchors become RSSI readings. Everything rejected is counted by reason.

use crate::geo::{GeoError, LocalFrame};
use crate::mt::{AfIncomingMsg, LinkQualityMap, MtError};
use crate::nmea::{LatLon, NmeaError, Pfoxb, Reference, Sentence};
use crate::stream::{DEFAULT_CAPACITY, Demux, Frame, StreamCounters};
use foxhunt_core::Bearing;
use foxhunt_core::preprocess::{DEFAULT_MIN_QUALITY, error_weight};
use heapless::Deque;

const DAY_MS: i64 = 86_400_000;

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
        }
    }
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
    /// DF quality.
    pub quality: f32,
    /// Frequency, MHz.
    pub freq_mhz: f64,
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
    /// Sentences with a missing or malformed field.
    pub bad_field: u32,
    /// Positions outside the valid range.
    pub bad_position: u32,
    /// Bearings at or below the quality gate.
    pub low_quality: u32,
    /// Relative bearings with no course to turn them by.
    pub no_course: u32,
    /// Bearings with no fix at all.
    pub no_fix: u32,
    /// Bearings whose nearest fix is further than the allowed gap.
    pub stale_fix: u32,
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
}

/// Fixes kept for interpolation.
const HISTORY: usize = 8;
/// Bearings that may wait for a fix at once.
const WAITING: usize = 16;

/// Frames to measurements, with `A` anchors for RSSI (0 for a bearing-only vehicle).
#[derive(Debug, Clone)]
pub struct Bridge<const A: usize = 0> {
    config: BridgeConfig,
    anchors: [(u16, [f32; 2]); A],
    frame: Option<LocalFrame>,
    clock: Option<i64>,
    fixes: Deque<VehicleFix, HISTORY>,
    course: Option<f32>,
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
            fixes: Deque::new(),
            course: None,
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
        self.fixes.back()
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
            Frame::Nmea(text) => match Sentence::parse(text) {
                Ok(Sentence::Gga(g)) => self.fix(g.time.ms_of_day, g.position, None, None, sink),
                Ok(Sentence::Rmc(r)) => {
                    let speed = r.speed_kn.map(|k| (k * 1852.0 / 3600.0) as f32);
                    let course = r.course_deg.map(|c| c as f32);
                    self.fix(r.time.ms_of_day, r.position, speed, course, sink)
                }
                Ok(Sentence::Gns(g)) => self.fix(g.time.ms_of_day, g.position, None, None, sink),
                Ok(Sentence::Pfoxb(b)) => self.bearing(&b, sink),
                Ok(_) => self.counters.unsupported_sentences += 1,
                Err(NmeaError::Unsupported) => self.counters.unsupported_sentences += 1,
                Err(NmeaError::NoFix) => self.counters.no_fix_sentences += 1,
                Err(NmeaError::BadField(_)) => self.counters.bad_field += 1,
            },
            Frame::Mt(m) => match AfIncomingMsg::parse(m) {
                Ok(msg) => self.rssi(&msg, sink),
                Err(MtError::Unsupported) => self.counters.other_mt += 1,
                Err(_) => self.counters.short_mt += 1,
            },
        }
    }

    fn fix(
        &mut self,
        ms_of_day: u32,
        position: LatLon,
        speed_mps: Option<f32>,
        course_deg: Option<f32>,
        sink: &mut impl FnMut(Event),
    ) {
        let Ok(local) = self.local(position) else {
            self.counters.bad_position += 1;
            return;
        };
        let time_ms = self.unwrap_time(ms_of_day);
        if course_deg.is_some() {
            self.course = course_deg;
        }
        if let Some(last) = self.fixes.back_mut()
            && last.time_ms == time_ms
        {
            // GGA and RMC of one epoch: one fix, with the RMC's speed and course.
            last.speed_mps = speed_mps.or(last.speed_mps);
            last.course_deg = course_deg.or(last.course_deg);
            return;
        }
        if self.fixes.is_full() {
            self.fixes.pop_front();
        }
        let fix = VehicleFix {
            time_ms,
            position,
            local,
            speed_mps,
            course_deg,
        };
        // Full was handled above, so this cannot fail.
        let _ = self.fixes.push_back(fix);
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

    fn bearing(&mut self, b: &Pfoxb, sink: &mut impl FnMut(Event)) {
        if !(b.quality > self.config.min_quality) {
            self.counters.low_quality += 1;
            return;
        }
        let azimuth_deg = match b.reference {
            Reference::True => b.azimuth_deg,
            Reference::Relative => match self.course {
                Some(c) => {
                    // Both lie in [0, 360]: one subtraction wraps the sum (no fmod linked).
                    let a = b.azimuth_deg + f64::from(c);
                    if a >= 360.0 { a - 360.0 } else { a }
                }
                None => {
                    self.counters.no_course += 1;
                    return;
                }
            },
        };
        let time_ms = self.unwrap_time(b.time.ms_of_day);
        let pending = Pending {
            time_ms,
            azimuth_deg,
            quality: b.quality,
            freq_mhz: b.freq_mhz,
        };
        if let Some(p) = b.position {
            match self.local(p) {
                Ok(v) => self.emit(&pending, v, sink),
                Err(_) => self.counters.bad_position += 1,
            }
            return;
        }
        let newest = self.fixes.back().map(|f| f.time_ms);
        if newest.is_some_and(|t| t >= time_ms) {
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
        let near = |f: &&VehicleFix| (f.time_ms - p.time_ms).abs() <= gap;
        let position = match (before.filter(near), after.filter(near)) {
            (Some(a), Some(b)) if b.time_ms > a.time_ms => {
                let w = (p.time_ms - a.time_ms) as f32 / (b.time_ms - a.time_ms) as f32;
                Some([
                    a.local[0] + w * (b.local[0] - a.local[0]),
                    a.local[1] + w * (b.local[1] - a.local[1]),
                ])
            }
            (Some(a), _) => Some(a.local),
            (None, Some(b)) => Some(b.local),
            (None, None) => None,
        };
        match position {
            Some(v) => self.emit(p, v, sink),
            None if self.fixes.is_empty() => self.counters.no_fix += 1,
            None => self.counters.stale_fix += 1,
        }
    }

    fn emit(&mut self, p: &Pending, vehicle: [f32; 2], sink: &mut impl FnMut(Event)) {
        let scale = match self.config.weighting {
            QualityWeighting::Uniform => 1.0,
            QualityWeighting::ErrorWeight => 1.0 + error_weight(p.quality),
        };
        let azimuth = (p.azimuth_deg as f32).to_radians();
        self.counters.bearings += 1;
        sink(Event::Bearing(BearingMeasurement {
            time_ms: p.time_ms,
            bearing: Bearing::from_azimuth(vehicle, azimuth, self.config.sigma_rad * scale),
            quality: p.quality,
            freq_mhz: p.freq_mhz,
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
