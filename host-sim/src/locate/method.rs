//! `locate` by any other method of the registry: one emitter from all bearings, the noise
//! estimated from the residuals unless given, no offset.

use crate::estimate::noise::{claim, with_estimated_noise};
use crate::estimate::options::{LocateOptions, SEEDS_JITTER_M2};
use crate::estimate::window::unit_fix;
use crate::estimate::{locate_bearings, pool};
use crate::inputs::capture::Decoded;
use crate::locate::Parts;
use crate::locate::explain::explain;
use crate::locate::report::{ChannelSummary, Drawn, EllipseReport, SourceReport, geodetic};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::consistency::check_cloud;
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::{Bearing, Method};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::collections::BTreeMap;

/// The most firefly moves fa-pf is given (particles squared times bearings): each step moves
/// every particle toward every brighter one, so its time grows with the square of the
/// particles (500 on 60 bearings, 1.5e7 moves: 5.5 s on one core; 1000: over 20 s).
pub const FIREFLY_MOVES: f64 = 1.0e7;

/// Refuse a run of fa-pf that would take minutes, saying how many particles fit.
fn within_budget(o: &LocateOptions, bearings: usize) -> Result<(), String> {
    let n = o.particles as f64;
    if o.method != Method::FaPf || n * n * bearings as f64 <= FIREFLY_MOVES {
        return Ok(());
    }
    let fits = foxhunt_core::PARTICLE_COUNTS
        .iter()
        .rev()
        .find(|&&k| (k * k) as f64 * bearings as f64 <= FIREFLY_MOVES)
        .map_or("none fits".to_string(), |k| {
            format!("--particles {k} or fewer fit")
        });
    Err(format!(
        "fa-pf moves every particle toward every brighter one at each bearing: {} particles on \
         {bearings} bearings are {:.0e} moves, more than the {FIREFLY_MOVES:.0e} it is given \
         (its time grows with the square of the particles; {fits}, or use fa-pf-imp)",
        o.particles,
        n * n * bearings as f64
    ))
}

/// Locate with a method other than the field pipeline. Not inlined: its methods'
/// fixed-capacity state is megabytes of stack, which the default method should not reserve
/// in `locate_answer`'s frame (inlined, 1.9 MB: a 2 MiB thread's whole stack).
#[inline(never)]
pub(crate) fn located_by(
    d: &Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
    rejected: &mut BTreeMap<&'static str, u32>,
) -> Result<Parts, String> {
    within_budget(o, d.observations.len())?;
    let mut rng = XorShiftRng::seed_from_u64(o.seed);
    // The unit's own ellipse, when the unit's method made the fix.
    let mut unit_ellipse = None;
    let (s, sigma, estimated) = if o.method == Method::Unit {
        // The unit's computation: the bearings at their capture times, its own noise model.
        let times: Vec<i64> = d
            .observations
            .iter()
            .map(|x| (f64::from(x.time_s) * 1000.0).round() as i64)
            .collect();
        let bearings = d.bearings_with_sigma(1.0);
        match unit_fix(&bearings, &times, o.sigma_deg.map(f32::to_radians)) {
            Ok(u) => {
                unit_ellipse = Some(u.ellipse);
                let estimated = u.fix.dof.is_some();
                (Ok(u.fix), u.noise.sigma, estimated)
            }
            Err(e) => (Err(e), o.sigma_deg.unwrap_or(2.0).to_radians(), true),
        }
    } else {
        match o.sigma_deg {
            Some(deg) => {
                let bearings = d.bearings_with_sigma(deg.to_radians());
                let fix = pool().install(|| {
                    locate_bearings(
                        o.method,
                        o.particles,
                        SEEDS_JITTER_M2,
                        &bearings,
                        true,
                        &mut rng,
                    )
                });
                (fix, deg.to_radians(), false)
            }
            None => {
                let bearings = d.bearings_with_sigma(1.0f32.to_radians());
                let r = pool().install(|| {
                    with_estimated_noise(
                        o.method,
                        o.particles,
                        SEEDS_JITTER_M2,
                        &bearings,
                        true,
                        &mut rng,
                    )
                });
                match r {
                    Ok((fix, noise)) => (Ok(fix), noise.sigma, true),
                    Err(e) => (Err(e), 1.0f32.to_radians(), true),
                }
            }
        }
    };
    let bearings = d.bearings_with_sigma(sigma);
    let mut s = s.map_err(|e| explain(e, &bearings))?;
    if !estimated && o.method != Method::Unit {
        // With the noise given the claim is chi-square's, still no tighter than the bound.
        claim(o.method, &mut s, &bearings).map_err(|e| explain(e, &bearings))?;
    }
    // Chi-square with the stated noise, 2 F(2, dof) with an estimated one (the fix says which).
    let ellipse = match unit_ellipse {
        Some(e) => e,
        None => Ellipse::with_scale(&s.covariance, s.ellipse_scale, 0.95)
            .map_err(|e| explain(e, &bearings))?,
    };
    let cep = s.cep50;
    let bound = crlb(&s.position, &bearings).map_err(|e| explain(e, &bearings))?;
    rejected.insert("outlier", s.outliers);
    // A particle cloud far tighter than the bearings allow is no estimate of the uncertainty.
    let consistent = (!s.cloud.is_empty())
        .then(|| check_cloud_points(&s.cloud, &bearings))
        .flatten();
    if consistent == Some(false) {
        // A fix whose own check says its ellipse is far tighter than the bearings allow is no
        // fix: reported, it would be a confident wrong answer.
        return Err(format!(
            "{}'s particles collapsed: its 95 % ellipse ({:.0} m by {:.0} m) is far tighter than \
             {} bearings with {:.1} degrees of noise allow, so neither the fix nor its \
             uncertainty can be trusted; ml-robust checks its fit",
            o.method.name(),
            ellipse.major,
            ellipse.minor,
            bearings.len(),
            sigma.to_degrees()
        ));
    }
    let g = geodetic(frame, s.position);
    let freq = d.observations.first().and_then(|x| x.freq_mhz);
    let report = SourceReport {
        freq_mhz: freq,
        lat: g.lat,
        lon: g.lon,
        east_m: s.position[0],
        north_m: s.position[1],
        ellipse: EllipseReport::from(&ellipse),
        cep50_m: cep,
        crlb_m: bound.rmse,
        bias_deg: None,
        bias_sd_deg: None,
        sigma_deg: sigma.to_degrees(),
        sigma_estimated: estimated,
        sigma_dof: s.dof,
        used: bearings.len() as u32,
        effective: None,
        consistent,
        time_span_s: None,
        why: None,
        offset_measured: None,
        offset_check: None,
    };
    let channel = ChannelSummary {
        freq_mhz: freq,
        bearings: bearings.len() as u32,
        outcome: "emitter".into(),
        region: None,
        reason: None,
        motion: None,
    };
    let drawn = vec![Drawn {
        position: s.position,
        ellipse,
        other: false,
    }];
    Ok((
        vec![report],
        Vec::new(),
        vec![channel],
        drawn,
        s.cloud,
        Vec::new(),
    ))
}

/// Whether a particle cloud is as wide as the bearings allow (`Some(false)`: collapsed).
fn check_cloud_points(cloud: &[[f32; 2]], bearings: &[Bearing]) -> Option<bool> {
    foxhunt_core::with_particles!(cloud.len(), N => {
        let mut set = Box::new(foxhunt_core::ParticleSet::<N, 2>::new());
        for (s, p) in set.states.iter_mut().zip(cloud) {
            *s = *p;
        }
        check_cloud(&set, bearings).map(|c| !c.collapsed)
    })
    .ok()
}
