//! Local metres back to latitude and longitude, cheaply, for the unit's fix sentences.

use crate::geo::LocalFrame;
use crate::nmea::LatLon;

/// Local metres back to latitude and longitude for the fix sentences, cheaply: a quadratic in
/// (east, north) fitted once per frame to the bridge's exact inverse
/// ([`LocalFrame::to_geodetic`], about 250 000 instructions of software `f64` on the
/// Cortex-M4F) at six points 5 km out. Evaluating it is a dozen `f64` multiply-adds. Its error
/// is of third order in the distance from the origin: under 0.1 m within 10 km, a few metres
/// at 50 km (the tests measure both), far inside any fix's ellipse at those ranges. Not across
/// the antimeridian (the fitted longitude does not wrap).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The frame origin the quadratic was fitted around.
    pub(super) origin: LatLon,
    lat: [f64; 6],
    lon: [f64; 6],
}

impl Projection {
    /// Half the fitting stencil, metres.
    const D: f64 = 5000.0;

    /// The quadratic of `frame`'s inverse, or `None` if the inverse fails at a stencil point.
    pub fn new(frame: &LocalFrame) -> Option<Self> {
        let d = Self::D;
        let g = |e: f64, n: f64| frame.to_geodetic([e, n]).ok();
        let p = [
            g(0.0, 0.0)?,
            g(d, 0.0)?,
            g(-d, 0.0)?,
            g(0.0, d)?,
            g(0.0, -d)?,
            g(d, d)?,
        ];
        let fit = |f: [f64; 6]| {
            let [f0, fx, fmx, fy, fmy, fxy] = f;
            let a1 = (fx - fmx) / (2.0 * d);
            let a3 = (fx + fmx - 2.0 * f0) / (2.0 * d * d);
            let a2 = (fy - fmy) / (2.0 * d);
            let a5 = (fy + fmy - 2.0 * f0) / (2.0 * d * d);
            let a4 = (fxy - f0 - a1 * d - a2 * d - a3 * d * d - a5 * d * d) / (d * d);
            [f0, a1, a2, a3, a4, a5]
        };
        Some(Self {
            origin: frame.origin,
            lat: fit(p.map(|q| q.lat)),
            lon: fit(p.map(|q| q.lon)),
        })
    }

    /// The position at east `e`, north `n` metres.
    pub fn at(&self, e: f64, n: f64) -> LatLon {
        let q =
            |a: &[f64; 6]| a[0] + a[1] * e + a[2] * n + a[3] * e * e + a[4] * e * n + a[5] * n * n;
        LatLon {
            lat: q(&self.lat),
            lon: q(&self.lon),
        }
    }
}
