//! What each update answers: the fix, what it is worth, and the work counted.

/// What a fix is worth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// A fix whose residuals agree with its noise.
    Valid,
    /// A fix, but the bearings scatter more than [`super::WindowConfig::max_sigma`]: not to be
    /// trusted.
    Noisy,
    /// The geometry gives no fix: parallel bearings, a vehicle that has not moved, a range
    /// without bound.
    Degenerate,
    /// Fewer than three bearings.
    TooFew,
    /// No pair of bearings crosses in front of the vehicle within range yet.
    Searching,
}

impl Status {
    /// The sentence letter: A, E, D, N, S.
    pub fn letter(self) -> u8 {
        match self {
            Self::Valid => b'A',
            Self::Noisy => b'E',
            Self::Degenerate => b'D',
            Self::TooFew => b'N',
            Self::Searching => b'S',
        }
    }

    /// The status a letter names.
    pub fn from_letter(c: u8) -> Option<Self> {
        Some(match c {
            b'A' => Self::Valid,
            b'E' => Self::Noisy,
            b'D' => Self::Degenerate,
            b'N' => Self::TooFew,
            b'S' => Self::Searching,
            _ => return None,
        })
    }

    /// Whether the fix carries a position.
    pub fn has_position(self) -> bool {
        matches!(self, Self::Valid | Self::Noisy)
    }
}

/// One update's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Update {
    /// Time of the newest bearing on the bridge's clock, ms.
    pub time_ms: i64,
    /// What the fix is worth; position and ellipse mean something only when
    /// [`Status::has_position`].
    pub status: Status,
    /// Emitter position (east, north) in the bridge's local frame, metres.
    pub position: [f32; 2],
    /// Position covariance, m^2 (at the noise used).
    pub covariance: [[f32; 2]; 2],
    /// Semi-major axis of the [`super::CONFIDENCE`] ellipse, metres.
    pub major: f32,
    /// Semi-minor axis, metres.
    pub minor: f32,
    /// Direction of the major axis, degrees clockwise from true north, in [0, 180).
    pub orientation_deg: f32,
    /// Circular error probable, metres.
    pub cep50: f32,
    /// Bearings with weight in the fix.
    pub used: u32,
    /// Bearings in the window.
    pub window: u32,
    /// Bearing noise used, radians (the stated sigma, or the estimate).
    pub sigma: f32,
    /// Passes over the window this update took.
    pub passes: u32,
}

/// Counters of the tracker's work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WindowCounters {
    /// Bearings taken into the window.
    pub bearings: u32,
    /// Bearings refused (non-finite, bad sigma).
    pub refused: u32,
    /// Pair searches run.
    pub searches: u32,
    /// Locks dropped (too few inliers, behind the vehicle, no bound).
    pub lost: u32,
}
