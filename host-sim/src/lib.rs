//! foxhunt-sim: the host side of foxhunt, the `foxhunt` command. Fixes of recorded and live
//! drives, indoor tracking, simulated captures, and seeded parallel Monte Carlo benchmarks of
//! every method of the core's registry against the CRLB.
//!
//! The folders follow the data, one way (each uses only those above it):
//! - [`inputs`]: the bytes and files that come in (captures decoded through the bridge, gpsd,
//!   a KrakenSDR's web pages, a DF unit's own sentences, calibration and road files);
//! - [`estimate`]: the core's estimators driven on the host (heap buffers, a thread pool);
//! - [`guidance`]: where to drive next and when to stop;
//! - [`locate`]: every emitter of a drive, recorded or live, and why there is none;
//! - [`track`]: a node followed indoors;
//! - [`outputs`]: what goes out (the terminal's words, tables, maps, the live map, frames);
//! - [`runs`]: simulated drives, scenarios and benchmarks;
//! - [`commands`]: the `foxhunt` subcommands, each reading its options and calling the rest.
#![deny(missing_docs)]

pub mod commands;
pub mod estimate;
pub mod guidance;
pub mod inputs;
pub mod locate;
pub mod outputs;
pub mod runs;
pub mod track;
