//! What goes out: the terminal's words and standard output, files written only where asked,
//! benchmark tables, maps (GeoJSON, KML, SVG), Cursor-on-Target events to TAK, the decoded
//! frames, and the live map served to a browser.

pub mod cot;
pub mod files;
pub mod frames;
pub mod history;
pub mod json;
pub mod maps;
pub mod mqtt;
pub mod serve;
pub mod tables;
pub mod terminal;
pub mod text;
pub mod tracks;
