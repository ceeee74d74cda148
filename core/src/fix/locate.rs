//! One entry point from bearings to emitters, honest about what the bearings hold.
//!
//! [`locate`] takes bearings (with their time, DF source and, if known, frequency) and returns
//! one emitter per channel, the other sources the bearings agree on, and what was rejected and
//! why. In order:
//!
//! 1. **Intake**: unusable observations (non-finite, bad sigma, unknown source, no room) are
//!    counted by reason.
//! 2. **Evidence counted once** ([`super::evidence`]): exact repeats and bearings older than
//!    their source's latest are set aside.
//! 3. **Channels** ([`super::channel`]): by frequency, one emitter per channel.
//! 4. **Sequential consensus** per channel ([`super::robust`]): the point most bearings agree
//!    on (RANSAC over pairs, each hypothesis with its best offset), refined by Tukey then
//!    trimmed ML over [x, y, offsets] ([`super::bias`]); its bearings are removed and the
//!    search repeats on the rest. The cluster with most bearings is the channel's emitter; the
//!    others (a reflection, a second transmitter on the channel) are reported as other sources
//!    with their own fix, count and span, their offsets' prior taken from the emitter's
//!    estimate (the same DF unit).
//! 5. **Consistency, always**: a cluster that luck could have lined up (uniform bearings, the
//!    search's size accounted for), or whose estimated noise exceeds
//!    [`LocateConfig::max_sigma`], is "no consistent emitter", a typed outcome, not a fix. The
//!    covariance is widened by N / N_eff (the residuals' autocorrelation), and the ellipse is
//!    scaled by 2 F(2, N_eff - p) when the noise was estimated ([`NoiseModel::Estimated`]), or
//!    by chi-square when the DF unit's sigmas hold ([`NoiseModel::Known`], checked by the
//!    residuals' chi-square; a unit noisier than it claims gets the estimated scale and
//!    `consistent: false`). The ellipse is then made to hold the likelihood-ratio region along
//!    its major axis ([`super::reach`]): driving at the emitter, the Fisher ellipse at a fix on
//!    the line of bearing next to the vehicle is tens of metres while the likelihood stays flat
//!    for kilometres. A region that runs out to [`RansacOptions::max_range`] is "no consistent
//!    emitter" with [`Error::ParallelBearings`]: the range is unobservable, not a fix.
//!
//! No allocation: the caller lends the working storage ([`Buffers`], or a [`Workspace`] of
//! fixed capacity `B`), the report holds at most `C` channels and `O` other sources, and every
//! iterative step has a hard cap (RANSAC's hypotheses and attempts, the solver's iterations,
//! the trimming rounds, the autocorrelation's lags, the sources per channel).
//!
//! ```
//! use foxhunt_core::fix::locate::{LocateConfig, Observation, Workspace, locate};
//! use foxhunt_core::model::bearing::{Bearing, predicted};
//! use rand_core::SeedableRng;
//!
//! // Forty bearings from a drive past an emitter at (300, 400), a 2 degree offset and some
//! // noise on them.
//! let emitter = [300.0f32, 400.0];
//! let obs: [Observation; 40] = core::array::from_fn(|k| {
//!     let v = [25.0 * k as f32, 0.04 * (k * k) as f32];
//!     let error = 0.035 + 0.01 * (1.7 * k as f32).sin();
//!     let bearing = Bearing { vehicle: v, theta: predicted(&emitter, &v) + error, sigma: 0.01 };
//!     Observation::new(bearing, k as f32)
//! });
//! let mut work = Workspace::<64>::new();
//! let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
//! let report = locate::<2, 2, _>(&obs, &LocateConfig::default(), work.buffers(), &mut rng)?;
//! let e = &report.emitters()[0];
//! assert!(e.consistent && e.ellipse.contains(&e.position, &emitter));
//! assert!((e.bias - 0.035).abs() < 3.0 * e.bias_sd);
//! # Ok::<(), foxhunt_core::Error>(())
//! ```

use super::bias::{BiasPrior, BiasedOptions, MAX_SOURCES, Sighting, Start, same_priors};
use super::channel::{self, NO_CHANNEL};
use super::consistency;
use super::ellipse::Ellipse;
use super::evidence::{self, Verdict};
use super::reach;
use super::robust::{self, OffsetWindow, RansacOptions, RefineOptions, TRIM_CUT};
use crate::error::{Error, check_finite};
use crate::likelihood::Gaussian;
use crate::model::bearing::{Bearing, predicted, wrap};
use crate::stats;
use rand_core::Rng;

pub use super::observation::Observation;

/// An observation in the working storage, with where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item {
    obs: Observation,
    index: u32,
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
    items: &'a mut [Item],
    scratch: &'a mut [Item],
    order: &'a mut [u32],
    tags: &'a mut [u8],
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

/// How far the bearings' own sigmas are trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NoiseModel {
    /// Estimate the noise from the residuals; intervals use the F distribution.
    #[default]
    Estimated,
    /// The sigmas are the unit's, checked by the residuals' chi-square.
    Known,
}

/// Settings of [`locate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocateConfig {
    /// Whether the bearings' sigmas are estimated or trusted.
    pub noise: NoiseModel,
    /// Prior of each DF source's offset ([`BiasPrior::calibrated`] for a calibrated unit).
    pub priors: [BiasPrior; MAX_SOURCES],
    /// Frequencies within this of a channel's lowest share the channel, MHz.
    pub channel_width_mhz: f32,
    /// Probability inside the reported ellipses.
    pub confidence: f32,
    /// Estimated noise above this (radians) means no consistent emitter.
    pub max_sigma: f32,
    /// A cluster is a source only if luck would line up as many bearings with a chance below
    /// this.
    pub significance: f32,
    /// With [`NoiseModel::Known`], a residual chi-square p-value below this marks the unit
    /// noisier than it claims.
    pub consistency: f32,
    /// Sources (emitter and others) sought per channel at most.
    pub max_sources_per_channel: u32,
    /// Bearings a source needs at least.
    pub min_bearings: u32,
    /// The robust search.
    pub ransac: RansacOptions,
    /// The solver.
    pub solver: BiasedOptions,
}

impl Default for LocateConfig {
    fn default() -> Self {
        Self {
            noise: NoiseModel::Estimated,
            priors: same_priors(BiasPrior::default()),
            channel_width_mhz: 0.05,
            confidence: 0.95,
            max_sigma: 10.0 * core::f32::consts::PI / 180.0,
            significance: 0.01,
            consistency: 1e-3,
            max_sources_per_channel: 4,
            min_bearings: 3,
            ransac: RansacOptions::default(),
            solver: BiasedOptions::default(),
        }
    }
}

impl LocateConfig {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), Error> {
        for p in &self.priors {
            p.check()?;
        }
        self.ransac.check()?;
        check_finite(&[
            self.channel_width_mhz,
            self.confidence,
            self.max_sigma,
            self.significance,
            self.consistency,
        ])?;
        if self.channel_width_mhz >= 0.0
            && self.confidence > 0.0
            && self.confidence < 1.0
            && self.max_sigma > 0.0
            && self.significance > 0.0
            && self.consistency >= 0.0
            && self.min_bearings >= 3
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// A located source: an emitter, or another point some bearings agree on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Source {
    /// The channel's frequency, MHz (`None` for bearings without one).
    pub freq_mhz: Option<f32>,
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
    /// says ([`super::reach`]), a range the bearings barely observe.
    pub stretch: f32,
    /// The bias-aware bound at the fix: sqrt(trace) of the marginal position block of the
    /// inverse information, at the noise used, metres.
    pub crlb: f32,
    /// Offset of the source's main DF unit (the one with most bearings), radians.
    pub bias: f32,
    /// Its standard deviation, radians (0 for a calibrated unit).
    pub bias_sd: f32,
    /// Which DF unit `bias` is.
    pub bias_source: u8,
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
    /// First and last input index of its bearings.
    pub index_span: [u32; 2],
    /// First and last time of its bearings, seconds.
    pub time_span: [f32; 2],
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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoEmitter {
    /// No point has more bearings agreeing than luck would give.
    NoConsensus,
    /// The residuals' noise is beyond [`LocateConfig::max_sigma`].
    TooNoisy,
    /// Too few bearings to estimate the noise and check the fit.
    TooFew,
    /// The geometry gives no fix (parallel bearings, a stationary vehicle...).
    Geometry(Error),
}

/// What a channel came to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChannelOutcome {
    /// Its emitter is `emitters()[i]`.
    Emitter(usize),
    /// No consistent emitter.
    NoConsistentEmitter(NoEmitter),
}

/// One channel's summary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelReport {
    /// Frequency, MHz (`None` for bearings without one).
    pub freq_mhz: Option<f32>,
    /// Bearings in the channel (after the evidence checks).
    pub bearings: u32,
    /// What it came to.
    pub outcome: ChannelOutcome,
}

/// Observations set aside, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rejected {
    /// Non-finite or out-of-range values (a bad sigma, a NaN angle, a negative frequency).
    pub invalid: u32,
    /// A DF source index beyond [`MAX_SOURCES`].
    pub unknown_source: u32,
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

const EMPTY_SOURCE: Source = Source {
    freq_mhz: None,
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
    bias_source: 0,
    sigma: 0.0,
    sigma_estimated: false,
    used: 0,
    effective: 0.0,
    dof: 0.0,
    p_value: 0.0,
    chance: 0.0,
    consistent: false,
    index_span: [0; 2],
    time_span: [0.0; 2],
};

/// What [`locate`] found: up to `C` channels (one emitter each) and `O` other sources.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report<const C: usize, const O: usize> {
    channels: [ChannelReport; C],
    channel_count: usize,
    emitters: [Source; C],
    emitter_count: usize,
    others: [OtherSource; O],
    other_count: usize,
    /// Observations set aside, by reason.
    pub rejected: Rejected,
    /// Observations accepted into the analysis (after the evidence checks).
    pub accepted: u32,
}

impl<const C: usize, const O: usize> Report<C, O> {
    fn new() -> Self {
        Self {
            channels: [ChannelReport {
                freq_mhz: None,
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
            rejected: Rejected::default(),
            accepted: 0,
        }
    }

    /// One consistent emitter per channel that has one.
    pub fn emitters(&self) -> &[Source] {
        self.emitters.get(..self.emitter_count).unwrap_or(&[])
    }

    /// Other sources, every channel's.
    pub fn others(&self) -> &[OtherSource] {
        self.others.get(..self.other_count).unwrap_or(&[])
    }

    /// Every channel and what it came to.
    pub fn channels(&self) -> &[ChannelReport] {
        self.channels.get(..self.channel_count).unwrap_or(&[])
    }
}

/// What an observation's intake check says.
fn intake(o: &Observation) -> Result<(), Error> {
    o.bearing.check()?;
    check_finite(&[o.time_s])?;
    if let Some(f) = o.freq_mhz {
        check_finite(&[f])?;
        if f < 0.0 {
            return Err(Error::OutOfRange);
        }
    }
    Ok(())
}

/// Locate every emitter the observations hold. See the module docs for the steps.
pub fn locate<const C: usize, const O: usize, R: Rng + ?Sized>(
    observations: &[Observation],
    config: &LocateConfig,
    work: Buffers<'_>,
    rng: &mut R,
) -> Result<Report<C, O>, Error> {
    config.check()?;
    let cap = work.capacity();
    let Buffers {
        items,
        scratch,
        order,
        tags,
    } = work;
    let mut report = Report::<C, O>::new();
    let rej = &mut report.rejected;
    // 1. Intake.
    let mut n = 0usize;
    for (i, o) in observations.iter().enumerate() {
        if (o.source as usize) >= MAX_SOURCES {
            rej.unknown_source += 1;
        } else if intake(o).is_err() {
            rej.invalid += 1;
        } else if n >= cap || i > u32::MAX as usize {
            rej.over_capacity += 1;
        } else if let Some(slot) = items.get_mut(n) {
            *slot = Item {
                obs: *o,
                index: i as u32,
            };
            n += 1;
        }
    }
    // 2. Evidence counted once.
    let counts = {
        let seen = &items[..n];
        evidence::sort_out(n, |i| seen.get(i).map(|it| it.obs), order, tags)?
    };
    rej.repeated = counts.repeated;
    rej.time_backwards = counts.backwards;
    let mut kept = 0;
    for i in 0..n {
        if tags[i] == Verdict::Fresh as u8 {
            items[kept] = items[i];
            kept += 1;
        }
    }
    let n = kept;
    report.accepted = n as u32;
    // 3. Channels: tags[i] becomes the channel of items[i].
    let channels = {
        let seen = &items[..n];
        channel::group::<C>(
            n,
            |i| seen.get(i).map(|it| it.obs.freq_mhz),
            config.channel_width_mhz,
            order,
            tags,
        )?
    };
    rej.too_many_channels = channels.overflow;
    // Each channel's bearings made contiguous, in input order within it (channels in order,
    // the unchannelled last): sorted through `scratch`, the channel of position k kept in
    // order[k].
    for (k, slot) in order.iter_mut().enumerate().take(n) {
        *slot = k as u32;
    }
    super::order::heapsort_by(&mut order[..n], |a, b| {
        (tags[*a as usize], *a) < (tags[*b as usize], *b)
    });
    for (s, &i) in scratch.iter_mut().zip(order.iter()).take(n) {
        *s = items[i as usize];
    }
    let mut channelled = 0;
    for k in 0..n {
        let c = tags[order[k] as usize];
        items[k] = scratch[k];
        order[k] = c as u32;
        if c != NO_CHANNEL {
            channelled = k + 1;
        }
    }
    let n = channelled;
    // 4-5. Each channel.
    let mut start = 0usize;
    for c in 0..channels.len() {
        let mut end = start;
        while end < n && order[end] == c as u32 {
            end += 1;
        }
        let freq = channels.freq(c).flatten();
        let outcome = channel_sources(
            &mut items[start..end],
            &mut scratch[start..end],
            freq,
            config,
            &mut report,
            rng,
        );
        if let Some(slot) = report.channels.get_mut(report.channel_count) {
            *slot = ChannelReport {
                freq_mhz: freq,
                bearings: (end - start) as u32,
                outcome,
            };
            report.channel_count += 1;
        }
        start = end;
    }
    Ok(report)
}

/// The sources of one channel: sequential consensus on `run` (its bearings, in input order),
/// pushed into `report`. Returns the channel's outcome.
fn channel_sources<const C: usize, const O: usize, R: Rng + ?Sized>(
    run: &mut [Item],
    scratch: &mut [Item],
    freq: Option<f32>,
    config: &LocateConfig,
    report: &mut Report<C, O>,
    rng: &mut R,
) -> ChannelOutcome {
    let mut len = run.len();
    let mut priors = config.priors;
    let mut outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::NoConsensus);
    for k in 0..config.max_sources_per_channel {
        let first = k == 0;
        let set = &run[..len];
        if (len as u32) < config.min_bearings {
            if first {
                outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::TooFew);
            }
            break;
        }
        let found = find_source(set, scratch, &priors, freq, config, rng);
        let (source, kept, fix_bias) = match found {
            Ok(f) => f,
            Err(why) => {
                if first {
                    outcome = ChannelOutcome::NoConsistentEmitter(why);
                }
                break;
            }
        };
        if first {
            if let Some(slot) = report.emitters.get_mut(report.emitter_count) {
                *slot = source;
                outcome = ChannelOutcome::Emitter(report.emitter_count);
                report.emitter_count += 1;
            }
            // The same DF units saw the other sources: the emitter's offsets are their prior.
            for s in 0..MAX_SOURCES {
                if priors[s].is_free() && fix_bias.1[s] > 0.0 {
                    priors[s] = BiasPrior {
                        mean: fix_bias.0[s],
                        sd: fix_bias.1[s],
                    };
                }
            }
        } else if let Some(slot) = report.others.get_mut(report.other_count) {
            *slot = OtherSource {
                source,
                why: OtherReason::Weaker,
            };
            report.other_count += 1;
        } else {
            report.rejected.too_many_sources += kept as u32;
        }
        // Remove the source's bearings (the first `kept` of scratch, in input order) from the
        // run, keeping the rest in order.
        len = remove_kept(&mut run[..len], &scratch[..kept]);
    }
    match outcome {
        ChannelOutcome::Emitter(_) => report.rejected.outliers += len as u32,
        ChannelOutcome::NoConsistentEmitter(_) => report.rejected.no_emitter += run.len() as u32,
    }
    outcome
}

/// Drop from `run` every item of `kept` (both in increasing input index); returns the new
/// length of `run`.
fn remove_kept(run: &mut [Item], kept: &[Item]) -> usize {
    let mut j = 0;
    let mut out = 0;
    for i in 0..run.len() {
        let it = run[i];
        while j < kept.len() && kept[j].index < it.index {
            j += 1;
        }
        if j < kept.len() && kept[j].index == it.index {
            continue;
        }
        run[out] = it;
        out += 1;
    }
    out
}

/// Offsets and their sds of a fix, to pass on as priors.
type Offsets = ([f32; MAX_SOURCES], [f32; MAX_SOURCES]);

/// One source from `set`: the consensus, its refinement and its honest statistics. On success
/// the source's bearings are the first `kept` of `scratch`.
fn find_source<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    priors: &[BiasPrior; MAX_SOURCES],
    freq: Option<f32>,
    config: &LocateConfig,
    rng: &mut R,
) -> Result<(Source, usize, Offsets), NoEmitter> {
    let window = OffsetWindow::from_priors(priors);
    let consensus =
        robust::ransac(set, &config.ransac, window, rng).map_err(NoEmitter::Geometry)?;
    let first_chance = robust::chance(
        consensus.inliers,
        consensus.candidates,
        consensus.threshold,
        consensus.hypotheses,
        window.half_width,
    )
    .map_err(NoEmitter::Geometry)?;
    if first_chance > config.significance {
        return Err(NoEmitter::NoConsensus);
    }
    let refined = robust::refine(
        set,
        scratch,
        priors,
        &consensus,
        RefineOptions {
            estimate_scale: true,
            solver: config.solver,
        },
    )
    .map_err(|e| match e {
        Error::TooFewMeasurements => NoEmitter::TooFew,
        e => NoEmitter::Geometry(e),
    })?;
    let kept = refined.kept as usize;
    let members = scratch.get(..kept).ok_or(NoEmitter::TooFew)?;
    let median = median_sigma(members);
    let estimated_sigma = refined.scale * median;
    // Significance again, with the refined set and its own agreement width.
    let cut = robust::trim_cut(refined.kept, kept as f32 - refined.fix.parameters);
    let width = (cut.min(2.0 * TRIM_CUT) * estimated_sigma).max(consensus.threshold);
    let chance = robust::chance(
        refined.kept,
        consensus.candidates,
        width,
        consensus.hypotheses,
        window.half_width,
    )
    .map_err(NoEmitter::Geometry)?;
    if chance > config.significance {
        return Err(NoEmitter::NoConsensus);
    }
    if estimated_sigma > config.max_sigma {
        return Err(NoEmitter::TooNoisy);
    }
    // Correlation in time: the normalised residuals in input order.
    let fix = refined.fix;
    let norm = refined.scale;
    let tau = consistency::correlation_time(
        members.iter().map(|it| {
            let b = it.bearing();
            let bias = fix.bias.get(it.source()).copied().unwrap_or(0.0);
            wrap(b.theta - predicted(&fix.position, &b.vehicle) - bias) / (norm * b.sigma)
        }),
        refined.kept,
    );
    let effective = refined.kept as f32 / tau;
    let dof = effective - fix.parameters;
    // The stated sigmas against the residuals: scale^2 dof ~ chi-square(dof) if they hold.
    let p_value = if dof > 0.0 {
        stats::chi2_sf(refined.scale * refined.scale * dof, dof).unwrap_or(0.0)
    } else {
        1.0
    };
    let (scale_used, estimated, consistent) = match config.noise {
        NoiseModel::Estimated => (refined.scale, true, dof >= 1.0),
        NoiseModel::Known => {
            if dof >= 1.0 && p_value < config.consistency {
                (refined.scale.max(1.0), true, false)
            } else {
                (1.0, false, dof >= 1.0)
            }
        }
    };
    if estimated && !(dof >= 1.0) {
        return Err(NoEmitter::TooFew);
    }
    // The covariance at the noise used (a prior on the offsets makes it not simply
    // proportional to the scale): one more solve from the fix, which is already converged.
    let at_scale = if scale_used == refined.scale {
        fix
    } else {
        super::bias::ml_sources(
            members,
            priors,
            Start {
                position: fix.position,
                bias: fix.bias,
            },
            &Gaussian,
            BiasedOptions {
                scale: scale_used,
                ..config.solver
            },
        )
        .map_err(NoEmitter::Geometry)?
    };
    let info = at_scale.covariance;
    let crlb = libm::sqrtf(info[0][0] + info[1][1]);
    let widened = [
        [tau * info[0][0], tau * info[0][1]],
        [tau * info[1][0], tau * info[1][1]],
    ];
    let dof_for_scale = if estimated { Some(dof) } else { None };
    let k = consistency::ellipse_scale(config.confidence, dof_for_scale)
        .map_err(NoEmitter::Geometry)?;
    let stretched = far_side(&widened, &fix.position, members, k, config.ransac.max_range);
    // The Fisher ellipse is the likelihood's curvature at the fix; where the range is barely
    // observed the likelihood-ratio region reaches much farther: the ellipse is made to hold
    // it, and a region that runs out to the search's range is no fix.
    let fit = reach::Fit {
        fix: &at_scale,
        priors,
        scale: scale_used,
        inflation: tau,
    };
    let held = reach::reach(members, fit, &stretched, k, config.ransac.max_range)
        .map_err(NoEmitter::Geometry)?;
    if !held.bounded {
        return Err(NoEmitter::Geometry(Error::ParallelBearings));
    }
    let covariance = held.covariance;
    let k50 = consistency::ellipse_scale(0.5, dof_for_scale).map_err(NoEmitter::Geometry)?;
    let ellipse =
        Ellipse::with_scale(&covariance, k, config.confidence).map_err(NoEmitter::Geometry)?;
    let half = Ellipse::with_scale(&covariance, k50, 0.5).map_err(NoEmitter::Geometry)?;
    // CEP50 ~ 0.59 (s1 + s2) for a Gaussian; the same rule on the 50 % ellipse's axes, which
    // carry the F scaling: 0.59 (a1 + a2) / sqrt(chi2(2; 0.5)) scaled as the ellipse is.
    let cep50 = 0.59 * (half.major + half.minor)
        / libm::sqrtf(stats::chi2_2_quantile(0.5).unwrap_or(1.386));
    // The main DF unit: most bearings in the source.
    let mut per = [0u32; MAX_SOURCES];
    for it in members {
        if let Some(c) = per.get_mut(it.source()) {
            *c += 1;
        }
    }
    let main = (0..MAX_SOURCES).max_by_key(|s| per[*s]).unwrap_or(0);
    let (first, last) = (members.first(), members.last());
    let source = Source {
        freq_mhz: freq,
        position: fix.position,
        covariance,
        ellipse,
        ellipse_scale: k,
        cep50,
        stretch: held.stretch,
        crlb,
        bias: at_scale.bias[main],
        bias_sd: at_scale.bias_sd[main],
        bias_source: main as u8,
        sigma: scale_used * median,
        sigma_estimated: estimated,
        used: refined.kept,
        effective,
        dof,
        p_value,
        chance,
        consistent,
        index_span: [
            first.map(|i| i.index).unwrap_or(0),
            last.map(|i| i.index).unwrap_or(0),
        ],
        time_span: [
            first.map(|i| i.obs.time_s).unwrap_or(0.0),
            last.map(|i| i.obs.time_s).unwrap_or(0.0),
        ],
    };
    let all = [
        source.position[0],
        source.position[1],
        source.covariance[0][0],
        source.covariance[0][1],
        source.covariance[1][1],
        source.cep50,
        source.stretch,
        source.crlb,
        source.bias,
        source.bias_sd,
        source.sigma,
        source.effective,
        source.dof,
        source.p_value,
        source.chance,
    ];
    check_finite(&all).map_err(NoEmitter::Geometry)?;
    Ok((source, kept, (at_scale.bias, at_scale.bias_sd)))
}

/// The covariance stretched along the line of sight so its ellipse reaches the far end of the
/// range interval. Bearings measure inverse range (the angle a baseline subtends) nearly
/// linearly, so the range interval of a distant emitter is [r / (1 + k s), r / (1 - k s)]
/// (s the relative range sd, k the ellipse's sqrt scale), not r (1 +- k s): a fix that fell
/// short of a distant emitter, with its ellipse computed at the short range, would exclude it.
/// The far end is capped at `max_range`. Near emitters (k s small) are barely touched, and an
/// emitter within twice the drive's own spread of its centre (a drive around it) is left alone:
/// its range is no line-of-sight quantity.
fn far_side(
    cov: &[[f32; 2]; 2],
    position: &[f32; 2],
    members: &[Item],
    scale: f32,
    max_range: f32,
) -> [[f32; 2]; 2] {
    let n = members.len().max(1) as f32;
    let mut c = [0.0f32; 2];
    for it in members {
        c[0] += it.obs.bearing.vehicle[0] / n;
        c[1] += it.obs.bearing.vehicle[1] / n;
    }
    let mut spread = 0.0f32;
    for it in members {
        let v = it.obs.bearing.vehicle;
        spread += ((v[0] - c[0]) * (v[0] - c[0]) + (v[1] - c[1]) * (v[1] - c[1])) / n;
    }
    let spread = libm::sqrtf(spread);
    let (dx, dy) = (position[0] - c[0], position[1] - c[1]);
    let r = libm::hypotf(dx, dy);
    if !(r > 2.0 * spread) || !(r > 0.0) {
        return *cov;
    }
    let u = [dx / r, dy / r];
    let var =
        u[0] * (cov[0][0] * u[0] + cov[0][1] * u[1]) + u[1] * (cov[1][0] * u[0] + cov[1][1] * u[1]);
    if !(var > 0.0) {
        return *cov;
    }
    let k = libm::sqrtf(scale);
    let ks = k * libm::sqrtf(var) / r;
    let far = if ks < 1.0 {
        (r * ks / (1.0 - ks)).min(max_range)
    } else {
        max_range
    };
    let wanted = (far / k) * (far / k);
    let extra = (wanted - var).max(0.0);
    let out = [
        [
            cov[0][0] + extra * u[0] * u[0],
            cov[0][1] + extra * u[0] * u[1],
        ],
        [
            cov[1][0] + extra * u[1] * u[0],
            cov[1][1] + extra * u[1] * u[1],
        ],
    ];
    if out.iter().flatten().all(|v| v.is_finite()) {
        out
    } else {
        *cov
    }
}

fn median_sigma(items: &[Item]) -> f32 {
    let mut s = [0.0f32; robust::SCORE_SAMPLE];
    let stride = items.len().div_ceil(robust::SCORE_SAMPLE).max(1);
    let mut k = 0;
    for it in items.iter().step_by(stride) {
        if let Some(slot) = s.get_mut(k) {
            *slot = it.obs.bearing.sigma;
            k += 1;
        }
    }
    super::order::median(&mut s[..k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random;
    use core::f32::consts::PI;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    const DEG: f32 = PI / 180.0;
    const E: [f32; 2] = [0.0, 1500.0];

    /// `n` positions on a U round (0, 1500) (9 km: east, north, west).
    fn u(k: usize, n: usize) -> [f32; 2] {
        let s = 9000.0 * k as f32 / n as f32;
        if s < 3000.0 {
            [-1500.0 + s, 0.0]
        } else if s < 6000.0 {
            [1500.0, s - 3000.0]
        } else {
            [1500.0 - (s - 6000.0), 3000.0]
        }
    }

    fn obs(v: [f32; 2], target: [f32; 2], error: f32, k: usize) -> Observation {
        Observation::new(
            Bearing {
                vehicle: v,
                theta: wrap(predicted(&target, &v) + error),
                sigma: 2.0 * DEG,
            },
            k as f32,
        )
    }

    fn drive(rng: &mut XorShiftRng, bias: f32) -> [Observation; 240] {
        core::array::from_fn(|k| obs(u(k, 240), E, bias + 2.0 * DEG * random::normal(rng), k))
    }

    fn run<const N: usize>(o: &[Observation], config: &LocateConfig) -> Report<4, 4> {
        let mut work = Workspace::<N>::new();
        let mut rng = XorShiftRng::seed_from_u64(7);
        locate::<4, 4, _>(o, config, work.buffers(), &mut rng).unwrap()
    }

    #[test]
    fn a_clean_drive_with_an_offset_gives_one_consistent_emitter() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let o = drive(&mut rng, 3.0 * DEG);
        let r = run::<512>(&o, &LocateConfig::default());
        assert_eq!(r.emitters().len(), 1);
        assert_eq!(r.channels()[0].outcome, ChannelOutcome::Emitter(0));
        let e = r.emitters()[0];
        let err = libm::hypotf(e.position[0] - E[0], e.position[1] - E[1]);
        assert!(err < 4.0 * e.crlb, "{err} m: {e:?}");
        assert!(e.consistent && e.sigma_estimated && e.used >= 238);
        assert!(
            (e.bias - 3.0 * DEG).abs() < 4.0 * e.bias_sd,
            "{}",
            e.bias / DEG
        );
        assert!((e.sigma - 2.0 * DEG).abs() < 0.3 * DEG, "{}", e.sigma / DEG);
        assert_eq!(
            r.rejected.repeated + r.rejected.invalid + r.rejected.no_emitter,
            0
        );
        assert_eq!((e.index_span, e.time_span), ([0, 239], [0.0, 239.0]));
        // Many white residuals: F scaling close to chi-square's, no widening.
        assert!((e.ellipse_scale - 5.99).abs() < 0.2, "{}", e.ellipse_scale);
        assert!(e.effective > 200.0, "{}", e.effective);
        assert!(r.others().is_empty(), "{:?}", r.others());
    }

    #[test]
    fn a_capture_concatenated_with_itself_is_counted_once() {
        let mut rng = XorShiftRng::seed_from_u64(2);
        let once = drive(&mut rng, 0.0);
        let twice: [Observation; 480] = core::array::from_fn(|k| once[k % 240]);
        let config = LocateConfig::default();
        let a = run::<512>(&once, &config);
        let b = run::<512>(&twice, &config);
        assert_eq!(b.rejected.repeated, 240);
        assert_eq!(a.emitters()[0].position, b.emitters()[0].position);
        assert_eq!(a.emitters()[0].covariance, b.emitters()[0].covariance);
    }

    #[test]
    fn a_ghost_is_another_source_and_noise_is_no_emitter() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        let ghost = [900.0, 1800.0];
        let o: [Observation; 240] = core::array::from_fn(|k| {
            let t = if (60..120).contains(&k) { ghost } else { E };
            obs(u(k, 240), t, 2.0 * DEG * random::normal(&mut rng), k)
        });
        let r = run::<512>(&o, &LocateConfig::default());
        let e = r.emitters()[0];
        assert!(
            libm::hypotf(e.position[0] - E[0], e.position[1] - E[1]) < 40.0,
            "{e:?}"
        );
        let g = r.others().first().expect("the ghost");
        assert_eq!(g.why, OtherReason::Weaker);
        assert!(
            libm::hypotf(
                g.source.position[0] - ghost[0],
                g.source.position[1] - ghost[1]
            ) < 150.0,
            "{g:?}"
        );
        assert!((55..=62).contains(&g.source.used), "{}", g.source.used);
        assert!(
            g.source.index_span[0] >= 58 && g.source.index_span[1] <= 121,
            "{:?}",
            g.source.index_span
        );
        // Uniform bearings: no point gathers more than luck would.
        let noise: [Observation; 240] = core::array::from_fn(|k| {
            let mut x = o[k];
            x.bearing.theta = random::uniform_in(&mut rng, -PI, PI);
            x
        });
        let r = run::<512>(&noise, &LocateConfig::default());
        assert!(r.emitters().is_empty());
        assert!(matches!(
            r.channels()[0].outcome,
            ChannelOutcome::NoConsistentEmitter(_)
        ));
        assert_eq!(r.rejected.no_emitter, 240);
    }

    #[test]
    fn two_frequencies_give_two_emitters() {
        let mut rng = XorShiftRng::seed_from_u64(4);
        let b = [-700.0, 2200.0];
        let o: [Observation; 480] = core::array::from_fn(|k| {
            let (t, f) = if k % 2 == 0 { (E, 145.0) } else { (b, 146.52) };
            let mut x = obs(u(k / 2, 240), t, 2.0 * DEG * random::normal(&mut rng), k);
            x.freq_mhz = Some(f);
            x
        });
        let r = run::<512>(&o, &LocateConfig::default());
        assert_eq!(r.emitters().len(), 2, "{:?}", r.channels());
        for (e, t) in r.emitters().iter().zip([E, b]) {
            assert!(
                libm::hypotf(e.position[0] - t[0], e.position[1] - t[1]) < 40.0,
                "{e:?}"
            );
            assert!(e.consistent);
        }
        assert_eq!(
            r.emitters()[1]
                .freq_mhz
                .map(|f| libm::roundf(f * 100.0) as i32),
            Some(14652)
        );
    }

    #[test]
    fn bad_observations_are_counted_by_reason() {
        let mut rng = XorShiftRng::seed_from_u64(5);
        let mut o = drive(&mut rng, 0.0);
        o[3].bearing.theta = f32::NAN;
        o[4].bearing.sigma = 0.0;
        o[5].source = 9;
        o[6].freq_mhz = Some(-1.0);
        o[7].time_s = 1.5; // older than o[6]: time went backwards
        let r = run::<200>(&o, &LocateConfig::default());
        let rej = r.rejected;
        assert_eq!(
            (rej.invalid, rej.unknown_source, rej.time_backwards),
            (3, 1, 1)
        );
        // 236 usable, 200 fit: the rest is over capacity.
        assert_eq!(rej.over_capacity, 36);
        assert_eq!(r.emitters().len(), 1);
        let bad = LocateConfig {
            confidence: 1.0,
            ..LocateConfig::default()
        };
        let mut work = Workspace::<8>::new();
        let mut rng = XorShiftRng::seed_from_u64(0);
        assert_eq!(
            locate::<1, 1, _>(&o, &bad, work.buffers(), &mut rng).map(|_| ()),
            Err(Error::OutOfRange)
        );
    }

    #[test]
    fn a_unit_noisier_than_it_claims_is_inconsistent_when_trusted() {
        let mut rng = XorShiftRng::seed_from_u64(6);
        // 4 degree noise, the unit claims 2.
        let o: [Observation; 240] =
            core::array::from_fn(|k| obs(u(k, 240), E, 4.0 * DEG * random::normal(&mut rng), k));
        let known = LocateConfig {
            noise: NoiseModel::Known,
            ..LocateConfig::default()
        };
        let r = run::<512>(&o, &known);
        let e = r.emitters()[0];
        assert!(!e.consistent && e.sigma_estimated, "{e:?}");
        assert!((e.sigma - 4.0 * DEG).abs() < 0.6 * DEG, "{}", e.sigma / DEG);
        assert!(e.p_value < 1e-3);
        // A unit that tells the truth is trusted: chi-square scale, its own sigma.
        let honest: [Observation; 240] =
            core::array::from_fn(|k| obs(u(k, 240), E, 2.0 * DEG * random::normal(&mut rng), k));
        let r = run::<512>(&honest, &known);
        let e = r.emitters()[0];
        assert!(e.consistent && !e.sigma_estimated, "{e:?}");
        assert!((e.ellipse_scale - 5.991).abs() < 1e-3 && e.sigma == 2.0 * DEG);
    }
}
