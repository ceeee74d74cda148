//! A capture's bytes decoded for a fix: the bridge fed chunk by chunk (the same code as the
//! firmware), keeping the bearings as observations (32 bytes each: memory grows with the
//! bearings kept, never with the capture), the vehicle track only when a map asks for it, and
//! every record's refusals attributed to its kind so an error can say which records failed.
//!
//! Each bearing names its station, the bridge's (docs/src/networks.md): a KrakenSDR's
//! STATION_ID, else its record kind on its input (each capture file is an input of its own,
//! [`Decoder::begin_input`]). The observations' station index is the bridge's, and
//! [`Decoded::stations`] says who each one is.

use foxhunt_bridge::Frame;
use foxhunt_bridge::bridge::{
    BearingKind, BearingMeasurement, BridgeConfig, BridgeCounters, Event, Receiver, StationKey,
    StationState, VehicleFix,
};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_bridge::record::RecordClass;
use foxhunt_bridge::stream::StreamCounters;
use foxhunt_core::Bearing;
use foxhunt_core::fix::locate::Observation;

/// Stations a host's bridge tells apart (the MCU's holds
/// [`MCU_STATIONS`](foxhunt_bridge::bridge::MCU_STATIONS)).
pub const HOST_STATIONS: usize = 256;

/// The receiver a host decodes with.
type HostReceiver = Receiver<0, HOST_STATIONS>;

/// A record kind as the station labels and reports name it.
pub fn kind_name(kind: BearingKind) -> &'static str {
    match kind {
        BearingKind::Pfoxb => "pfoxb",
        BearingKind::Agrelo => "agrelo",
        BearingKind::KrakenCsv => "kraken-csv",
        BearingKind::KrakenXml => "kraken-xml",
    }
}

/// A station as the capture showed it.
#[derive(Debug, Clone, PartialEq)]
pub struct StationInfo {
    /// Its id: a KrakenSDR's STATION_ID, or for a unit that names none its record kind,
    /// `INPUT:KIND` when the decoder was told of its inputs (`drive.nmea:agrelo`).
    pub id: String,
    /// Whether its records name it.
    pub named: bool,
    /// Whether it never moved (or stands at a surveyed position).
    pub fixed: bool,
    /// Where its first bearing was taken.
    pub position: Option<LatLon>,
    /// How far its bearings spread from the first, metres.
    pub span_m: f32,
    /// Bearings it handed on.
    pub bearings: u32,
}

/// Sentences and records of one kind seen in a capture, and how many the bridge refused as
/// malformed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct KindTally {
    /// Seen.
    pub seen: u32,
    /// Refused with a bad or out-of-range field.
    pub malformed: u32,
    /// Saying the receiver has no fix (GPS only).
    pub no_fix: u32,
}

/// Everything decoded from a capture.
#[derive(Debug, Clone, Default)]
pub struct Decoded {
    /// The bearings in the local frame, with their times, frequencies and DF sources.
    pub observations: Vec<Observation>,
    /// Bridge time of the first bearing, ms (the origin of the observations' times).
    pub first_ms: Option<i64>,
    /// The vehicle's fixes, kept only when a map asks for them.
    pub track: Vec<VehicleFix>,
    /// Vehicle fixes seen.
    pub fixes: u64,
    /// The local frame, if any fix arrived.
    pub frame: Option<LocalFrame>,
    /// Stream counters.
    pub stream: StreamCounters,
    /// Bridge counters.
    pub bridge: BridgeCounters,
    /// GPS position sentences seen.
    pub gps: KindTally,
    /// Bearing records seen.
    pub bearing_records: KindTally,
    /// What a DF unit running foxhunt's firmware said (its own sentences in the capture).
    pub unit: crate::inputs::unit::UnitLog,
    /// The stations, by the observations' station index.
    pub stations: Vec<StationInfo>,
    /// The bridge's bearings as it handed them on (quality, record kind, time on its clock),
    /// kept only when asked for ([`Decoder::keep_measurements`]) and drained by the caller:
    /// what `foxhunt publish` sends.
    pub measurements: Vec<BearingMeasurement>,
}

/// Whether a frame carries a GPS position, a bearing, or something else.
enum Kind {
    Gps,
    Bearing,
    Other,
}

fn kind(f: &Frame<'_>) -> Kind {
    match f.kind().class() {
        RecordClass::Position => Kind::Gps,
        RecordClass::Bearing => Kind::Bearing,
        _ => Kind::Other,
    }
}

/// The bridge fed byte by byte or chunk by chunk, keeping what a fix needs.
pub struct Decoder {
    rx: Box<HostReceiver>,
    /// What has been decoded so far.
    pub decoded: Decoded,
    keep_track: bool,
    /// The inputs' names, by input number (none: one unnamed input).
    inputs: Vec<String>,
    /// The input the bytes come from now.
    current: u8,
    /// Keep each bearing's measurement too.
    keep_measurements: bool,
}

impl Decoder {
    /// A decoder; `keep_track` keeps every vehicle fix (for maps).
    pub fn new(config: BridgeConfig, keep_track: bool) -> Self {
        Self {
            rx: Box::new(Receiver::new(config, [])),
            decoded: Decoded::default(),
            keep_track,
            inputs: Vec::new(),
            current: 0,
            keep_measurements: false,
        }
    }

    /// Keep every bearing's measurement in [`Decoded::measurements`] as well, for a caller
    /// that drains them as they come.
    pub fn keep_measurements(&mut self) {
        self.keep_measurements = true;
    }

    /// The bytes from now on come from input `name` (a capture file): a unit whose records
    /// name no station is a station of its own on each input. Errors past 256 inputs.
    pub fn begin_input(&mut self, name: &str) -> Result<(), String> {
        let i = u8::try_from(self.inputs.len())
            .map_err(|_| "more than 256 capture files: join them first".to_string())?;
        // A frame waiting on look-ahead is the last input's: delivered before the switch.
        self.idle();
        self.inputs.push(name.to_string());
        self.rx.bridge.set_input(i);
        self.current = i;
        Ok(())
    }

    /// The bytes from now on come from input `i`, one begun before (live sources polled in
    /// turn, each handing over whole records).
    pub fn switch_input(&mut self, i: u8) {
        if i != self.current && usize::from(i) < self.inputs.len() {
            self.idle();
            self.rx.bridge.set_input(i);
            self.current = i;
        }
    }

    /// Station `id` stands at `at` (a stations file's surveyed position): its bearings are
    /// placed there. `id` is a KrakenSDR's STATION_ID, or a unit's label (`KIND`, or
    /// `INPUT:KIND` with several inputs). False when the id names no station this decoder can
    /// have yet (an input not begun) or the station table is full.
    pub fn survey(&mut self, id: &str, at: LatLon) -> bool {
        match self.key_of(id) {
            Some(key) => self.rx.bridge.survey(key, at),
            None => false,
        }
    }

    /// The bridge's key for a station label (the inverse of the labels of
    /// [`Decoded::stations`]); `None` for the label of an input not begun.
    fn key_of(&self, id: &str) -> Option<StationKey> {
        let kind = |name: &str| {
            [
                BearingKind::Pfoxb,
                BearingKind::Agrelo,
                BearingKind::KrakenCsv,
                BearingKind::KrakenXml,
            ]
            .into_iter()
            .find(|k| kind_name(*k) == name)
        };
        let named = || StationKey::Named(foxhunt_bridge::kraken::Station::new(id));
        match id.rsplit_once(':') {
            Some((input, k)) if kind(k).is_some() => {
                let i = self.inputs.iter().position(|n| n == input)?;
                Some(StationKey::Unnamed {
                    kind: kind(k)?,
                    input: u8::try_from(i).ok()?,
                })
            }
            _ => match kind(id) {
                Some(k) if self.inputs.len() <= 1 => {
                    Some(StationKey::Unnamed { kind: k, input: 0 })
                }
                _ => Some(named()),
            },
        }
    }

    /// The label of a station of the bridge.
    fn label(&self, s: &StationState) -> (String, bool) {
        match s.key() {
            StationKey::Named(id) => (id.as_str().to_string(), true),
            StationKey::Unnamed { kind, input } => {
                let kind = kind_name(kind);
                match self.inputs.get(usize::from(input)) {
                    Some(name) if self.inputs.len() > 1 => (format!("{name}:{kind}"), false),
                    _ => (kind.to_string(), false),
                }
            }
        }
    }

    /// Feed bytes as they arrive.
    pub fn feed(&mut self, bytes: &[u8]) {
        let keep = self.keeps();
        let (demux, bridge) = (&mut self.rx.demux, &mut self.rx.bridge);
        let d = &mut self.decoded;
        demux.feed(bytes, &mut |f| push(bridge, &f, d, keep));
    }

    /// The line went quiet: settle frames waiting on look-ahead.
    pub fn idle(&mut self) {
        self.rx.demux.idle();
        let keep = self.keeps();
        let d = &mut self.decoded;
        while let Some(f) = self.rx.demux.next_frame() {
            push(&mut self.rx.bridge, &f, d, keep);
        }
        self.snapshot();
    }

    /// End of the stream: frames still buffered are delivered and bearings waiting for a
    /// later fix are placed with the fixes there are. Idempotent.
    pub fn end(&mut self) {
        let keep = self.keeps();
        let (demux, bridge) = (&mut self.rx.demux, &mut self.rx.bridge);
        let d = &mut self.decoded;
        demux.finish_into(&mut |f| push(bridge, &f, d, keep));
        bridge.finish(&mut |e| absorb(d, e, keep));
        self.snapshot();
    }

    /// End of the stream: everything decoded.
    pub fn finish(mut self) -> Decoded {
        self.end();
        self.decoded
    }

    /// Take one NMEA sentence body (no `$`, checksum or line end) as if it had come on the
    /// line: how gpsd's positions and headings reach the bridge, between the line's bytes.
    pub fn push_sentence(&mut self, body: &str) {
        self.push_frame(&Frame::Nmea(body));
    }

    /// Take one frame already decoded (a record rebuilt from a broker's message) as if its
    /// bytes had come on the line.
    pub fn push_frame(&mut self, frame: &Frame<'_>) {
        let keep = self.keeps();
        let d = &mut self.decoded;
        push(&mut self.rx.bridge, frame, d, keep);
    }

    /// What to keep besides the observations.
    fn keeps(&self) -> Keep {
        Keep {
            track: self.keep_track,
            measurements: self.keep_measurements,
        }
    }

    /// Bring the frame, counters and stations up to date (before a fix is computed
    /// mid-stream).
    pub fn snapshot(&mut self) {
        self.decoded.frame = self.rx.bridge.local_frame().copied();
        let (s, b) = self.rx.counters();
        self.decoded.stream = *s;
        self.decoded.bridge = *b;
        let stations = self
            .rx
            .bridge
            .stations()
            .iter()
            .map(|s| {
                let (id, named) = self.label(s);
                StationInfo {
                    id,
                    named,
                    fixed: s.fixed(),
                    position: s.surveyed().or(s.first_position()),
                    span_m: s.span_m(),
                    bearings: s.bearings(),
                }
            })
            .collect();
        self.decoded.stations = stations;
    }
}

/// What a decoder keeps besides the observations.
#[derive(Debug, Clone, Copy)]
struct Keep {
    track: bool,
    measurements: bool,
}

fn absorb(d: &mut Decoded, e: Event, keep: Keep) {
    match e {
        Event::Bearing(b) => {
            if keep.measurements {
                d.measurements.push(b);
            }
            let t0 = *d.first_ms.get_or_insert(b.time_ms);
            d.observations.push(Observation {
                bearing: b.bearing,
                time_s: (b.time_ms - t0) as f32 / 1000.0,
                freq_mhz: (b.freq_mhz > 0.0).then_some(b.freq_mhz as f32),
                station: b.station,
                // An Agrelo bearing takes the GPS clock's time when it arrives.
                stamped: b.kind != BearingKind::Agrelo,
            });
        }
        Event::Fix(f) => {
            d.fixes += 1;
            if keep.track {
                d.track.push(f);
            }
        }
        Event::Rssi(_) => {}
    }
}

/// One frame into the bridge, its refusals attributed to its kind.
fn push(
    bridge: &mut foxhunt_bridge::Bridge<0, HOST_STATIONS>,
    f: &Frame<'_>,
    d: &mut Decoded,
    keep: Keep,
) {
    if let Frame::Nmea(text) = f
        && d.unit.push(text)
    {
        return;
    }
    let before = *bridge.counters();
    bridge.push(f, &mut |e| absorb(d, e, keep));
    let after = bridge.counters();
    let malformed =
        (after.bad_field - before.bad_field) + (after.bad_position - before.bad_position);
    let tally = match kind(f) {
        Kind::Gps => &mut d.gps,
        Kind::Bearing => &mut d.bearing_records,
        Kind::Other => return,
    };
    tally.seen += 1;
    tally.malformed += malformed;
    tally.no_fix += after.no_fix_sentences - before.no_fix_sentences;
}

/// Decode whole captures (bytes as a UART delivered them).
pub fn decode(bytes: &[u8], config: BridgeConfig, keep_track: bool) -> Decoded {
    let mut dec = Decoder::new(config, keep_track);
    dec.feed(bytes);
    dec.finish()
}

impl Decoded {
    /// The bearings alone.
    pub fn bearings(&self) -> impl ExactSizeIterator<Item = &Bearing> + Clone {
        self.observations.iter().map(|o| &o.bearing)
    }

    /// The bearings as a list, each with noise `sigma` (radians).
    pub fn bearings_with_sigma(&self, sigma: f32) -> Vec<Bearing> {
        self.bearings().map(|b| Bearing { sigma, ..*b }).collect()
    }
}

/// What a live line's chunks are fed to: the bearings' decoder, or a decoder that reads an
/// anchors file's RSSI from the same bytes beside it.
pub trait LineFeed {
    /// The bearings' decoder, for what only it reads (records, sentences, inputs).
    fn bearings(&mut self) -> &mut Decoder;
    /// The line's bytes as they arrive.
    fn feed(&mut self, bytes: &[u8]) {
        self.bearings().feed(bytes);
    }
    /// The line went quiet: frames waiting on look-ahead are settled.
    fn idle(&mut self) {
        self.bearings().idle();
    }
}

impl LineFeed for Decoder {
    fn bearings(&mut self) -> &mut Decoder {
        self
    }
}
