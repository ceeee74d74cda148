//! The DF unit end to end, as its MCU runs it and as the host replays it: bytes of each serial
//! port in, the unit's sentences out.
//!
//! Four ports, each with its own demultiplexer: the GPS receiver's NMEA ([`Port::Gps`]), the
//! DF unit's bearings in any format the bridge decodes ([`Port::Df`]), the ZigBee
//! coordinator's MT frames when configured ([`Port::Zigbee`]), and the user port
//! ([`Port::User`]), which carries configuration commands in ([`crate::command`]) and the
//! unit's sentences out ([`crate::telemetry`]). The first three feed one bridge; every bearing
//! it places goes to the core's windowed fix ([`WindowFix`]), and every update goes out as a `$PFOXF` sentence.
//!
//! Everything the unit says is a function of the order in which the ports' frames reach it
//! (and of nothing else: no clock, no randomness but the pair search's generator, seeded with [`SEARCH_SEED`]). So the
//! MCU logs, for each read that completed a frame, the port and its byte count so far, and
//! [`crate::replay`] feeds the same bytes in the same order on the host: identical bits.
//!
//! The bridge is configured with a bearing sigma of 1 radian, so each bearing's sigma is its
//! relative weight (1, or the quality weighting's widening); the windowed fix holds the unit's
//! sigma, which `SIGMA` then changes without touching the bridge.
//!
//! The fix sentences' cheap inverse projection is in `projection.rs`.

mod projection;

#[cfg(test)]
mod tests;

pub use projection::Projection;

use crate::bridge::{BearingMeasurement, Bridge, BridgeConfig, Event};
use crate::command::{self, Command};
use crate::nmea::UtcTime;
use crate::record::{RecordClass, RecordKind};
use crate::stream::{DEFAULT_CAPACITY, Demux, Frame};
use crate::telemetry::{FixSentence, LinkSentence, SentenceBuf};
use foxhunt_core::fix::window::{Noise, Status, Update, WindowConfig, WindowError, WindowFix};
use heapless::Deque;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const DAY_MS: i64 = 86_400_000;
/// The seed of the windowed fix's pair search.
pub const SEARCH_SEED: u64 = 0x9E37_79B9;
/// Bearings one frame can release at most (a GPS fix places every bearing waiting for it).
const RELEASED: usize = 24;

/// The unit's serial ports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Port {
    /// GPS NMEA (USART1).
    Gps = 0,
    /// The DF unit's bearings (USART2).
    Df = 1,
    /// The ZigBee coordinator's MT frames (UART4), read when configured.
    Zigbee = 2,
    /// Commands in, sentences out (USART3).
    User = 3,
}

impl Port {
    /// Every port, in index order.
    pub const ALL: [Port; 4] = [Port::Gps, Port::Df, Port::Zigbee, Port::User];

    /// The port with this index.
    pub fn from_index(i: u8) -> Option<Self> {
        Self::ALL.get(usize::from(i)).copied()
    }

    /// The port a record of a mixed capture belongs to, by its [`RecordKind`]: `$PFOXC`
    /// commands the user port; bearings (`$PFOXB`, Agrelo `%`, KrakenSDR XML `<` and CSV) the
    /// DF port; other sentences the GPS port; MT frames (`0xFE`) the ZigBee port. `None`: not
    /// the start of a record (the bytes go with the record before them).
    pub fn of_record(record: &[u8]) -> Option<Self> {
        Some(match RecordKind::of_record(record)?.class() {
            RecordClass::Command => Self::User,
            RecordClass::Bearing => Self::Df,
            RecordClass::Mt => Self::Zigbee,
            RecordClass::Position
            | RecordClass::Heading
            | RecordClass::Unit
            | RecordClass::OtherSentence => Self::Gps,
        })
    }
}

/// The unit's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitConfig {
    /// The bridge's (its `sigma_rad` is kept at 1: see the module doc).
    pub bridge: BridgeConfig,
    /// The windowed fix's.
    pub window: WindowConfig,
    /// Whether the ZigBee port is read.
    pub zigbee: bool,
}

impl Default for UnitConfig {
    fn default() -> Self {
        Self {
            bridge: BridgeConfig {
                sigma_rad: 1.0,
                ..BridgeConfig::default()
            },
            window: WindowConfig::default(),
            zigbee: false,
        }
    }
}

/// What one call did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Fed {
    /// Frames completed.
    pub frames: u32,
    /// Fix sentences sent.
    pub fixes: u32,
}

/// Counters of bridges replaced by a reconfiguration.
#[derive(Debug, Clone, Copy, Default)]
struct Retired {
    rejected: u32,
    bearings: u32,
}

/// The unit.
#[derive(Debug, Clone)]
pub struct Unit {
    demux: [Demux<DEFAULT_CAPACITY>; 4],
    bridge: Bridge<0>,
    state: State,
}

/// Everything but the demultiplexers and the bridge (so their callbacks may borrow it).
#[derive(Debug, Clone)]
struct State {
    config: UnitConfig,
    window: WindowFix,
    /// The pair search's generator: seeded, so the host's replay draws what the MCU drew.
    search: XorShiftRng,
    retired: Retired,
    fixes: u32,
    dropped: u32,
    /// Frames on the user port that are not commands.
    ignored: u32,
    last: Option<Update>,
    released: Deque<BearingMeasurement, RELEASED>,
    overflow: u32,
    projection: Option<Projection>,
}

fn rejected_by(b: &crate::bridge::BridgeCounters) -> u32 {
    [
        b.bad_field,
        b.bad_position,
        b.low_quality,
        b.no_bearing,
        b.no_heading,
        b.no_fix,
        b.stale_fix,
        b.time_jump,
        b.short_mt,
        b.unknown_anchor,
    ]
    .iter()
    .fold(0u32, |a, v| a.wrapping_add(*v))
}

impl Default for Unit {
    fn default() -> Self {
        Self::new(UnitConfig::default())
    }
}

impl Unit {
    /// A unit with these settings.
    pub fn new(config: UnitConfig) -> Self {
        Self {
            demux: [Demux::new(), Demux::new(), Demux::new(), Demux::new()],
            bridge: Bridge::new(config.bridge, []),
            state: State {
                config,
                window: WindowFix::new(config.window),
                search: XorShiftRng::seed_from_u64(SEARCH_SEED),
                retired: Retired::default(),
                fixes: 0,
                dropped: 0,
                ignored: 0,
                last: None,
                released: Deque::new(),
                overflow: 0,
                projection: None,
            },
        }
    }

    /// The settings now.
    pub fn config(&self) -> &UnitConfig {
        &self.state.config
    }

    /// Whether the ZigBee port is to be read.
    pub fn zigbee_enabled(&self) -> bool {
        self.state.config.zigbee
    }

    /// The bridge (its counters say why bearings were rejected).
    pub fn bridge(&self) -> &Bridge<0> {
        &self.bridge
    }

    /// The demultiplexer of a port (its counters say what framing rejected).
    pub fn demux(&self, port: Port) -> Option<&Demux<DEFAULT_CAPACITY>> {
        self.demux.get(port as usize)
    }

    /// The windowed fix.
    pub fn window(&self) -> &WindowFix {
        &self.state.window
    }

    /// The latest update of the fix.
    pub fn last_fix(&self) -> Option<&Update> {
        self.state.last.as_ref()
    }

    /// The link counters the unit keeps (overruns and full queues are the MCU's to fill in).
    pub fn link(&self) -> LinkSentence {
        let [g, d, z, u] = &self.demux;
        let bytes = |x: &Demux<DEFAULT_CAPACITY>| x.counters().bytes as u32;
        let stream = [g, d, z, u]
            .iter()
            .fold(0u32, |a, x| a.wrapping_add(x.counters().rejected()));
        let s = &self.state;
        LinkSentence {
            bytes: [bytes(g), bytes(d), bytes(z)],
            overruns: 0,
            full: 0,
            dropped: s.dropped,
            rejected: stream
                .wrapping_add(rejected_by(self.bridge.counters()))
                .wrapping_add(s.retired.rejected)
                .wrapping_add(s.window.counters().refused)
                .wrapping_add(s.ignored)
                .wrapping_add(s.overflow),
            bearings: self
                .bridge
                .counters()
                .bearings
                .wrapping_add(s.retired.bearings),
            fixes: s.fixes,
        }
    }

    /// Bytes from `port`, in any chunking; the unit's sentences go to `out`, which returns
    /// `false` when it had no room (the sentence is counted as dropped).
    pub fn feed(&mut self, port: Port, bytes: &[u8], out: &mut impl FnMut(&[u8]) -> bool) -> Fed {
        let mut fed = Fed::default();
        let Self {
            demux,
            bridge,
            state,
        } = self;
        let Some(d) = demux.get_mut(port as usize) else {
            return fed;
        };
        d.feed(bytes, &mut |f| {
            fed.frames += 1;
            state.frame(port, &f, bridge, out, &mut fed);
        });
        fed
    }

    /// `port` went quiet: settle the frame its demultiplexer holds back for look-ahead.
    pub fn idle(&mut self, port: Port, out: &mut impl FnMut(&[u8]) -> bool) -> Fed {
        let mut fed = Fed::default();
        let Self {
            demux,
            bridge,
            state,
        } = self;
        let Some(d) = demux.get_mut(port as usize) else {
            return fed;
        };
        d.idle();
        while let Some(f) = d.next_frame() {
            fed.frames += 1;
            state.frame(port, &f, bridge, out, &mut fed);
        }
        fed
    }
}

impl State {
    fn frame(
        &mut self,
        port: Port,
        f: &Frame<'_>,
        bridge: &mut Bridge<0>,
        out: &mut impl FnMut(&[u8]) -> bool,
        fed: &mut Fed,
    ) {
        if port == Port::User {
            match f {
                Frame::Nmea(body) if body.starts_with("PFOXC,") => self.command(body, bridge, out),
                _ => self.ignored = self.ignored.wrapping_add(1),
            }
            return;
        }
        let released = &mut self.released;
        let overflow = &mut self.overflow;
        bridge.push(f, &mut |e| {
            if let Event::Bearing(m) = e
                && released.push_back(m).is_err()
            {
                *overflow = overflow.wrapping_add(1);
            }
        });
        if let Some(frame) = bridge.local_frame()
            && self.projection.is_none_or(|p| p.origin != frame.origin)
        {
            self.projection = Projection::new(frame);
        }
        while let Some(m) = self.released.pop_front() {
            let Ok(fix) = self.window.push(&m.bearing, m.time_ms, &mut self.search) else {
                continue;
            };
            self.last = Some(fix);
            let position = self
                .projection
                .filter(|_| fix.status.has_position())
                .map(|p| p.at(f64::from(fix.position[0]), f64::from(fix.position[1])));
            let sentence = FixSentence {
                time: UtcTime {
                    ms_of_day: fix.time_ms.rem_euclid(DAY_MS) as u32,
                },
                position,
                major_m: fix.major,
                minor_m: fix.minor,
                orientation_deg: fix.orientation_deg,
                cep50_m: fix.cep50,
                used: fix.used,
                window: fix.window,
                sigma_deg: fix.sigma.to_degrees(),
                status: if position.is_some() || !fix.status.has_position() {
                    fix.status
                } else {
                    Status::Degenerate
                },
            };
            if self.send(sentence.write(), out) {
                self.fixes = self.fixes.wrapping_add(1);
                fed.fixes += 1;
            }
        }
    }

    fn send(&mut self, mut s: SentenceBuf, out: &mut impl FnMut(&[u8]) -> bool) -> bool {
        let sent = s.finish().is_some_and(out);
        if !sent {
            self.dropped = self.dropped.wrapping_add(1);
        }
        sent
    }

    /// A new bridge with `config` (the frame's origin kept unless `keep_origin` is false).
    fn rebuild(&mut self, bridge: &mut Bridge<0>, keep_origin: bool) {
        let old = bridge.counters();
        self.retired.rejected = self.retired.rejected.wrapping_add(rejected_by(old));
        self.retired.bearings = self.retired.bearings.wrapping_add(old.bearings);
        let mut c = self.config.bridge;
        if keep_origin && c.reference.is_none() {
            c.reference = bridge.local_frame().map(|f| f.origin);
        }
        *bridge = Bridge::new(c, []);
    }

    fn command(&mut self, body: &str, bridge: &mut Bridge<0>, out: &mut impl FnMut(&[u8]) -> bool) {
        let name = command::name_of(body);
        let mut ack = SentenceBuf::new("PFOXA");
        ack.field(name.as_bytes());
        let applied = Command::parse(body).and_then(|c| {
            self.apply(c, bridge)
                .map(|()| c)
                .map_err(|_| command::CommandError::BadArgument)
        });
        match applied {
            Ok(c) => {
                ack.field(b"OK");
                self.describe(c, &mut ack);
            }
            Err(e) => {
                ack.field(b"ERR").field(e.word().as_bytes());
            }
        }
        self.send(ack, out);
    }

    fn apply(&mut self, c: Command, bridge: &mut Bridge<0>) -> Result<(), WindowError> {
        let window = self.config.window;
        match c {
            Command::Sigma(s) => {
                let noise = match s {
                    Some(deg) => Noise::Known(deg.to_radians()),
                    None => Noise::Estimated(match window.noise {
                        Noise::Known(s) | Noise::Estimated(s) => s,
                    }),
                };
                let t = WindowConfig { noise, ..window };
                self.window.set_config(t)?;
                self.config.window = t;
            }
            Command::Window { count, seconds } => {
                let t = WindowConfig {
                    window: count,
                    max_age_ms: seconds.saturating_mul(1000),
                    ..window
                };
                self.window.set_config(t)?;
                self.config.window = t;
            }
            Command::Gate(q) => {
                self.config.bridge.min_quality = q;
                self.rebuild(bridge, true);
            }
            Command::Mount(deg) => {
                self.config.bridge.mount_offset_deg = deg;
                self.rebuild(bridge, true);
                self.window.clear();
            }
            Command::Reference(r) => {
                self.config.bridge.reference = r;
                self.rebuild(bridge, false);
                self.window.clear();
            }
            Command::Zigbee(on) => self.config.zigbee = on,
            Command::Show => {}
        }
        Ok(())
    }

    /// The acknowledgement's detail: the setting as applied (every setting for `SHOW`).
    fn describe(&self, c: Command, ack: &mut SentenceBuf) {
        let cfg = &self.config;
        let sigma = |ack: &mut SentenceBuf| match cfg.window.noise {
            Noise::Known(s) => {
                ack.fixed(s.to_degrees(), 2);
            }
            Noise::Estimated(_) => {
                ack.field(b"EST");
            }
        };
        let window = |ack: &mut SentenceBuf| {
            ack.uint(u32::from(cfg.window.window), 1)
                .uint(cfg.window.max_age_ms / 1000, 1);
        };
        let reference = |ack: &mut SentenceBuf| match cfg.bridge.reference {
            Some(p) => {
                ack.angle(p.lat, false).angle(p.lon, true);
            }
            None => {
                ack.field(b"AUTO");
            }
        };
        let zigbee = |ack: &mut SentenceBuf| {
            ack.field(if cfg.zigbee { b"ON" } else { b"OFF" });
        };
        match c {
            Command::Sigma(_) => sigma(ack),
            Command::Gate(_) => {
                ack.fixed(cfg.bridge.min_quality, 1);
            }
            Command::Reference(_) => reference(ack),
            Command::Mount(_) => {
                ack.signed(cfg.bridge.mount_offset_deg, 1);
            }
            Command::Window { .. } => window(ack),
            Command::Zigbee(_) => zigbee(ack),
            Command::Show => {
                sigma(ack);
                ack.fixed(cfg.bridge.min_quality, 1);
                ack.signed(cfg.bridge.mount_offset_deg, 1);
                window(ack);
                zigbee(ack);
                reference(ack);
            }
        }
    }
}
