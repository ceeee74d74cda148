//! foxhunt-sim: the host side of foxhunt, the `foxhunt` command. Fixes of recorded and live
//! drives, indoor tracking, simulated captures, and seeded parallel Monte Carlo benchmarks of
//! every method of the core's registry against the CRLB.
#![deny(missing_docs)]

pub mod calibration;
pub mod capture;
pub mod cmd;
pub mod field;
pub mod frames;
pub mod gpsd;
pub mod guidance;
pub mod indoor;
pub mod io;
pub mod kraken_http;
pub mod live;
pub mod locate;
pub mod maps;
pub mod montecarlo;
pub mod perf;
pub mod report;
pub mod roads;
pub mod runs;
pub mod scenario;
pub mod serve;
pub mod simulate;
pub mod tracking;
pub mod unit;
