//! The problem the solver works on: the cost over [x, y, offsets] with any loss, and its normal
//! equations (IRLS weights, the priors included), centred on the drive.

use super::super::{Geometry, geometry_of};
use super::{BiasPrior, BiasedOptions, MAX_SOURCES, STATE, Sighting, Start};
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::model::bearing::{Bearing, predicted, wrap};

/// Residual z - h(p) - b of one sighting at centred position `p` with offsets `b`.
#[inline]
pub(super) fn residual(b: &Bearing, origin: [f32; 2], p: [f32; 2], bias: f32) -> f32 {
    let s = [b.vehicle[0] - origin[0], b.vehicle[1] - origin[1]];
    wrap(b.theta - predicted(&p, &s) - bias)
}

/// The usable sightings with a known source.
pub(super) fn usable<T: Sighting>(items: &[T]) -> impl Iterator<Item = (&Bearing, usize)> {
    items
        .iter()
        .map(|t| (t.bearing(), t.source()))
        .filter(|(b, s)| *s < MAX_SOURCES && b.check().is_ok())
}

/// Working problem: centred origin, priors, which offsets are free.
pub(super) struct Problem<'a, T, L> {
    pub(super) items: &'a [T],
    pub(super) priors: &'a [BiasPrior; MAX_SOURCES],
    loss: &'a L,
    origin: [f32; 2],
    pub(super) scale: f32,
    position_sd: f32,
    pub(super) free: [bool; MAX_SOURCES],
}

impl<T: Sighting, L: Likelihood> Problem<'_, T, L> {
    /// The bearing's sd at centred position `p` (the position error's share included).
    fn sigma(&self, b: &Bearing, p: [f32; 2]) -> f32 {
        let plain = self.scale * b.sigma;
        if self.position_sd > 0.0 {
            let (dx, dy) = (
                p[0] - (b.vehicle[0] - self.origin[0]),
                p[1] - (b.vehicle[1] - self.origin[1]),
            );
            let d2 = (dx * dx + dy * dy).max(1e-6);
            libm::sqrtf(plain * plain + self.position_sd * self.position_sd / d2)
        } else {
            plain
        }
    }

    pub(super) fn cost(&self, x: &[f32; STATE]) -> f32 {
        let p = [x[0], x[1]];
        let mut c = 0.0f32;
        for (b, s) in usable(self.items) {
            let r = residual(b, self.origin, p, x[2 + s]);
            let sigma = self.sigma(b, p);
            c -= self.loss.ln(r, sigma);
            if self.position_sd > 0.0 {
                // The normalising constant, now that the sd depends on the position.
                c += libm::logf(sigma / (self.scale * b.sigma));
            }
        }
        for s in 0..MAX_SOURCES {
            if self.free[s] {
                let d = x[2 + s] - self.priors[s].mean;
                c += 0.5 * d * d * self.priors[s].information();
            }
        }
        c
    }

    /// Normal matrix and gradient (IRLS weights), priors included; fixed offsets get an
    /// identity row so the step leaves them alone.
    pub(super) fn normal(&self, x: &[f32; STATE]) -> ([[f32; STATE]; STATE], [f32; STATE]) {
        let mut h = [[0.0f32; STATE]; STATE];
        let mut g = [0.0f32; STATE];
        let p = [x[0], x[1]];
        for (b, s) in usable(self.items) {
            let v = [b.vehicle[0] - self.origin[0], b.vehicle[1] - self.origin[1]];
            let (dx, dy) = (p[0] - v[0], p[1] - v[1]);
            let d2 = (dx * dx + dy * dy).max(1e-6);
            let r = wrap(b.theta - predicted(&p, &v) - x[2 + s]);
            let sigma = self.sigma(b, p);
            let w = self.loss.irls_weight(r, sigma) / (sigma * sigma);
            // d h / d [x, y, b_s] for h = atan2(dy, dx) + b_s.
            let jac = [-dy / d2, dx / d2, 1.0];
            let idx = [0, 1, 2 + s];
            for i in 0..3 {
                for j in 0..3 {
                    h[idx[i]][idx[j]] += w * jac[i] * jac[j];
                }
                g[idx[i]] += w * jac[i] * r;
            }
        }
        for s in 0..MAX_SOURCES {
            let k = 2 + s;
            if self.free[s] {
                let info = self.priors[s].information();
                h[k][k] += info;
                g[k] += info * (self.priors[s].mean - x[k]);
            } else {
                for j in 0..STATE {
                    h[k][j] = 0.0;
                    h[j][k] = 0.0;
                }
                h[k][k] = 1.0;
                g[k] = 0.0;
            }
        }
        (h, g)
    }
}
/// The geometry check of the usable sightings.
fn sighting_geometry<T: Sighting>(items: &[T]) -> Result<Geometry, Error> {
    // The plain geometry check on the bearings of known sources; unknown sources count as
    // skipped.
    let mut g = geometry_of(usable(items).map(|(b, _)| b))?;
    g.skipped = items.len() as u32 - g.used;
    Ok(g)
}
/// A checked problem, the solver's starting state (centred on the drive) and the geometry.
pub(super) type SetUp<'a, T, L> = (Problem<'a, T, L>, [f32; STATE], Geometry);

/// The checked problem and the solver's starting state (centred on the drive).
pub(super) fn set_up<'a, T: Sighting, L: Likelihood>(
    items: &'a [T],
    priors: &'a [BiasPrior; MAX_SOURCES],
    start: Start,
    loss: &'a L,
    options: BiasedOptions,
) -> Result<SetUp<'a, T, L>, Error> {
    for p in priors {
        p.check()?;
    }
    check_finite(&[options.scale, options.tolerance_m, options.position_sd_m])?;
    check_finite(&start.position)?;
    check_finite(&start.bias)?;
    if !(options.scale > 0.0 && options.position_sd_m >= 0.0) {
        return Err(Error::OutOfRange);
    }
    let geo = sighting_geometry(items)?;
    let mut seen = [false; MAX_SOURCES];
    for (_, s) in usable(items) {
        seen[s] = true;
    }
    let free: [bool; MAX_SOURCES] = core::array::from_fn(|s| seen[s] && priors[s].is_free());
    let problem = Problem {
        items,
        priors,
        loss,
        origin: geo.origin,
        scale: options.scale,
        position_sd: options.position_sd_m,
        free,
    };
    let mut x = [0.0f32; STATE];
    x[0] = start.position[0] - geo.origin[0];
    x[1] = start.position[1] - geo.origin[1];
    for s in 0..MAX_SOURCES {
        x[2 + s] = if free[s] {
            start.bias[s]
        } else {
            priors[s].mean
        };
    }
    Ok((problem, x, geo))
}

/// The normal equations with the position reduced to one unknown t along `along` (x = x0 +
/// t along): row and column 0 become t's, row 1 an identity that leaves the rest alone.
pub(super) fn on_line(
    h: &[[f32; STATE]; STATE],
    g: &[f32; STATE],
    along: [f32; 2],
) -> ([[f32; STATE]; STATE], [f32; STATE]) {
    let [a, b] = along;
    let mut r = *h;
    let mut q = *g;
    r[0][0] = a * a * h[0][0] + a * b * (h[0][1] + h[1][0]) + b * b * h[1][1];
    for k in 2..STATE {
        let v = a * h[0][k] + b * h[1][k];
        r[0][k] = v;
        r[k][0] = v;
        r[1][k] = 0.0;
        r[k][1] = 0.0;
    }
    r[0][1] = 0.0;
    r[1][0] = 0.0;
    r[1][1] = 1.0;
    q[0] = a * g[0] + b * g[1];
    q[1] = 0.0;
    (r, q)
}
