//! A history as `locate` writes it: shared by the thread that reads the broker (each bearing
//! stored before it is acknowledged) and the updates, fed the decoder's bearings for every
//! other source, and read back into a decoder (a worker resuming, a replay).

use super::{History, Reader, Window};
use crate::inputs::capture::Decoder;
use crate::inputs::messages::{Stamper, today_ms};
use crate::inputs::mqtt::BearingMessage;
use crate::locate::report::{Located, NoFix};
use crate::outputs::terminal::{Stop, note};
use foxhunt_bridge::Frame;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

/// Failures noted before the rest are only counted.
const NOTED: u32 = 5;

/// A history being written by a run (cloned into the threads that write it).
#[derive(Debug, Clone)]
pub struct Recorder {
    history: Arc<Mutex<History>>,
    /// Bearings or updates the file did not take.
    failed: Arc<AtomicU32>,
}

impl Recorder {
    /// Open `path` to write ([`History::open`]).
    pub fn open(path: &Path) -> Result<Self, Stop> {
        Ok(Self {
            history: Arc::new(Mutex::new(History::open(path)?)),
            failed: Arc::new(AtomicU32::new(0)),
        })
    }

    /// A failure to store: noted, the first few. The run goes on: the fix matters more.
    fn failed(&self, e: &str, what: &str) {
        if self.failed.fetch_add(1, Ordering::Relaxed) < NOTED {
            note(&format!("{e}; {what} not stored"));
        }
    }

    /// Store bearing `m`; whether it is new (a bearing the file could not take counts as new:
    /// it is still fused).
    pub fn keep(&self, m: &BearingMessage) -> bool {
        match self
            .history
            .lock()
            .map_err(|_| "the history's lock".to_string())
            .and_then(|mut h| h.keep(m))
        {
            Ok(new) => new,
            Err(e) => {
                self.failed(&e, "a bearing");
                true
            }
        }
    }

    /// Store the bearings `dec` decoded since the last call (it keeps its measurements), as
    /// the network's messages.
    pub fn keep_decoded(&self, stamper: &mut Stamper, dec: &mut Decoder) {
        if dec.decoded.measurements.is_empty() {
            return;
        }
        dec.snapshot();
        if let Some(m) = dec.decoded.measurements.first() {
            stamper.date_live(m.time_ms);
        }
        for m in std::mem::take(&mut dec.decoded.measurements) {
            match stamper.message(dec, &m) {
                Ok(msg) => {
                    self.keep(&msg);
                }
                Err(e) => self.failed(&e, "a bearing"),
            }
        }
    }

    /// Store an update's outcome.
    pub fn keep_update(&self, located: &Result<Located, Box<NoFix>>) {
        if let Err(e) = self
            .history
            .lock()
            .map_err(|_| "the history's lock".to_string())
            .and_then(|mut h| h.keep_update(located))
        {
            self.failed(&e, "an update");
        }
    }

    /// Feed `dec` the bearings stored, in the order they arrived; how many.
    pub fn resume(&self, dec: &mut Decoder) -> Result<u64, Stop> {
        let h = self
            .history
            .lock()
            .map_err(|_| Stop::Error("the history's lock".into()))?;
        let n = h.bearings(|m| push(dec, &m))?;
        note(&format!(
            "history: {n} bearings resumed from {}",
            h.path().display()
        ));
        Ok(n)
    }

    /// Keep `dec`'s measurements from now on, for [`Recorder::keep_decoded`]: the stamper of
    /// its bearings, dated by its first one (the day nearest now) unless the caller says.
    pub fn stamper(&self, dec: &mut Decoder) -> Stamper {
        dec.keep_measurements();
        Stamper {
            station: None,
            day0_ms: today_ms(),
            dated: false,
        }
    }
}

/// A stored bearing into `dec`: the broker's path, its KrakenSDR record through the bridge.
fn push(dec: &mut Decoder, m: &BearingMessage) {
    dec.push_frame(&Frame::KrakenXml(m.record()));
}

/// Replay the bearings of `path` in `window` into `dec`; how many. The file is only read.
pub fn replay(path: &Path, window: Window, dec: &mut Decoder) -> Result<u64, Stop> {
    let n = Reader::open(path)?.bearings(window, |m| push(dec, &m))?;
    note(&format!(
        "history: {n} bearings replayed from {}",
        path.display()
    ));
    Ok(n)
}
