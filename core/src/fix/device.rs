//! What kind of DF device a station is, and what each kind is known to do to its bearings: its
//! typical noise, the noise beyond which a cluster of its bearings is no emitter (the
//! ceiling), and its unmodelled systematic error (the floor under the ellipse). The figures
//! and why: docs/src/networks.md, "Device classes".
//!
//! A station whose class is not stated keeps its records' own noise, the ceiling of
//! [`UNSTATED`] and no floor, as before classes existed.

use core::f32::consts::PI;

const DEG: f32 = PI / 180.0;

/// A kind of DF device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceClass {
    /// A pseudo-Doppler array on a vehicle or a mast.
    Doppler,
    /// A uniform circular array (KrakenSDR's usual five elements).
    Uca,
    /// A uniform linear array (front and back are mirror images).
    Ula,
    /// An Adcock or Watson-Watt array.
    Adcock,
    /// A directional antenna (a Yagi) turned by hand or by a rotator.
    Yagi,
    /// An indoor angle-of-arrival array (Bluetooth 5.1 direction finding and the like).
    IndoorAoa,
    /// Something else.
    Other,
}

/// What a device class does to its bearings, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClassNoise {
    /// Typical bearing noise (sd), the bearings' sigma where nothing else states one; `None`:
    /// the records' own.
    pub noise: Option<f32>,
    /// A cluster whose estimated noise exceeds this is no consistent emitter: the largest
    /// scatter a working unit of the class shows, with room.
    pub ceiling: f32,
    /// Sd of the unmodelled systematic error, common to the station's bearings, that no
    /// number of bearings averages away.
    pub unmodelled: f32,
}

/// A station of no stated class: its records' noise, a 10 degree ceiling, no floor.
pub const UNSTATED: ClassNoise = ClassNoise {
    noise: None,
    ceiling: 10.0 * DEG,
    unmodelled: 0.0,
};

impl DeviceClass {
    /// Every class, in the order the docs list them.
    pub const ALL: [DeviceClass; 7] = [
        DeviceClass::Doppler,
        DeviceClass::Uca,
        DeviceClass::Ula,
        DeviceClass::Adcock,
        DeviceClass::Yagi,
        DeviceClass::IndoorAoa,
        DeviceClass::Other,
    ];

    /// Its name in files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            DeviceClass::Doppler => "doppler",
            DeviceClass::Uca => "uca",
            DeviceClass::Ula => "ula",
            DeviceClass::Adcock => "adcock",
            DeviceClass::Yagi => "yagi",
            DeviceClass::IndoorAoa => "indoor-aoa",
            DeviceClass::Other => "other",
        }
    }

    /// The class of a name ([`DeviceClass::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// What the class does to its bearings (docs/src/networks.md, "Device classes").
    pub const fn noise(self) -> ClassNoise {
        let (noise, ceiling, unmodelled) = match self {
            DeviceClass::Doppler => (Some(3.0), 10.0, 1.0),
            DeviceClass::Uca => (Some(2.0), 10.0, 1.0),
            DeviceClass::Ula => (Some(3.0), 10.0, 1.0),
            DeviceClass::Adcock => (Some(2.0), 10.0, 0.5),
            DeviceClass::Yagi => (Some(8.0), 20.0, 2.0),
            DeviceClass::IndoorAoa => (Some(13.0), 25.0, 2.0),
            DeviceClass::Other => (None, 10.0, 1.0),
        };
        ClassNoise {
            noise: match noise {
                Some(n) => Some(n * DEG),
                None => None,
            },
            ceiling: ceiling * DEG,
            unmodelled: unmodelled * DEG,
        }
    }
}

/// The widest ceiling of any class, radians: bearings that scatter by more than this about
/// anything share nothing a DF unit could have measured.
pub const WIDEST_CEILING: f32 = {
    let mut widest = UNSTATED.ceiling;
    let mut k = 0;
    while k < DeviceClass::ALL.len() {
        let c = DeviceClass::ALL[k].noise().ceiling;
        if c > widest {
            widest = c;
        }
        k += 1;
    }
    widest
};

/// How a tracker takes a class's reports, where they differ from independent bearings at
/// the class's noise (docs/src/tracking.md, "Indoors from angles of arrival").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackTraits {
    /// How many times its noise sd a track gives each report (1: as they come).
    pub report_sd_factor: f32,
    /// The offset prior's sd where no one stated the station's own, radians (`None`: the
    /// track's default).
    pub offset_sd: Option<f32>,
    /// Seconds in which a track's offsets forget (`None`: the tracker's own).
    pub memory_s: Option<f32>,
}

/// Reports taken as they come.
pub const AS_REPORTED: TrackTraits = TrackTraits {
    report_sd_factor: 1.0,
    offset_sd: None,
    memory_s: None,
};

impl DeviceClass {
    /// How a track takes the class's reports. Every class but one: as they come. An indoor
    /// angle-of-arrival array's reports carry an error that stays while the emitter stays
    /// near one place (its angles compressed toward boresight beyond 40-60 degrees, by up
    /// to 19), at tens of reports a second: each report taken at twice its noise, the
    /// offsets' prior twice the sd of the arrays' biases (-5 to +7.5 degrees: 7.2) and
    /// forgetting in 10 s, so that they take up the compression where the emitter is.
    /// Trusting each report as it came held a walker 68 % of the time.
    pub const fn track(self) -> TrackTraits {
        match self {
            DeviceClass::IndoorAoa => TrackTraits {
                report_sd_factor: 2.0,
                offset_sd: Some(7.2 * DEG),
                memory_s: Some(10.0),
            },
            _ => AS_REPORTED,
        }
    }
}

/// What a station of `class` (`None`: not stated) does to its bearings.
pub const fn class_noise(class: Option<DeviceClass>) -> ClassNoise {
    match class {
        Some(c) => c.noise(),
        None => UNSTATED,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_reads_back_by_name_and_keeps_its_noise_under_its_ceiling() {
        for c in DeviceClass::ALL {
            assert_eq!(DeviceClass::from_name(c.name()), Some(c));
            let n = c.noise();
            // The ceiling leaves room above the typical noise (a unit half again as noisy as
            // its class is still a fix), and the floor is a fraction of a bearing's noise.
            assert!(n.noise.is_none_or(|s| 1.5 * s <= n.ceiling), "{c:?}");
            assert!(n.unmodelled > 0.0 && n.unmodelled < n.ceiling, "{c:?}");
            // A track takes every class's reports as they come but an indoor array's.
            assert_eq!(
                c.track() == AS_REPORTED,
                c != DeviceClass::IndoorAoa,
                "{c:?}"
            );
        }
        assert_eq!(DeviceClass::from_name("nonsense"), None);
        assert_eq!(WIDEST_CEILING, DeviceClass::IndoorAoa.noise().ceiling);
        assert_eq!(class_noise(None), UNSTATED);
    }
}
