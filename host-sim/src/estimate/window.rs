//! `--method unit`: the DF unit's windowed fix ([`foxhunt_core::fix::window`]) run on the
//! host over a capture's bearings, as the firmware runs it: one bearing at a time with its time,
//! the unit's own noise model, and the last update as the answer. Its ellipse is the unit's
//! own (no floor at the bound, no rescaling): what the unit says is what is measured.

use super::{BearingFix, Noise};
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::fix::window::{self, Status, WindowConfig};
use foxhunt_core::{Bearing, Error};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// What the unit answers, as the host's reports take it.
#[derive(Debug, Clone)]
pub struct UnitFix {
    /// The fix (its covariance, ellipse scale and CEP50 the unit's).
    pub fix: BearingFix,
    /// The noise the unit used.
    pub noise: Noise,
    /// The unit's own 95 % ellipse, exactly as its fix sentence carries it.
    pub ellipse: Ellipse,
}

/// The unit's fix over `bearings` in order, each at its time (ms): with the noise `sigma`
/// (radians) stated, or (`None`) estimated from the unit's default start, as the unit does.
/// The pair search draws from the unit's own seeded generator, so the same bearings give the
/// unit's bits. The noise's degrees of freedom: the inliers less two.
pub fn unit_fix(
    bearings: &[Bearing],
    times_ms: &[i64],
    sigma: Option<f32>,
) -> Result<UnitFix, Error> {
    let mut config = WindowConfig::default();
    if let Some(s) = sigma {
        config.noise = window::Noise::Known(s);
    }
    // The unit weighs each bearing relative to its own sigma: 1 for every bearing here.
    let relative = bearings
        .iter()
        .zip(times_ms)
        .map(|(b, &t)| (Bearing { sigma: 1.0, ..*b }, t));
    let mut rng = XorShiftRng::seed_from_u64(foxhunt_bridge::unit::SEARCH_SEED);
    let u = window::over(config, relative, &mut rng).ok_or(Error::TooFewMeasurements)?;
    match u.status {
        Status::Valid | Status::Noisy => {}
        Status::TooFew => return Err(Error::TooFewMeasurements),
        Status::Degenerate => return Err(Error::DegenerateGeometry),
        // No crossing most bearings agree with: the bearings do not meet at one emitter.
        Status::Searching => return Err(Error::NotConverged),
    }
    let dof = u.used.saturating_sub(2) as f32;
    let estimated = !matches!(config.noise, window::Noise::Known(s) if s == u.sigma);
    let scale = ellipse_scale_of(&u)?;
    Ok(UnitFix {
        fix: BearingFix {
            position: u.position,
            covariance: u.covariance,
            ellipse_scale: scale,
            dof: estimated.then_some(dof),
            cep50: u.cep50,
            evaluations: 0,
            outliers: u.window.saturating_sub(u.used),
            cloud: Vec::new(),
        },
        noise: Noise {
            sigma: u.sigma,
            dof,
        },
        ellipse: Ellipse {
            major: u.major,
            minor: u.minor,
            // The sentence's degrees clockwise from north, as radians counter-clockwise from
            // east.
            orientation: (90.0 - u.orientation_deg).to_radians(),
            confidence: window::CONFIDENCE,
        },
    })
}

/// The scale k of the unit's 95 % ellipse (x^T C^-1 x <= k): its semi-major axis squared over
/// the covariance's largest eigenvalue.
fn ellipse_scale_of(u: &window::Update) -> Result<f32, Error> {
    let unit = Ellipse::with_scale(&u.covariance, 1.0, 0.5)?;
    let k = (u.major / unit.major) * (u.major / unit.major);
    if k.is_finite() && k > 0.0 {
        Ok(k)
    } else {
        Err(Error::DegenerateGeometry)
    }
}

/// Times for bearings one a second (ms), as the benches' drives give them.
pub fn one_a_second(n: usize) -> Vec<i64> {
    (0..n as i64).map(|k| 1000 * k).collect()
}
