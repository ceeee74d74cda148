//! `$PFOXB`: this project's bearing sentence from the direction finder.

use super::fields::{Fields, number, position, time};
use super::writer::{PositionField, TimeField};
use super::{LatLon, NmeaError, UtcTime};
use core::fmt::{self, Write};

/// Reference of a DF azimuth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reference {
    /// Clockwise from true north (`T`).
    True,
    /// Clockwise from the vehicle's heading (`R`).
    Relative,
}

/// `$PFOXB`: one bearing from the direction finder.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pfoxb {
    /// Time of the bearing.
    pub time: UtcTime,
    /// Azimuth, degrees in [0, 360).
    pub azimuth_deg: f64,
    /// What the azimuth is measured from.
    pub reference: Reference,
    /// DF quality 0..100.
    pub quality: f32,
    /// Frequency, MHz.
    pub freq_mhz: f64,
    /// The DF unit's own position, if it sent one.
    pub position: Option<LatLon>,
}

impl Pfoxb {
    pub(super) fn from_fields(f: &Fields<'_>) -> Result<Self, NmeaError> {
        let reference = match f.get(3) {
            "T" => Reference::True,
            "R" => Reference::Relative,
            _ => return Err(NmeaError::BadField(3)),
        };
        let position = match f.count {
            6 => None,
            10 => Some(position(f, 6).map_err(|e| match e {
                NmeaError::NoFix => NmeaError::BadField(6),
                e => e,
            })?),
            _ => return Err(NmeaError::BadField(f.count.min(255) as u8)),
        };
        Ok(Self {
            time: f.required(1, time)?,
            azimuth_deg: f.required(2, |s| number(s).filter(|v| (0.0..360.0).contains(v)))?,
            reference,
            quality: f.required(4, |s| number(s).filter(|v| (0.0..=100.0).contains(v)))? as f32,
            freq_mhz: f.required(5, |s| number(s).filter(|v| *v > 0.0))?,
            position,
        })
    }

    /// Write the body (`PFOXB,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let r = match self.reference {
            Reference::True => 'T',
            Reference::Relative => 'R',
        };
        write!(
            out,
            "PFOXB,{},{:.2},{r},{:.0},{:.3}",
            TimeField(self.time),
            self.azimuth_deg,
            self.quality,
            self.freq_mhz
        )?;
        if let Some(p) = self.position {
            write!(out, ",{}", PositionField(p))?;
        }
        Ok(())
    }
}
