//! What an extract's readers hand over, whichever the format: the one interface between the
//! XML and PBF readers and what is built from them.

use foxhunt_bridge::nmea::LatLon;

/// What the two readers hand over, element by element, whichever the format.
pub(super) trait Extract {
    /// A node and where it is (as the file says: not checked).
    fn node(&mut self, id: i64, at: LatLon);
    /// A way: its nodes in order, their locations when the file carries them on the way
    /// (else empty), and its tags.
    fn way(&mut self, refs: &[i64], at: &[LatLon], tags: &mut dyn Iterator<Item = (&str, &str)>);
}
