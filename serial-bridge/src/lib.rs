//! foxhunt-bridge: the bytes the radios send, turned into measurements for foxhunt-core.
//!
//! [`stream`] splits a raw serial stream into checked records (NMEA sentences, TI
//! Monitor-and-Test frames, Agrelo bearings, KrakenSDR CSV lines and XML records), [`record`]
//! tells what a record is from its first bytes, [`nmea`], [`mt`], [`agrelo`] and [`kraken`]
//! decode and encode them, [`geo`] puts positions in local metres, and [`bridge`] turns
//! fixes, headings, bearings and link qualities into core measurements. The DF unit's own
//! side: [`telemetry`] writes and reads the unit's sentences, [`command`] its configuration
//! commands, [`unit`](mod@unit) puts ports, bridge and the core's windowed fix
//! (`foxhunt_core::fix::window`) together as the MCU runs them, and
//! [`replay`] runs the MCU's logged order of frames again on the host.
//! Nothing allocates; every buffer has a fixed capacity; every rejection is counted by reason.
//!
//! ```
//! use foxhunt_bridge::{BridgeConfig, Event, Receiver};
//! use foxhunt_bridge::nmea::write_sentence;
//!
//! // Two GPS fixes a second apart and a bearing between them, then a flipped byte.
//! let mut capture = String::new();
//! for body in [
//!     "GPGGA,120000.000,4700.000000,N,00800.000000,E,1,08,1.0,0.0,M,0.0,M,,",
//!     "PFOXB,120000.50,45.00,T,80,433.920",
//!     "GPGGA,120001.000,4700.000000,N,00800.000792,E,1,08,1.0,0.0,M,0.0,M,,",
//! ] {
//!     write_sentence(&mut capture, body).unwrap();
//! }
//! let mut bytes = capture.into_bytes();
//! bytes.extend_from_slice(b"$GPGGA,1200X2.000*00\r\n");
//! let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
//! let mut bearings = Vec::new();
//! // Any chunking gives the same result: here one byte at a time.
//! for b in &bytes {
//!     rx.feed(core::slice::from_ref(b), &mut |e| {
//!         if let Event::Bearing(m) = e {
//!             bearings.push(m.bearing);
//!         }
//!     });
//! }
//! rx.finish(&mut |_| {});
//! // The second fix is 0.000792 minutes (1.0 m) east of the first: the bearing, half a second
//! // after the first, is placed halfway, 0.5 m east.
//! assert_eq!(bearings.len(), 1);
//! assert!((bearings[0].vehicle[0] - 0.5).abs() < 0.01);
//! assert_eq!(rx.counters().0.bad_checksum, 1);
//! ```
#![cfg_attr(not(any(feature = "std", test)), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]
// The MCU image runs this crate: no unwrap, expect, panic or unreachable anywhere, and no
// unchecked indexing but in the byte decoders that allow it where they index the bytes they
// have measured (agrelo, geo, kraken, mt, nmea's field readers, stream). The firmware image
// test (tests/tests/firmware_image.rs) checks the linked image for panic calls in the rest.
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::unreachable,
    clippy::todo,
    clippy::unimplemented
)]

pub mod agrelo;
pub mod bridge;
pub mod command;
pub mod geo;
pub mod kraken;
pub mod mt;
pub mod nmea;
pub mod record;
pub mod replay;
pub mod stream;
pub mod telemetry;
pub mod unit;

pub use bridge::{Bridge, BridgeConfig, BridgeCounters, Event, Receiver};
pub use stream::{Demux, Frame, KrakenCsvFrame, MtFrame, StreamCounters};
