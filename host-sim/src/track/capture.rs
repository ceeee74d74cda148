//! A capture decoded for tracking: its bearings as `locate` reads them
//! ([`crate::inputs::capture`], so every record format and every DF source it knows), and the
//! RSSI of an anchors file's anchors from the ZigBee coordinator's MT frames, each reading
//! timed by the GPS fix before it when the capture has fixes.

use crate::inputs::capture::{Decoded, Decoder, LineFeed};
use crate::track::indoor::{AnchorsFile, MAX_ANCHORS};
use foxhunt_bridge::Frame;
use foxhunt_bridge::bridge::{BridgeConfig, Event, Receiver};
use foxhunt_bridge::mt::AfIncomingMsg;
use std::collections::BTreeSet;

/// One RSSI reading of a known anchor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// The anchor's index in the anchors file.
    pub anchor: usize,
    /// Received power, dBm.
    pub dbm: f32,
    /// Bridge time of the last GPS fix before it, ms (none without fixes).
    pub after_fix_ms: Option<i64>,
}

/// What a capture gave the tracker.
#[derive(Debug, Clone, Default)]
pub struct Measured {
    /// The bearings and everything `locate` reads.
    pub decoded: Decoded,
    /// RSSI readings of the anchors file's anchors, in order.
    pub readings: Vec<Reading>,
    /// MT frames from addresses the anchors file does not list, and those addresses.
    pub unknown: (u32, BTreeSet<u16>),
    /// AF_INCOMING_MSG frames seen, from any address.
    pub rssi_frames: u32,
}

/// The bearings' decoder and, with an anchors file, a bridge holding its anchors, fed the same
/// bytes.
pub struct TrackDecoder {
    bearings: Decoder,
    rssi: Option<(Receiver<MAX_ANCHORS>, usize)>,
    addresses: Vec<u16>,
    last_fix_ms: Option<i64>,
    readings: Vec<Reading>,
    unknown: (BTreeSet<u16>, u32),
    frames: u32,
}

impl TrackDecoder {
    /// A decoder; `anchors` when the capture may hold RSSI (at most [`MAX_ANCHORS`]).
    pub fn new(anchors: Option<&AnchorsFile>) -> Self {
        let rssi = anchors.map(|f| {
            // Unused slots take an address no anchor has; their readings are dropped.
            let table: [(u16, [f32; 2]); MAX_ANCHORS] =
                std::array::from_fn(|i| match f.anchor.get(i) {
                    Some(a) => (a.addr, [a.x, a.y]),
                    None => (0xFFFF, [0.0, 0.0]),
                });
            (
                Receiver::new(BridgeConfig::default(), table),
                f.anchor.len().min(MAX_ANCHORS),
            )
        });
        Self {
            bearings: Decoder::new(BridgeConfig::default(), false),
            rssi,
            addresses: anchors
                .map(|f| f.anchor.iter().map(|a| a.addr).collect())
                .unwrap_or_default(),
            last_fix_ms: None,
            readings: Vec::new(),
            unknown: (BTreeSet::new(), 0),
            frames: 0,
        }
    }

    /// Feed bytes as they arrive.
    pub fn feed(&mut self, bytes: &[u8]) {
        self.bearings.feed(bytes);
        let Some((rx, used)) = self.rssi.as_mut() else {
            return;
        };
        let (demux, bridge) = (&mut rx.demux, &mut rx.bridge);
        let (readings, last, unknown, frames, addrs) = (
            &mut self.readings,
            &mut self.last_fix_ms,
            &mut self.unknown,
            &mut self.frames,
            &self.addresses,
        );
        let used = *used;
        demux.feed(bytes, &mut |f| {
            take(bridge, &f, used, addrs, readings, last, unknown, frames)
        });
    }

    /// The line went quiet: settle frames waiting on look-ahead.
    pub fn idle(&mut self) {
        self.bearings.idle();
        if let Some((rx, used)) = self.rssi.as_mut() {
            rx.demux.idle();
            let used = *used;
            while let Some(f) = rx.demux.next_frame() {
                take(
                    &mut rx.bridge,
                    &f,
                    used,
                    &self.addresses,
                    &mut self.readings,
                    &mut self.last_fix_ms,
                    &mut self.unknown,
                    &mut self.frames,
                );
            }
        }
    }

    /// The RSSI readings decoded since the last call, taken out (a line that never ends keeps
    /// none it handed on).
    pub fn take_readings(&mut self) -> Vec<Reading> {
        std::mem::take(&mut self.readings)
    }

    /// Frames from addresses the anchors file does not list, and those addresses.
    pub fn unknown(&self) -> (u32, &BTreeSet<u16>) {
        (self.unknown.1, &self.unknown.0)
    }

    /// What has been decoded so far (the bearings' frame and counters brought up to date).
    pub fn snapshot(&mut self) -> Measured {
        self.bearings.snapshot();
        Measured {
            decoded: self.bearings.decoded.clone(),
            readings: self.readings.clone(),
            unknown: (self.unknown.1, self.unknown.0.clone()),
            rssi_frames: self.frames,
        }
    }

    /// End of the stream: everything decoded.
    pub fn finish(mut self) -> Measured {
        if let Some((rx, used)) = self.rssi.as_mut() {
            let used = *used;
            let (demux, bridge) = (&mut rx.demux, &mut rx.bridge);
            let (readings, last, unknown, frames, addrs) = (
                &mut self.readings,
                &mut self.last_fix_ms,
                &mut self.unknown,
                &mut self.frames,
                &self.addresses,
            );
            demux.finish_into(&mut |f| {
                take(bridge, &f, used, addrs, readings, last, unknown, frames)
            });
        }
        Measured {
            decoded: self.bearings.finish(),
            readings: self.readings,
            unknown: (self.unknown.1, self.unknown.0),
            rssi_frames: self.frames,
        }
    }
}

impl LineFeed for TrackDecoder {
    fn bearings(&mut self) -> &mut Decoder {
        &mut self.bearings
    }
    fn feed(&mut self, bytes: &[u8]) {
        TrackDecoder::feed(self, bytes);
    }
    fn idle(&mut self) {
        TrackDecoder::idle(self);
    }
}

/// One frame into the RSSI bridge: readings of the listed anchors kept with the last fix's
/// time, other addresses counted.
#[allow(clippy::too_many_arguments)]
fn take(
    bridge: &mut foxhunt_bridge::Bridge<MAX_ANCHORS>,
    f: &Frame<'_>,
    used: usize,
    addresses: &[u16],
    readings: &mut Vec<Reading>,
    last_fix_ms: &mut Option<i64>,
    unknown: &mut (BTreeSet<u16>, u32),
    frames: &mut u32,
) {
    if let Frame::Mt(m) = f
        && let Ok(msg) = AfIncomingMsg::parse(m)
    {
        *frames += 1;
        if !addresses.contains(&msg.src_addr) {
            unknown.0.insert(msg.src_addr);
            unknown.1 += 1;
        }
    }
    bridge.push(f, &mut |e| match e {
        Event::Fix(fix) => *last_fix_ms = Some(fix.time_ms),
        Event::Rssi(r) if r.anchor < used => readings.push(Reading {
            anchor: r.anchor,
            dbm: r.dbm,
            after_fix_ms: *last_fix_ms,
        }),
        _ => {}
    });
}

/// Decode whole captures for tracking.
pub fn measure(bytes: &[u8], anchors: Option<&AnchorsFile>) -> Measured {
    let mut d = TrackDecoder::new(anchors);
    d.feed(bytes);
    d.finish()
}
