//! What is measured at one update time: bearings and RSSI readings, from any stations.

use crate::error::{Error, check_finite};
use crate::fix::observation::Observation;
use crate::model::rssi::PathLoss;

/// One RSSI reading: where it was received, what, and the receiver's path-loss law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// The receiving anchor or station (east, north), metres: fixed or moving.
    pub anchor: [f32; 2],
    /// Received power, dBm.
    pub dbm: f32,
    /// Its noise sd, dB (> 0).
    pub sigma_db: f32,
    /// The anchor's own path loss: the tracker's power offset and exponent correction are
    /// added to its P0 and eta.
    pub law: PathLoss,
}

impl Level {
    /// `Ok` when every field is finite, the noise and the reference distance positive.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[
            self.anchor[0],
            self.anchor[1],
            self.dbm,
            self.sigma_db,
            self.law.p0,
            self.law.d0,
            self.law.eta,
        ])?;
        if self.sigma_db > 0.0 && self.law.d0 > 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// The measurements of one update time: up to `K` bearings and `K` RSSI readings, and the
/// seconds since the previous update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Epoch<const K: usize> {
    /// Seconds since the previous update (0 for the first).
    pub dt: f32,
    bearings: [Observation; K],
    bearing_count: u8,
    levels: [Level; K],
    level_count: u8,
}

const EMPTY_LEVEL: Level = Level {
    anchor: [0.0; 2],
    dbm: 0.0,
    sigma_db: 1.0,
    law: PathLoss {
        p0: 0.0,
        d0: 1.0,
        eta: 2.0,
    },
};

const EMPTY_BEARING: Observation = Observation::new(
    crate::model::bearing::Bearing {
        vehicle: [0.0; 2],
        theta: 0.0,
        sigma: 1.0,
    },
    0.0,
);

impl<const K: usize> Epoch<K> {
    /// An update `dt` seconds after the previous one, with nothing measured yet.
    pub const fn new(dt: f32) -> Self {
        const {
            assert!(
                K > 0 && K <= u8::MAX as usize,
                "an epoch holds 1 to 255 of each"
            )
        };
        Self {
            dt,
            bearings: [EMPTY_BEARING; K],
            bearing_count: 0,
            levels: [EMPTY_LEVEL; K],
            level_count: 0,
        }
    }

    /// Add a bearing; [`Error::OutOfRange`] when `K` are held already.
    pub fn push_bearing(&mut self, o: Observation) -> Result<(), Error> {
        let slot = self
            .bearings
            .get_mut(self.bearing_count as usize)
            .ok_or(Error::OutOfRange)?;
        *slot = o;
        self.bearing_count += 1;
        Ok(())
    }

    /// Add an RSSI reading; [`Error::OutOfRange`] when `K` are held already.
    pub fn push_level(&mut self, l: Level) -> Result<(), Error> {
        let slot = self
            .levels
            .get_mut(self.level_count as usize)
            .ok_or(Error::OutOfRange)?;
        *slot = l;
        self.level_count += 1;
        Ok(())
    }

    /// The bearings.
    pub fn bearings(&self) -> &[Observation] {
        &self.bearings[..self.bearing_count as usize]
    }

    /// The bearings, to change in place (a source's noise scaled when it is estimated).
    pub fn bearings_mut(&mut self) -> &mut [Observation] {
        &mut self.bearings[..self.bearing_count as usize]
    }

    /// The RSSI readings.
    pub fn levels(&self) -> &[Level] {
        &self.levels[..self.level_count as usize]
    }

    /// Whether nothing was measured.
    pub fn is_empty(&self) -> bool {
        self.bearing_count == 0 && self.level_count == 0
    }

    /// Whether either list is full.
    pub fn is_full(&self) -> bool {
        self.bearing_count as usize == K || self.level_count as usize == K
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_epoch_holds_k_of_each_and_refuses_more() {
        let mut e = Epoch::<2>::new(1.0);
        assert!(e.is_empty());
        for _ in 0..2 {
            e.push_bearing(EMPTY_BEARING).unwrap();
        }
        assert_eq!(e.push_bearing(EMPTY_BEARING), Err(Error::OutOfRange));
        assert_eq!(e.bearings().len(), 2);
        assert!(e.is_full() && !e.is_empty());
        e.push_level(EMPTY_LEVEL).unwrap();
        assert_eq!(e.levels().len(), 1);
        let mut bad = EMPTY_LEVEL;
        bad.sigma_db = 0.0;
        assert_eq!(bad.check(), Err(Error::OutOfRange));
        bad.dbm = f32::NAN;
        assert_eq!(bad.check(), Err(Error::NonFinite));
    }
}
