//! foxhunt-bridge: serial byte streams to measurements.
#![no_std]
#![deny(missing_docs)]
