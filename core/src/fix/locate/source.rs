//! One source from a set of bearings, step by step: a consensus luck could not have lined up,
//! its robust refinement, significance again on the refined set, the noise (its scale and the
//! residuals' correlation in time), the fit at the noise used, and the confidence region
//! ([`super::region`]).

use super::super::bias::{self, BiasedFix, BiasedOptions, Sighting, StationSlot};
use super::super::consistency;
use super::super::noise::median_sigma;
use super::super::robust::{self, Consensus, OffsetWindow, RefineOptions, RobustFix, TRIM_CUT};
use super::region::{Confidence, Held, Wedge, confidence_region};
use super::{ChannelFreq, Item, LocateConfig, NoEmitter, NoiseModel, Region, Source};
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

/// One source from `set`: the consensus, its refinement and its honest statistics. On success
/// the source's bearings are the first `kept` of `scratch`, and each station's offset in the
/// fit is in its row of `stations`.
pub(super) fn find_source<R: Rng + ?Sized>(
    set: &[Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    rng: &mut R,
) -> Result<Found, NoEmitter> {
    let window = OffsetWindow::from_stations(set, stations);
    let consensus = significant_consensus(set, window, config, rng)?;
    let refined = refine(set, scratch, stations, &consensus, config)?;
    let kept = refined.kept as usize;
    let members = scratch.get(..kept).ok_or(NoEmitter::TooFew)?;
    let median = median_sigma(members);
    let estimated_sigma = refined.scale * median;
    let chance = refined_chance(&refined, &consensus, window, estimated_sigma)?;
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
            let region = as_region(members, freq, &w, &noise, config.confidence);
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

/// The open region as reported.
fn as_region(
    members: &[Item],
    freq: ChannelFreq,
    w: &Wedge,
    noise: &Noise,
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
        sigma: noise.sigma,
        sigma_estimated: noise.estimated,
        used: members.len() as u32,
        effective: noise.effective,
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
/// lines up as many bearings within the trimming cut (at the estimated noise) of a point.
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
            let bias = stations.get(it.station()).map_or(0.0, |s| s.offset().0);
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
