//! A serial line end to end: the demultiplexer and the bridge.

use super::{Bridge, BridgeConfig, BridgeCounters, Event, MCU_STATIONS};
use crate::stream::{DEFAULT_CAPACITY, Demux, StreamCounters};

/// A serial line end to end: the demultiplexer and the bridge.
#[derive(Debug, Clone)]
pub struct Receiver<const A: usize = 0, const S: usize = MCU_STATIONS> {
    /// The byte-stream demultiplexer.
    pub demux: Demux<DEFAULT_CAPACITY>,
    /// The bridge.
    pub bridge: Bridge<A, S>,
}

impl<const A: usize, const S: usize> Receiver<A, S> {
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
