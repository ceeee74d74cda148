//! Tracking a moving node: indoors from the RSSI fixed anchors report.

pub mod indoor;
