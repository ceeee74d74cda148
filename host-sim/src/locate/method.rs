//! `locate` by any other method of the registry: one emitter from all bearings, the noise
//! estimated from the residuals unless given, no offset.

use crate::estimate::noise::{claim, with_estimated_noise};
use crate::estimate::options::{LocateOptions, SEEDS_JITTER_M2};
use crate::estimate::{locate_bearings, pool};
use crate::inputs::capture::Decoded;
use crate::locate::Parts;
use crate::locate::explain::explain;
use crate::locate::report::{ChannelSummary, Drawn, EllipseReport, SourceReport, geodetic};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::Bearing;
use foxhunt_core::fix::consistency::check_cloud;
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::Ellipse;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::collections::BTreeMap;

pub(crate) fn located_by(
    d: &Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
    rejected: &mut BTreeMap<&'static str, u32>,
) -> Result<Parts, String> {
    let mut rng = XorShiftRng::seed_from_u64(o.seed);
    let (s, sigma, estimated) = match o.sigma_deg {
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
    };
    let bearings = d.bearings_with_sigma(sigma);
    let mut s = s.map_err(|e| explain(e, &bearings))?;
    if !estimated {
        // With the noise given the claim is chi-square's, still no tighter than the bound.
        claim(&mut s, &bearings).map_err(|e| explain(e, &bearings))?;
    }
    // Chi-square with the stated noise, 2 F(2, dof) with an estimated one (the fix says which).
    let ellipse = Ellipse::with_scale(&s.covariance, s.ellipse_scale, 0.95)
        .map_err(|e| explain(e, &bearings))?;
    let cep = s.cep50;
    let bound = crlb(&s.position, &bearings).map_err(|e| explain(e, &bearings))?;
    rejected.insert("outlier", s.outliers);
    // A particle cloud far tighter than the bearings allow is no estimate of the uncertainty.
    let consistent = (!s.cloud.is_empty())
        .then(|| check_cloud_points(&s.cloud, &bearings))
        .flatten();
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
    };
    let channel = ChannelSummary {
        freq_mhz: freq,
        bearings: bearings.len() as u32,
        outcome: "emitter".into(),
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
