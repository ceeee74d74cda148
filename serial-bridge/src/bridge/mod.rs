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
//! Geometry and time (docs/src/formats/bridge.md): a true azimuth is measured from north at the vehicle, which
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
//!
//! Every bearing names its station (`stations`): a KrakenSDR's STATION_ID, else its record
//! kind on its input; a station's own headings (a record's HEADING) feed its own yaw rate,
//! the vehicle's (HDT, HDG, course) the vehicle's, and a surveyed station is placed where it
//! stands.
//!
//! The files: `config` (the settings), `event` (what the bridge hands on, and its counters),
//! `heading` (the heading rule and the yaw rate), `placement` (the fix history and a bearing's
//! place in it), `stations` (who took each bearing) and `receiver` (a serial line end to end);
//! the frames come in here.

mod clock;
mod config;
mod event;
mod heading;
mod placement;
mod receiver;
mod stations;

pub use clock::CLOCKS;
use clock::{ClockKey, Clocks};
pub use config::{BridgeConfig, QualityWeighting};
pub use event::{
    BearingKind, BearingMeasurement, BridgeCounters, Event, HeadingSource, RssiReading, VehicleFix,
};
use heading::Stamped;
pub use heading::{TURN_HISTORY, TURN_SPACING_MS};
pub use placement::FIX_HISTORY;
pub use receiver::Receiver;
use stations::Stations;
pub use stations::{FIXED_WITHIN_M, MCU_STATIONS, STATION_TURNS, StationKey, StationState};

use crate::agrelo::Agrelo;
use crate::geo::{GeoError, LocalFrame};
use crate::mt::{AfIncomingMsg, MtError};
use crate::nmea::{KNOT_MPS, LatLon, NmeaError, Reference, Sentence, UtcTime};
use crate::stream::Frame;
use foxhunt_core::Bearing;
use foxhunt_core::preprocess::error_weight;
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

/// A bearing waiting for the fix after it.
#[derive(Debug, Clone, Copy)]
struct Pending {
    time_ms: i64,
    azimuth_deg: f64,
    quality: f32,
    freq_mhz: f64,
    kind: BearingKind,
    heading: HeadingSource,
    station: u16,
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
    /// Who took it.
    key: StationKey,
}

const DAY_MS_U64: u64 = 86_400_000;

/// A time of day on a continuous clock: the representative nearest `reference` (the time of
/// day itself without one).
fn nearest_day(reference: Option<i64>, ms_of_day: u32) -> i64 {
    let t = i64::from(ms_of_day);
    match reference {
        None => t,
        Some(last) => {
            let day = last.div_euclid(DAY_MS);
            [day - 1, day, day + 1]
                .map(|d| d * DAY_MS + t)
                .into_iter()
                .min_by_key(|c| (c - last).abs())
                .unwrap_or(t)
        }
    }
}
/// Bearings that may wait for a fix at once.
const WAITING: usize = 16;

/// Frames to measurements, with `A` anchors for RSSI (0 for a bearing-only vehicle) and room
/// for `S` stations (`stations.rs`; the MCU's [`MCU_STATIONS`], a host's as many as it
/// wants).
///
/// Fixed memory: [`FIX_HISTORY`] fixes, [`TURN_HISTORY`] heading samples, 16 bearings
/// waiting for their next fix and `S` stations of about 340 bytes, about 5 KB and the
/// stations in all.
#[derive(Debug, Clone)]
pub struct Bridge<const A: usize = 0, const S: usize = MCU_STATIONS> {
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
    /// Each bearing source's own clock (records whose time jumps are held and judged there).
    clocks: Clocks<Incoming>,
    counters: BridgeCounters,
    /// The stations seen, each with its own heading samples and motion.
    stations: Stations<S>,
    /// The input unnamed records come in on ([`Bridge::set_input`]).
    input: u8,
}

impl<const A: usize, const S: usize> Bridge<A, S> {
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
            clocks: Clocks::new(),
            counters: BridgeCounters::default(),
            stations: Stations::new(),
            input: 0,
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
        let unwrapped = nearest_day(self.clock, ms_of_day);
        self.clock = Some(unwrapped);
        unwrapped
    }

    /// A bearing record with a time of its own (`ms_of_day`), judged on its source's clock
    /// ([`clock`]): it passes on at once, is held until the source's next record says whether
    /// its time or the clock jumped, or is refused (`time_jump`); with
    /// [`BridgeConfig::judged_clocks`] it passes at once.
    fn timed(&mut self, key: ClockKey, ms_of_day: u32, b: Incoming, sink: &mut impl FnMut(Event)) {
        let time_ms = nearest_day(self.clocks.last(key).or(self.clock), ms_of_day);
        if self.config.judged_clocks {
            self.clock = Some(time_ms);
            self.bearing_in(Incoming { time_ms, ..b }, sink);
            return;
        }
        let judged = self.clocks.judge(key, time_ms, Incoming { time_ms, ..b });
        self.counters.time_jump += judged.jumped;
        for r in judged.pass.into_iter().flatten() {
            self.clock = Some(r.time_ms);
            self.bearing_in(r, sink);
        }
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
                let key = ClockKey::new(BearingKind::KrakenCsv, r.station.as_str());
                self.timed(
                    key,
                    (r.epoch_ms % DAY_MS_U64) as u32,
                    Incoming {
                        time_ms: 0,
                        azimuth_deg: f64::from(r.relative_deg(self.config.kraken_convention)),
                        relative: true,
                        record_heading: r.position.map(|_| r.heading_deg),
                        quality: conf.clamp(0.0, 100.0),
                        freq_mhz: r.freq_hz as f64 / 1e6,
                        position: r.position,
                        kind: BearingKind::KrakenCsv,
                        key: StationKey::of(BearingKind::KrakenCsv, Some(&r.station), self.input),
                    },
                    sink,
                );
            }
            Frame::KrakenXml(r) => {
                if r.conf.is_some_and(|c| !(c >= self.config.kraken_min_conf)) {
                    self.counters.low_quality += 1;
                    return;
                }
                let incoming = Incoming {
                    time_ms: 0,
                    azimuth_deg: f64::from(r.relative_deg()),
                    relative: true,
                    record_heading: r.position.and(r.heading_deg),
                    quality: r.conf.unwrap_or(100.0).clamp(0.0, 100.0),
                    freq_mhz: r.freq_mhz.unwrap_or(0.0),
                    position: r.position,
                    kind: BearingKind::KrakenXml,
                    key: StationKey::of(BearingKind::KrakenXml, Some(&r.station), self.input),
                };
                match (r.time_ms, self.clock) {
                    (Some(t), _) => {
                        let key = ClockKey::new(BearingKind::KrakenXml, r.station.as_str());
                        self.timed(key, (t % DAY_MS_U64) as u32, incoming, sink);
                    }
                    // No time of its own: the clock's, as an Agrelo record.
                    (None, Some(time_ms)) => self.bearing_in(
                        Incoming {
                            time_ms,
                            ..incoming
                        },
                        sink,
                    ),
                    (None, None) => self.counters.no_fix += 1,
                }
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
                        key: StationKey::of(BearingKind::Pfoxb, None, self.input),
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
                key: StationKey::of(BearingKind::Agrelo, None, self.input),
            },
            sink,
        );
    }

    /// Every bearing kind ends here: its station, the heading rule, the mounting offset, the
    /// placement.
    fn bearing_in(&mut self, b: Incoming, sink: &mut impl FnMut(Event)) {
        let Some(station) = self.station_of(b.key) else {
            return;
        };
        if let Some(h) = b.record_heading {
            self.station_turn(station, h, b.time_ms);
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
            station,
        };
        if let Some(p) = self.surveyed_at(station).or(b.position) {
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

    /// Hand on a placed bearing at local `vehicle`, geodetic `at`: the yaw gate, then the
    /// azimuth carried from north at `at` into the local frame.
    fn emit(&mut self, p: &Pending, vehicle: [f32; 2], at: LatLon, sink: &mut impl FnMut(Event)) {
        if let Some(gate) = self.config.yaw_gate_deg_s {
            // A record's own heading turns with its station; the others with the vehicle.
            let rate = match p.heading {
                HeadingSource::TrueBearing => None,
                HeadingSource::Record => self.station_yaw_rate(p.station, p.time_ms),
                _ => self.yaw_rate_at(p.time_ms),
            };
            if rate.is_some_and(|r| r > gate) {
                self.counters.turning += 1;
                return;
            }
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
        self.station_placed(p.station, vehicle, at);
        sink(Event::Bearing(BearingMeasurement {
            time_ms: p.time_ms,
            bearing: Bearing::from_azimuth(vehicle, azimuth, self.config.sigma_rad * scale),
            quality: p.quality,
            freq_mhz: p.freq_mhz,
            kind: p.kind,
            heading: p.heading,
            station: p.station,
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
        // Records held for their source's next one: none came, so nothing says they jumped.
        let mut held: heapless::Vec<Incoming, { 2 * CLOCKS }> = heapless::Vec::new();
        self.clocks.release(|r| {
            let _ = held.push(r);
        });
        for r in held {
            self.clock = Some(r.time_ms);
            self.bearing_in(r, sink);
        }
        while let Some(p) = self.waiting.pop_front() {
            self.place(&p, sink);
        }
    }
}
