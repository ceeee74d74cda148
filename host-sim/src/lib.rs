//! foxhunt-sim: the host side of foxhunt. Simulation of the canonical scenarios, seeded
//! parallel Monte Carlo benchmarks of every method against the CRLB, and reports.
#![deny(missing_docs)]

pub mod field;
pub mod frames;
pub mod indoor;
pub mod live;
pub mod locate;
pub mod maps;
pub mod methods;
pub mod montecarlo;
pub mod perf;
pub mod report;
pub mod scenario;
pub mod simulate;
pub mod tracking;
