//! One source from a set of bearings, step by step: a consensus luck could not have lined up,
//! its robust refinement, significance again on the refined set, the noise (its scale and the
//! residuals' correlation in time), the fit at the noise used, and the confidence region
//! ([`super::region`]).

use super::super::bias::{
    self, BiasPrior, BiasedFix, BiasedOptions, CONTRADICTED_Z, KNOWN_SD, OffsetCircle, Sighting,
    StationSlot,
};
use super::super::consistency;
use super::super::noise::median_sigma;
use super::super::robust::{self, Consensus, OffsetWindow, RefineOptions, RobustFix, TRIM_CUT};
use super::region::{Confidence, Held, Wedge, confidence_region};
use super::{
    ChannelFreq, Item, LocateConfig, NoEmitter, NoiseModel, OffsetBeyond, OffsetCheck, Region,
    Source,
};
use crate::error::{Error, check_finite};
use crate::model::bearing::{predicted, wrap};
use crate::stats;
use rand_core::Rng;

/// What a set of bearings agreeing on a source came to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Found {
    /// A fix, and how many bearings it used.
    Source(Source, usize),
    /// The range is open: the line of bearing and range interval, and the bearings used.
    Region(Region, usize),
}

/// One source from `set`: the consensus, its refinement and its honest statistics, the main
/// station's offset checked against its prior ([`past_prior`] where the data contradict it).
/// On success the source's bearings are the first `kept` of `scratch`, and each station's
/// offset in the fit is in its row of `stations`.
pub(super) fn find_source<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    rng: &mut R,
) -> Result<Found, NoEmitter> {
    let window = OffsetWindow::from_stations(set, stations);
    let (mut source, kept) = match attempt(set, scratch, stations, freq, config, window, rng) {
        Ok(Found::Source(source, kept)) => (source, kept),
        Ok(region @ Found::Region(..)) => return Ok(region),
        Err(why @ (NoEmitter::NoConsensus | NoEmitter::TooNoisy | NoEmitter::Geometry(_)))
            if window.half_width > 0.0 =>
        {
            return round_the_circle(set, scratch, stations, freq, config, rng, why);
        }
        Err(why) => return Err(why),
    };
    let main = usize::from(source.bias_station);
    let prior = stations
        .get(main)
        .map_or(BiasPrior::calibrated(0.0), StationSlot::prior_in_force);
    let tau = correlation(&source);
    let z = prior.surprise_correlated(source.bias, source.bias_sd, tau);
    source.offset_check = OffsetCheck {
        z,
        unmeasured: unmeasured(&source),
        ..OffsetCheck::default()
    };
    if z.abs() <= CONTRADICTED_Z {
        return Ok(Found::Source(source, kept));
    }
    past_prior(
        set,
        scratch,
        stations,
        freq,
        config,
        rng,
        (&source, kept),
        prior,
    )
}

/// Whether the data allow the main station's offset a rival far from `source`'s, its profile
/// round the whole circle on the source's bearings `members` ([`OffsetCheck::ambiguous`]).
/// Asked of a fix inside a free prior, once it is known to be a fix (a source that turns out
/// to be a moving emitter's, or a span's in the search for one, needs no such check: two dozen
/// solves each). The table is left as it came.
pub(super) fn check_ambiguity(
    source: &mut Source,
    members: &[Item],
    stations: &mut [StationSlot],
    config: &LocateConfig,
) -> Result<(), NoEmitter> {
    let main = usize::from(source.bias_station);
    let prior = stations
        .get(main)
        .map_or(BiasPrior::calibrated(0.0), StationSlot::prior_in_force);
    if !(source.offset_check.z.abs() <= CONTRADICTED_Z && prior.is_free()) {
        return Ok(());
    }
    // Each step's deviance is needed to well within the rival's gap, not its position to the
    // fix's millimetre: a step stops at a fiftieth of the fix's smallest sd, where the
    // deviance it leaves is under 0.0004 (the fix's own solve keeps the configured tolerance).
    let minor = crate::linalg::eigen2(&source.covariance).map_or(0.0, |(a, b, _)| a.min(b));
    let solver = BiasedOptions {
        tolerance_m: config
            .solver
            .tolerance_m
            .max(CIRCLE_TOLERANCE_SD * libm::sqrtf(minor.max(0.0))),
        ..solver_at(source, members, config)
    };
    // Deviances of correlated bearings count tau times what they hold.
    let gap = AMBIGUOUS_DEVIANCE * correlation(source);
    // Other stations that pin the position leave no rival to walk to (a network's solve).
    if bias::no_rival(
        members,
        stations,
        main,
        source.position,
        solver,
        RIVAL_APART,
        gap,
    ) {
        return Ok(());
    }
    let circle = bias::offset_circle(members, stations, main, source.position, solver)
        .map_err(NoEmitter::Geometry)?;
    source.offset_check.ambiguous = circle.rival(source.bias, RIVAL_APART, gap);
    Ok(())
}

/// How closely each step of the ambiguity check's circle is solved, in the fix's smallest sd.
const CIRCLE_TOLERANCE_SD: f32 = 0.02;

/// Past the prior: the data put the main station's offset `z` of its predicted sds from the
/// prior's mean (`first`: that fit and its bearings' count). Its profile round the whole
/// circle on the first fit's bearings finds where the offset lies without the prior. Two
/// minima the data do not tell apart (a gap under [`AMBIGUOUS_DEVIANCE`]) are reported, not
/// picked from; one is the start of the whole search again with the station's prior relaxed
/// (no prior; the consensus' offsets searched about that minimum), whose ellipse then carries
/// the offset's uncertainty. A relaxed fit that fails the checks, or leaves the offset
/// unmeasured (sd above [`OBSERVED_SD`]: the drive did not turn enough to show it), is no fix
/// but [`NoEmitter::OffsetBeyondPrior`].
#[allow(clippy::too_many_arguments)]
fn past_prior<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    rng: &mut R,
    first: (&Source, usize),
    prior: BiasPrior,
) -> Result<Found, NoEmitter> {
    let (source, kept) = first;
    let main = usize::from(source.bias_station);
    let members = scratch.get(..kept).ok_or(NoEmitter::TooFew)?;
    let options = solver_at(source, members, config);
    let circle = bias::offset_circle(members, stations, main, source.position, options)
        .map_err(NoEmitter::Geometry)?;
    let offset = OffsetCircle::offset(circle.best);
    let mut beyond = OffsetBeyond {
        station: main as u16,
        offset,
        second: None,
        prior,
        z: source.offset_check.z,
    };
    // Deviances of correlated bearings count tau times what they hold.
    if circle.second_gap() < AMBIGUOUS_DEVIANCE * correlation(source) {
        beyond.second = circle.second.map(OffsetCircle::offset);
        return Err(NoEmitter::OffsetBeyondPrior(beyond));
    }
    let relaxed = BiasPrior {
        mean: offset,
        sd: f32::INFINITY,
    };
    if let Some(s) = stations.get_mut(main) {
        s.set_prior_in_force(relaxed);
    }
    let window = OffsetWindow::from_prior(relaxed);
    match attempt(set, scratch, stations, freq, config, window, rng) {
        Ok(Found::Source(mut again, kept))
            if again.bias_sd * libm::sqrtf(correlation(&again)) <= OBSERVED_SD =>
        {
            again.offset_check = OffsetCheck {
                z: source.offset_check.z,
                relaxed: true,
                ambiguous: false,
                unmeasured: unmeasured(&again),
            };
            Ok(Found::Source(again, kept))
        }
        Ok(Found::Source(again, _)) => {
            beyond.offset = again.bias;
            Err(NoEmitter::OffsetBeyondPrior(beyond))
        }
        // With the offset free the range opened: the drive does not show the offset.
        Ok(Found::Region(..)) | Err(_) => Err(NoEmitter::OffsetBeyondPrior(beyond)),
    }
}

/// No source with the offsets inside their priors' window (`why`: no consensus, too noisy, or
/// no fix the geometry allows): is there one with an offset far outside it (a unit turned 90
/// degrees agrees with nothing near 0, and one turned 180 puts the emitter behind it)? The
/// search again with every free station's prior dropped and the consensus' offsets searched
/// round the whole circle ([`CIRCLE_WINDOWS`] windows, the chance test's significance shared
/// among them; the window whose source keeps most bearings wins). A source whose main offset
/// lies within [`CONTRADICTED_Z`] predicted sds of its prior changes nothing (`why` stands);
/// one beyond goes on to [`past_prior`] as a fix with the prior would.
fn round_the_circle<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    rng: &mut R,
    why: NoEmitter,
) -> Result<Found, NoEmitter> {
    let restore = |stations: &mut [StationSlot]| {
        for s in stations.iter_mut() {
            s.reset();
        }
    };
    for s in stations.iter_mut() {
        let p = s.prior_in_force();
        if p.is_free() {
            s.set_prior_in_force(BiasPrior {
                mean: p.mean,
                sd: f32::INFINITY,
            });
        }
    }
    // RANSAC crosses pairs with the window's centre removed, so a search centred at 0 never
    // crosses bearings turned 90 degrees: the circle in windows, each window's chance test at
    // the significance shared out among them (Bonferroni).
    let shared = LocateConfig {
        significance: config.significance / CIRCLE_WINDOWS as f32,
        ..*config
    };
    let width = core::f32::consts::PI / CIRCLE_WINDOWS as f32;
    let window = |k: usize| OffsetWindow {
        centre: wrap(width * (2 * k + 1) as f32),
        half_width: width,
    };
    let surprise = |stations: &[StationSlot], found: &Source| {
        let main = usize::from(found.bias_station);
        let prior = stations
            .get(main)
            .map_or(BiasPrior::calibrated(0.0), |s| s.prior());
        let sd = found.bias_sd * libm::sqrtf(correlation(found));
        (prior, prior.surprise_unaided(found.bias, sd))
    };
    let mut best: Option<(usize, u32)> = None;
    for k in 0..CIRCLE_WINDOWS {
        if let Ok(Found::Source(found, _)) =
            attempt(set, scratch, stations, freq, &shared, window(k), rng)
        {
            let beyond = surprise(stations, &found).1.abs() > CONTRADICTED_Z;
            if beyond && best.is_none_or(|(_, used)| found.used > used) {
                best = Some((k, found.used));
            }
        }
    }
    let found = best.map(|(k, _)| attempt(set, scratch, stations, freq, &shared, window(k), rng));
    let Some(Ok(Found::Source(mut source, kept))) = found else {
        restore(stations);
        return Err(why);
    };
    let (prior, z) = surprise(stations, &source);
    if !(z.abs() > CONTRADICTED_Z) {
        restore(stations);
        return Err(why);
    }
    // The others back to their priors: only the main station's is past it.
    let main = usize::from(source.bias_station);
    for (i, s) in stations.iter_mut().enumerate() {
        if i != main {
            s.set_prior_in_force(s.prior());
        }
    }
    source.offset_check = OffsetCheck {
        z,
        ..OffsetCheck::default()
    };
    past_prior(
        set,
        scratch,
        stations,
        freq,
        config,
        rng,
        (&source, kept),
        prior,
    )
}

/// Windows the circle is searched in when nothing agrees inside the prior's (60 degrees each).
pub const CIRCLE_WINDOWS: usize = 6;

/// The solver at the noise `source` used (its sigma over its `members`' median).
fn solver_at(source: &Source, members: &[Item], config: &LocateConfig) -> BiasedOptions {
    BiasedOptions {
        scale: noise_scale(source, members),
        ..config.solver
    }
}

/// The correlation time of `source`'s residuals, in bearings (N / N_eff, at least 1): its
/// likelihood counts its bearings this many times over, so its offset's sd and its deviances
/// are read at that rate.
fn correlation(source: &Source) -> f32 {
    if source.effective > 0.0 {
        (source.used as f32 / source.effective).max(1.0)
    } else {
        1.0
    }
}

/// Whether `source`'s bearings left its main station's offset unmeasured: its sd, read at
/// their correlation, above [`KNOWN_SD`].
fn unmeasured(source: &Source) -> bool {
    !(source.bias_sd * libm::sqrtf(correlation(source)) <= KNOWN_SD)
}

/// The noise scale `source` used: its sigma over its bearings' (`members`) median sigma.
pub(super) fn noise_scale(source: &Source, members: &[Item]) -> f32 {
    let median = median_sigma(members);
    if median > 0.0 {
        source.sigma / median
    } else {
        1.0
    }
}

/// A minimum of the offset's profile this far (radians: 30 degrees, two of its steps) from a
/// fit's offset, and within [`AMBIGUOUS_DEVIANCE`] of the lowest, is a rival the data allow:
/// the fit stands on the prior alone ([`OffsetCheck::ambiguous`]).
pub const RIVAL_APART: f32 = 30.0 * core::f32::consts::PI / 180.0;

/// Two minima of an offset's profile round the circle closer than this in deviance (a
/// likelihood ratio of 1 in 90) are both possible: the data do not choose between them.
pub const AMBIGUOUS_DEVIANCE: f32 = 9.0;

/// A relaxed fit whose offset sd exceeds this (radians: 6 degrees, the default prior's) did not
/// measure the offset: relaxing a prior the data contradict is honest only where the data pin
/// the offset at least as well as the prior claimed to. Wider, the fix rests on an offset the
/// drive cannot show, and its linearised ellipse misses: at 15 degrees, on a straight road with
/// the unit 30-105 degrees off, a fifth to half of such fixes missed the truth beyond 3 sigma.
pub const OBSERVED_SD: f32 = 6.0 * core::f32::consts::PI / 180.0;

/// One pass of the search for a source in `set`, the consensus' common offsets searched in
/// `window`.
fn attempt<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    window: OffsetWindow,
    rng: &mut R,
) -> Result<Found, NoEmitter> {
    let consensus = significant_consensus(set, window, config, rng)?;
    let refined = refine(set, scratch, stations, &consensus, config)?;
    let kept = refined.kept as usize;
    let members = scratch.get(..kept).ok_or(NoEmitter::TooFew)?;
    let median = median_sigma(members);
    let estimated_sigma = refined.scale * median;
    // Agreement judged at no less than a stated noise: luck in the scatter is no evidence.
    let judged_sigma = if config.noise_stated {
        estimated_sigma.max(median)
    } else {
        estimated_sigma
    };
    let chance = refined_chance(&refined, &consensus, window, judged_sigma)?;
    if chance > config.significance {
        return Err(NoEmitter::NoConsensus);
    }
    if estimated_sigma > config.max_sigma {
        return Err(NoEmitter::TooNoisy);
    }
    let noise = noise_used(members, stations, &refined, median, config)?;
    let at_scale = at_noise(members, stations, &refined, noise.scale, config.solver)?;
    let region = match confidence_region(
        members,
        stations,
        &at_scale,
        &refined.fix.position,
        noise.for_region(),
        config,
    )? {
        Held::Bounded(c) => c,
        Held::Open(w) => {
            let noise_used = (noise.sigma, noise.estimated, noise.effective);
            let region = as_region(members, freq, &w, noise_used, config.confidence);
            return Ok(Found::Region(region, kept));
        }
    };
    let source = as_reported(members, freq, &refined, &at_scale, &noise, &region, chance);
    check_finite(&[
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
    ])
    .map_err(NoEmitter::Geometry)?;
    Ok(Found::Source(source, kept))
}

/// `members`' open region `w` as reported, at the noise `sigma` (estimated or given) with
/// `effective` independent bearings.
pub(super) fn as_region(
    members: &[Item],
    freq: ChannelFreq,
    w: &Wedge,
    (sigma, estimated, effective): (f32, bool, f32),
    confidence: f32,
) -> Region {
    let (first, last) = (members.first(), members.last());
    Region {
        freq_mhz: freq.mean,
        channel_lowest_mhz: freq.lowest,
        apex: w.apex,
        theta: w.theta,
        half_width: w.half_width,
        min_range: w.min_range,
        max_range: w.max_range,
        parallel: w.parallel,
        confidence,
        sigma,
        sigma_estimated: estimated,
        used: members.len() as u32,
        effective,
        index_span: [
            first.map(|i| i.index).unwrap_or(0),
            last.map(|i| i.index).unwrap_or(0),
        ],
        time_span: [
            first.map(|i| i.obs.time_s).unwrap_or(0.0),
            last.map(|i| i.obs.time_s).unwrap_or(0.0),
        ],
    }
}

/// RANSAC's best point, if luck is unlikely to have lined up as many bearings on it.
fn significant_consensus<R: Rng + ?Sized>(
    set: &[Item],
    window: OffsetWindow,
    config: &LocateConfig,
    rng: &mut R,
) -> Result<Consensus, NoEmitter> {
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
    Ok(consensus)
}

/// The consensus refined (Tukey, then trimmed ML with the noise scale estimated); its bearings
/// the first `kept` of `scratch`.
fn refine(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    consensus: &Consensus,
    config: &LocateConfig,
) -> Result<RobustFix, NoEmitter> {
    robust::refine(
        set,
        scratch,
        stations,
        consensus,
        RefineOptions {
            estimate_scale: true,
            solver: config.solver,
        },
    )
    .map_err(|e| match e {
        Error::TooFewMeasurements => NoEmitter::TooFew,
        e => NoEmitter::Geometry(e),
    })
}

/// Significance again, with the refined set and its own agreement width: how likely luck
/// lines up as many bearings within the trimming cut (at the noise `estimated_sigma`) of a
/// point.
fn refined_chance(
    refined: &RobustFix,
    consensus: &Consensus,
    window: OffsetWindow,
    estimated_sigma: f32,
) -> Result<f32, NoEmitter> {
    let kept = refined.kept as usize;
    let cut = robust::trim_cut(refined.kept, kept as f32 - refined.fix.parameters);
    let width = (cut.min(2.0 * TRIM_CUT) * estimated_sigma).max(consensus.threshold);
    robust::chance(
        refined.kept,
        consensus.candidates,
        width,
        consensus.hypotheses,
        window.half_width,
    )
    .map_err(NoEmitter::Geometry)
}

/// What the residuals say about the noise, and the noise the statistics use.
struct Noise {
    /// Correlation time of the residuals in input order, in bearings (N / N_eff).
    tau: f32,
    /// Effective number of bearings, N / tau.
    effective: f32,
    /// Residual degrees of freedom: N_eff minus the effective unknowns.
    dof: f32,
    /// P(chi-square > observed) of the residuals against the bearings' stated sigmas.
    p_value: f32,
    /// The noise scale used: every bearing's sigma times this.
    scale: f32,
    /// Whether `scale` was estimated from the residuals.
    estimated: bool,
    /// Whether the residuals agree with the noise model.
    consistent: bool,
    /// The bearing noise used, radians: the median bearing sigma times `scale`.
    sigma: f32,
}

impl Noise {
    /// What the confidence region needs of it.
    fn for_region(&self) -> super::region::Noise {
        super::region::Noise {
            scale: self.scale,
            inflation: self.tau,
            dof: if self.estimated { Some(self.dof) } else { None },
        }
    }
}

/// The residuals' correlation in time and chi-square, and the noise scale the configured noise
/// model then uses (`median`: the members' median sigma). Too few effective bearings to
/// estimate the noise is [`NoEmitter::TooFew`].
fn noise_used(
    members: &[Item],
    stations: &[StationSlot],
    refined: &RobustFix,
    median: f32,
    config: &LocateConfig,
) -> Result<Noise, NoEmitter> {
    // Correlation in time: the normalised residuals in input order.
    let fix = refined.fix;
    let norm = refined.scale;
    let tau = consistency::correlation_time(
        members.iter().map(|it| {
            let b = it.bearing();
            let bias = stations
                .get(it.station())
                .map_or(0.0, |s| s.correction(it.relative()));
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
    let (scale, estimated, consistent) = match config.noise {
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
    Ok(Noise {
        tau,
        effective,
        dof,
        p_value,
        scale,
        estimated,
        consistent,
        sigma: scale * median,
    })
}

/// The fit at the noise used. A prior on the offsets makes the covariance not simply
/// proportional to the scale: one more solve from the fix, which is already converged.
fn at_noise(
    members: &[Item],
    stations: &mut [StationSlot],
    refined: &RobustFix,
    scale: f32,
    solver: BiasedOptions,
) -> Result<BiasedFix, NoEmitter> {
    if scale == refined.scale {
        return Ok(refined.fix);
    }
    bias::refit(members, stations, &refined.fix, scale, solver).map_err(NoEmitter::Geometry)
}

/// The source as reported.
fn as_reported(
    members: &[Item],
    freq: ChannelFreq,
    refined: &RobustFix,
    at_scale: &BiasedFix,
    noise: &Noise,
    region: &Confidence,
    chance: f32,
) -> Source {
    let (first, last) = (members.first(), members.last());
    Source {
        freq_mhz: freq.mean,
        channel_lowest_mhz: freq.lowest,
        position: refined.fix.position,
        covariance: region.covariance,
        ellipse: region.ellipse,
        ellipse_scale: region.scale,
        cep50: region.cep50,
        stretch: region.stretch,
        crlb: region.crlb,
        bias: at_scale.bias,
        bias_sd: at_scale.bias_sd,
        bias_station: at_scale.main,
        offsets: [0; 2],
        sigma: noise.sigma,
        sigma_estimated: noise.estimated,
        used: refined.kept,
        effective: noise.effective,
        dof: noise.dof,
        p_value: noise.p_value,
        chance,
        consistent: noise.consistent,
        offset_check: OffsetCheck::default(),
        index_span: [
            first.map(|i| i.index).unwrap_or(0),
            last.map(|i| i.index).unwrap_or(0),
        ],
        time_span: [
            first.map(|i| i.obs.time_s).unwrap_or(0.0),
            last.map(|i| i.obs.time_s).unwrap_or(0.0),
        ],
        motion_p: None,
    }
}
