//! foxhunt-bridge: the bytes the radios send, turned into measurements for foxhunt-core.
//!
//! [`stream`] splits a raw serial stream into checked records (NMEA sentences, TI
//! Monitor-and-Test frames, Agrelo bearings, KrakenSDR CSV lines and XML records), [`nmea`],
//! [`mt`], [`agrelo`] and [`kraken`] decode and encode them, [`geo`] puts positions in local
//! metres, and [`bridge`] turns fixes, headings, bearings and link qualities into core
//! measurements. The DF unit's own side: [`track`] keeps a fix on one emitter for ever in fixed
//! memory, [`telemetry`] writes and reads the unit's sentences, [`command`] its configuration
//! commands, [`unit`] puts ports, bridge and tracker together as the MCU runs them, and
//! [`replay`] runs the MCU's logged order of frames again on the host.
//! Nothing allocates; every buffer has a fixed capacity; every rejection is counted by reason.
#![cfg_attr(not(any(feature = "std", test)), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod agrelo;
pub mod bridge;
pub mod command;
pub mod geo;
pub mod kraken;
pub mod mt;
pub mod nmea;
pub mod replay;
pub mod stream;
pub mod telemetry;
pub mod track;
pub mod unit;

pub use bridge::{Bridge, BridgeConfig, BridgeCounters, Event, Receiver};
pub use stream::{Demux, Frame, KrakenCsvFrame, MtFrame, StreamCounters};
