//! Tracking what moves: the moving-emitter tracker on any mix of stations, bearings and RSSI
//! ([`moving`]), and a ZigBee node indoors from the RSSI its fixed anchors report
//! ([`indoor`]).

pub mod capture;
pub mod direction;
pub mod indoor;
pub mod live;
pub mod moving;
pub mod noise;
pub mod tracks;
pub mod updates;
