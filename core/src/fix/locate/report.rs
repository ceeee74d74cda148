//! What [`super::locate`] reports: the sources found (emitters and others), each channel's
//! outcome, and the observations set aside by reason.

use super::super::bias::BiasPrior;
use super::super::channel;
use super::super::ellipse::Ellipse;
use super::motion::Motion;
use crate::error::Error;

/// A located source: an emitter, or another point some bearings agree on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Source {
    /// The channel's frequency, the mean of its bearings', MHz (`None` for bearings without
    /// one).
    pub freq_mhz: Option<f32>,
    /// The channel's lowest frequency, where it starts, MHz (`None` for bearings without one):
    /// with the channel width, which bearings are the channel's ([`Source::in_channel`]).
    pub channel_lowest_mhz: Option<f32>,
    /// Position (east, north), metres.
    pub position: [f32; 2],
    /// Honest position covariance, m^2: offsets integrated out, at the noise used, widened by
    /// N / N_eff. The ellipse is x^T C^-1 x <= `ellipse_scale`.
    pub covariance: [[f32; 2]; 2],
    /// The `confidence` ellipse.
    pub ellipse: Ellipse,
    /// The ellipse's scale k (chi-square or 2 F(2, dof)).
    pub ellipse_scale: f32,
    /// Circular error probable, metres (with the same scaling).
    pub cep50: f32,
    /// The ellipse's major axis over the Fisher ellipse's (after the N / N_eff and far-side
    /// widening): above 1 where the likelihood reaches farther than its curvature at the fix
    /// says ([`super::super::reach`]), a range the bearings barely observe.
    pub stretch: f32,
    /// The bias-aware bound at the fix: sqrt(trace) of the marginal position block of the
    /// inverse information, at the noise used, metres.
    pub crlb: f32,
    /// Offset of the source's main station (the one with most bearings), radians.
    pub bias: f32,
    /// Its standard deviation, radians (0 for a calibrated station).
    pub bias_sd: f32,
    /// Which station `bias` is.
    pub bias_station: u16,
    /// Every station's offset in the fix: the range [start, end) of the offsets table lent
    /// with the working storage ([`super::Buffers`]); empty for other sources and where the
    /// table was full.
    pub offsets: [u32; 2],
    /// Bearing noise used, radians (the median bearing sigma times the scale).
    pub sigma: f32,
    /// Whether `sigma` was estimated from the residuals.
    pub sigma_estimated: bool,
    /// Bearings used.
    pub used: u32,
    /// Their effective number (N / tau, tau from the residuals' autocorrelation).
    pub effective: f32,
    /// Residual degrees of freedom: N_eff minus the effective unknowns.
    pub dof: f32,
    /// P(chi-square > observed) of the residuals against the bearings' stated sigmas.
    pub p_value: f32,
    /// How likely luck lines up this many bearings (smaller is surer).
    pub chance: f32,
    /// The residuals agree with the noise model and the noise is plausible.
    pub consistent: bool,
    /// How the main station's offset sat with its prior.
    pub offset_check: OffsetCheck,
    /// First and last input index of its bearings.
    pub index_span: [u32; 2],
    /// First and last time of its bearings, seconds.
    pub time_span: [f32; 2],
    /// P-value of the motion check ([`super::motion`]): how likely an emitter that stands still
    /// gives spans this far apart (`None`: too few bearings per span to check).
    pub motion_p: Option<f32>,
}

impl Source {
    /// Whether a bearing at `freq_mhz` (`None`: without a frequency) is in this source's
    /// channel, `width_mhz` being the channel width the bearings were grouped with
    /// ([`LocateConfig::channel_width_mhz`](super::LocateConfig::channel_width_mhz)): the
    /// grouping's own rule, [`channel::belongs`].
    pub fn in_channel(&self, freq_mhz: Option<f32>, width_mhz: f32) -> bool {
        channel::belongs(freq_mhz, self.channel_lowest_mhz, width_mhz)
    }
}

/// How a fix's offset sat with its prior (docs/src/field.md, "Past the prior").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OffsetCheck {
    /// The main station's offset, as first fitted with its prior, from the prior's mean in
    /// the sds the prior predicts for it ([`BiasPrior::surprise`]; 0 for a calibrated station).
    pub z: f32,
    /// The data contradicted the prior (|z| above
    /// [`CONTRADICTED_Z`](crate::fix::bias::CONTRADICTED_Z)) and the fix is the one
    /// with the offset free, started from the single minimum of its profile round the circle
    /// ([`crate::fix::bias::offset_circle`]): its ellipse carries the offset's uncertainty, and
    /// the unit needs checking all the same.
    pub relaxed: bool,
    /// The offset's profile round the circle has a minimum 30 degrees or more from the fit's
    /// offset about as likely as the best (0 against 180 degrees where the drive barely turns):
    /// the prior alone chose between them, and a swapped cable or an array indexed off would
    /// give the other.
    pub ambiguous: bool,
    /// The bearings did not measure the main station's offset (its sd, read at the
    /// residuals' correlation, above [`KNOWN_SD`](crate::fix::bias::KNOWN_SD)) and its prior
    /// does not state it that well: the fix holds only while the offset lies within its prior,
    /// which these bearings cannot check (a straight road, a fixed station).
    pub unmeasured: bool,
}

impl OffsetCheck {
    /// Whether the offset needs checking before the fix is trusted: relaxed or ambiguous.
    pub fn doubtful(&self) -> bool {
        self.relaxed || self.ambiguous
    }
}

/// An offset the data place far beyond its prior, where no fix is honest enough to report:
/// the offset's profile round the circle has two minima the data do not tell apart, or the
/// fit with the offset free finds nothing the checks accept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetBeyond {
    /// The station (its row in the station table).
    pub station: u16,
    /// Where its offset's profile round the circle is lowest, radians (to 15 degrees).
    pub offset: f32,
    /// The other minimum the data cannot rule out, radians, if any.
    pub second: Option<f32>,
    /// The prior the data contradicted.
    pub prior: BiasPrior,
    /// The first fit's offset from the prior's mean in predicted sds ([`OffsetCheck::z`]).
    pub z: f32,
}

/// One station's offset as an emitter's fix estimated it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationOffset {
    /// The station (its row in the station table).
    pub station: u16,
    /// Its bearings in the fix.
    pub used: u32,
    /// Its offset, radians.
    pub bias: f32,
    /// Its standard deviation, radians (the prior's for a calibrated station).
    pub sd: f32,
    /// Share of the offset's information the bearings gave (0: the prior alone, as for a
    /// fixed station; 1: measured by the drive).
    pub measured: f32,
    /// The prior it had.
    pub prior: BiasPrior,
}

impl StationOffset {
    /// An empty slot, to fill working storage with.
    pub const EMPTY: Self = Self {
        station: 0,
        used: 0,
        bias: 0.0,
        sd: 0.0,
        measured: 0.0,
        prior: BiasPrior { mean: 0.0, sd: 0.0 },
    };
}

/// Why bearings that agree on a point are not the channel's emitter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OtherReason {
    /// Fewer bearings agree on it than on the channel's emitter: a reflection (a stretch of
    /// the drive that saw a ghost) or a second transmitter on the channel.
    Weaker,
}

/// Another source: a point some bearings agree on besides the channel's emitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtherSource {
    /// Its fix.
    pub source: Source,
    /// Why it is not the emitter.
    pub why: OtherReason,
}

/// Why a channel has no consistent emitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoEmitter {
    /// No point has more bearings agreeing than luck would give.
    NoConsensus,
    /// The residuals' noise is beyond [`LocateConfig::max_sigma`](super::LocateConfig::max_sigma).
    TooNoisy,
    /// Too few bearings to estimate the noise and check the fit.
    TooFew,
    /// The geometry gives no fix (parallel bearings, a stationary vehicle...).
    Geometry(Error),
    /// A DF unit's offset lies far beyond its prior and no fix with it free holds up: check
    /// the antenna (mounting, array indexing, cables) and calibrate.
    OffsetBeyondPrior(OffsetBeyond),
    /// The emitter moves: the early and late bearings meet in places too far apart for their
    /// noise and the stations' offsets ([`super::motion`]). A track, not a fix.
    Moving(Motion),
}

/// What the bearings of a channel hold when their likelihood region is open in range (it runs
/// out to [`RansacOptions::max_range`](super::super::robust::RansacOptions::max_range), or the
/// bearings are parallel): no fix, but a line of bearing from the observers and a range
/// interval. The emitter is within `half_width` of `theta` seen from `apex`, and between
/// `min_range` and `max_range` of it, at the configured confidence (docs/src/field.md,
/// "Regions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// The channel's frequency, the mean of its bearings', MHz (`None` for bearings without
    /// one).
    pub freq_mhz: Option<f32>,
    /// The channel's lowest frequency, MHz (as [`Source::channel_lowest_mhz`]).
    pub channel_lowest_mhz: Option<f32>,
    /// Where the line of bearing starts (east, north), metres: the observers' centroid, each
    /// bearing weighted by its information, from which the best-fitting direction is the same
    /// at every range (to first order in the drive's extent over the range).
    pub apex: [f32; 2],
    /// The line of bearing, radians counter-clockwise from east (the model's angle; the
    /// outputs give it clockwise from north).
    pub theta: f32,
    /// The `confidence` half-width about `theta`, radians: the bearings' noise over their
    /// effective number, each station's offset prior in series (at long range the offset and
    /// the direction are one unknown); pi when an offset without a prior leaves the direction
    /// unknown.
    pub half_width: f32,
    /// The nearest range from `apex` the likelihood-ratio region allows, metres.
    pub min_range: f32,
    /// The farthest, metres; `None`: the region runs out to the search's range (unbounded).
    pub max_range: Option<f32>,
    /// The bearings (less their stations' offsets) spread by under
    /// [`PARALLEL_SPREAD`](super::PARALLEL_SPREAD): parallel, not merely crossing too
    /// shallowly for their noise.
    pub parallel: bool,
    /// The probability the region is drawn at.
    pub confidence: f32,
    /// Bearing noise used, radians.
    pub sigma: f32,
    /// Whether `sigma` was estimated from the residuals.
    pub sigma_estimated: bool,
    /// Bearings used.
    pub used: u32,
    /// Their effective number (N / tau).
    pub effective: f32,
    /// First and last input index of its bearings.
    pub index_span: [u32; 2],
    /// First and last time of its bearings, seconds.
    pub time_span: [f32; 2],
}

impl Region {
    /// Whether `p` (east, north, metres) is inside: within the half-width of the line of
    /// bearing and within the range interval.
    pub fn contains(&self, p: &[f32; 2]) -> bool {
        let d = [p[0] - self.apex[0], p[1] - self.apex[1]];
        let r = libm::hypotf(d[0], d[1]);
        let off = crate::model::bearing::wrap(libm::atan2f(d[1], d[0]) - self.theta).abs();
        off <= self.half_width && r >= self.min_range && self.max_range.is_none_or(|m| r <= m)
    }
}

/// What a channel came to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChannelOutcome {
    /// Its emitter is `emitters()[i]`.
    Emitter(usize),
    /// No fix: the range is open; what the bearings hold is `regions()[i]`.
    Region(usize),
    /// No consistent emitter.
    NoConsistentEmitter(NoEmitter),
}

/// One channel's summary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelReport {
    /// Frequency, MHz (`None` for bearings without one).
    pub freq_mhz: Option<f32>,
    /// Lowest frequency, where the channel starts, MHz (`None` for bearings without one): with
    /// the channel width, which bearings are the channel's ([`ChannelReport::holds`]).
    pub lowest_mhz: Option<f32>,
    /// Bearings in the channel (after the evidence checks).
    pub bearings: u32,
    /// What it came to.
    pub outcome: ChannelOutcome,
}

impl ChannelReport {
    /// Whether a bearing at `freq_mhz` (`None`: without a frequency) is in this channel,
    /// `width_mhz` being the channel width the bearings were grouped with: the grouping's own
    /// rule, [`channel::belongs`].
    pub fn holds(&self, freq_mhz: Option<f32>, width_mhz: f32) -> bool {
        channel::belongs(freq_mhz, self.lowest_mhz, width_mhz)
    }
}

/// Observations set aside, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rejected {
    /// Non-finite or out-of-range values (a bad sigma, a NaN angle, a negative frequency).
    pub invalid: u32,
    /// A station index beyond the station table ([`super::Buffers`]).
    pub unknown_station: u32,
    /// Beyond the working storage's capacity.
    pub over_capacity: u32,
    /// Exact repeats of earlier observations.
    pub repeated: u32,
    /// Older than their source's latest.
    pub time_backwards: u32,
    /// In a channel beyond the report's capacity.
    pub too_many_channels: u32,
    /// In a channel but agreeing with no source found (wild bearings).
    pub outliers: u32,
    /// In a channel without a consistent emitter.
    pub no_emitter: u32,
    /// In an other source beyond the report's capacity.
    pub too_many_sources: u32,
}

/// A slot not yet filled.
const EMPTY_SOURCE: Source = Source {
    freq_mhz: None,
    channel_lowest_mhz: None,
    position: [0.0; 2],
    covariance: [[0.0; 2]; 2],
    ellipse: Ellipse {
        major: 0.0,
        minor: 0.0,
        orientation: 0.0,
        confidence: 0.0,
    },
    ellipse_scale: 0.0,
    cep50: 0.0,
    stretch: 0.0,
    crlb: 0.0,
    bias: 0.0,
    bias_sd: 0.0,
    bias_station: 0,
    offsets: [0; 2],
    sigma: 0.0,
    sigma_estimated: false,
    used: 0,
    effective: 0.0,
    dof: 0.0,
    p_value: 0.0,
    chance: 0.0,
    consistent: false,
    offset_check: OffsetCheck {
        z: 0.0,
        relaxed: false,
        ambiguous: false,
        unmeasured: false,
    },
    index_span: [0; 2],
    time_span: [0.0; 2],
    motion_p: None,
};

/// A region slot not yet filled.
const EMPTY_REGION: Region = Region {
    freq_mhz: None,
    channel_lowest_mhz: None,
    apex: [0.0; 2],
    theta: 0.0,
    half_width: 0.0,
    min_range: 0.0,
    max_range: None,
    parallel: false,
    confidence: 0.0,
    sigma: 0.0,
    sigma_estimated: false,
    used: 0,
    effective: 0.0,
    index_span: [0; 2],
    time_span: [0.0; 2],
};

/// What [`super::locate`] found: up to `C` channels (one emitter each) and `O` other sources.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report<const C: usize, const O: usize> {
    pub(super) channels: [ChannelReport; C],
    pub(super) channel_count: usize,
    pub(super) emitters: [Source; C],
    pub(super) emitter_count: usize,
    pub(super) others: [OtherSource; O],
    pub(super) other_count: usize,
    pub(super) regions: [Region; C],
    pub(super) region_count: usize,
    /// Entries of the offsets table written.
    pub(super) offsets_written: usize,
    /// Observations set aside, by reason.
    pub rejected: Rejected,
    /// Observations accepted into the analysis (after the evidence checks).
    pub accepted: u32,
}

impl<const C: usize, const O: usize> Report<C, O> {
    /// Nothing found yet.
    pub(super) fn new() -> Self {
        Self {
            channels: [ChannelReport {
                freq_mhz: None,
                lowest_mhz: None,
                bearings: 0,
                outcome: ChannelOutcome::NoConsistentEmitter(NoEmitter::NoConsensus),
            }; C],
            channel_count: 0,
            emitters: [EMPTY_SOURCE; C],
            emitter_count: 0,
            others: [OtherSource {
                source: EMPTY_SOURCE,
                why: OtherReason::Weaker,
            }; O],
            other_count: 0,
            regions: [EMPTY_REGION; C],
            region_count: 0,
            offsets_written: 0,
            rejected: Rejected::default(),
            accepted: 0,
        }
    }

    /// One consistent emitter per channel that has one.
    pub fn emitters(&self) -> &[Source] {
        self.emitters.get(..self.emitter_count).unwrap_or(&[])
    }

    /// The regions of the channels whose range is open ([`ChannelOutcome::Region`]).
    pub fn regions(&self) -> &[Region] {
        self.regions.get(..self.region_count).unwrap_or(&[])
    }

    /// Other sources, every channel's.
    pub fn others(&self) -> &[OtherSource] {
        self.others.get(..self.other_count).unwrap_or(&[])
    }

    /// The per-station offsets of `source` (an emitter of this report) in `table`, the
    /// offsets table lent to [`super::locate`].
    pub fn offsets_of<'t>(
        &self,
        source: &Source,
        table: &'t [StationOffset],
    ) -> &'t [StationOffset] {
        let [a, b] = source.offsets;
        table.get(a as usize..b as usize).unwrap_or(&[])
    }

    /// Every channel and what it came to.
    pub fn channels(&self) -> &[ChannelReport] {
        self.channels.get(..self.channel_count).unwrap_or(&[])
    }
}
