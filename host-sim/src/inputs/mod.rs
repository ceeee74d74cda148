//! What comes in: capture files and live lines decoded through the bridge, positions from
//! gpsd, a KrakenSDR's web pages, a DF unit's own sentences, and the side files (calibration,
//! roads).

pub mod calibration;
pub mod capture;
pub mod files;
pub mod gpsd;
pub mod kraken_http;
pub mod messages;
pub mod mqtt;
pub mod osm_pbf;
pub mod roads;
pub mod seen;
pub mod stations;
pub mod unit;
