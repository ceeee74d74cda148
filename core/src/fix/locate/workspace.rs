//! The working storage [`super::locate`] borrows: no allocation, a capacity the caller picks.

use super::super::bias::Sighting;
use super::Observation;
use crate::model::bearing::Bearing;

/// An observation in the working storage, with where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item {
    pub(super) obs: Observation,
    /// Its index in the caller's input.
    pub(super) index: u32,
}

impl Item {
    /// An empty slot, to fill working storage with.
    pub const EMPTY: Self = Self {
        obs: Observation::new(
            Bearing {
                vehicle: [0.0; 2],
                theta: 0.0,
                sigma: 0.0,
            },
            0.0,
        ),
        index: 0,
    };
}

impl Sighting for Item {
    fn bearing(&self) -> &Bearing {
        &self.obs.bearing
    }
    fn source(&self) -> usize {
        self.obs.source as usize
    }
}

/// Working storage lent by the caller (a host can lend `Vec`s): the capacity is the shortest
/// of the four slices.
pub struct Buffers<'a> {
    pub(super) items: &'a mut [Item],
    pub(super) scratch: &'a mut [Item],
    pub(super) order: &'a mut [u32],
    pub(super) tags: &'a mut [u8],
}

impl<'a> Buffers<'a> {
    /// Borrow the four work areas.
    pub fn new(
        items: &'a mut [Item],
        scratch: &'a mut [Item],
        order: &'a mut [u32],
        tags: &'a mut [u8],
    ) -> Self {
        Self {
            items,
            scratch,
            order,
            tags,
        }
    }

    /// Observations that fit.
    pub fn capacity(&self) -> usize {
        self.items
            .len()
            .min(self.scratch.len())
            .min(self.order.len())
            .min(self.tags.len())
    }
}

/// Working storage for `B` observations (about 80 bytes each), e.g. in a `static` on the MCU.
pub struct Workspace<const B: usize> {
    items: [Item; B],
    scratch: [Item; B],
    order: [u32; B],
    tags: [u8; B],
}

impl<const B: usize> Default for Workspace<B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize> Workspace<B> {
    /// Empty storage.
    pub const fn new() -> Self {
        Self {
            items: [Item::EMPTY; B],
            scratch: [Item::EMPTY; B],
            order: [0; B],
            tags: [0; B],
        }
    }

    /// The storage as [`Buffers`].
    pub fn buffers(&mut self) -> Buffers<'_> {
        Buffers::new(
            &mut self.items,
            &mut self.scratch,
            &mut self.order,
            &mut self.tags,
        )
    }
}
