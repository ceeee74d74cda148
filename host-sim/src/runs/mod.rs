//! Simulated drives and benchmarks: the canonical scenarios, captures written as the radios
//! would send them, seeded parallel Monte Carlo runs, the field conditions, the network
//! conditions, the closed-loop guidance benchmark, tracking scenarios and the speed measurements.

pub mod field;
pub mod guidance;
pub mod montecarlo;
pub mod moving;
pub mod mqtt_load;
pub mod network;
pub mod perf;
pub mod perf_track;
pub mod run;
pub mod scenario;
pub mod simulate;
pub mod small_n;
pub mod tracking;
pub mod writer;
