//! Likelihoods of a residual, as a type parameter of every filter and of the robust ML fix.
//!
//! Each works on the normalised residual u = r / sigma and gives the log-likelihood up to a
//! constant, plus the iteratively-reweighted-least-squares weight psi(u)/u that the robust ML
//! fix uses. Heavy tails are how a filter survives wild bearings (reflections, a wrong lobe);
//! a redescending loss ([`Cauchy`], [`Tukey`]) gives a wild bearing (almost) no say at all,
//! which is what a consistent ghost needs, provided the start is already near the emitter.

use core::f32::consts::PI;

/// A residual's log-likelihood and its IRLS weight.
pub trait Likelihood: Copy {
    /// log L(r) up to an additive constant, for residual `r` with scale `sigma` (> 0).
    fn ln(&self, r: f32, sigma: f32) -> f32;
    /// [`Likelihood::ln`] at one `sigma`, for the loops over every particle: implementations
    /// hoist what depends on `sigma` alone (the Gaussian multiplies by -1 / (2 sigma^2) instead
    /// of dividing per residual). Agrees with `ln` to a few ulp.
    fn ln_at(&self, sigma: f32) -> impl Fn(f32) -> f32 {
        let lik = *self;
        move |r| lik.ln(r, sigma)
    }
    /// IRLS weight -(d ln L / du) / u of residual `r` with scale `sigma`, u = r / sigma: 1 for
    /// a Gaussian, in [0, 1] for Huber, Cauchy, Tukey and the Gaussian + uniform mixture, and up
    /// to (nu + 1) / nu at u = 0 for Student-t (1.25 at the default nu = 4). Always >= 0 and
    /// finite for finite input. The scale is an argument because a mixture's weight depends on
    /// it, not only on u.
    fn irls_weight(&self, r: f32, sigma: f32) -> f32;
    /// The summed [`Likelihood::ln`] of `n` residuals with scale `sigma` from their mean and
    /// their scatter about it (the sum of squared deviations), where the loss allows it: a
    /// quadratic does, so a fixed station's many bearings cost one term; `None` (the default)
    /// for a loss that needs every residual.
    fn ln_sum(&self, _n: f32, _mean: f32, _scatter: f32, _sigma: f32) -> Option<f32> {
        None
    }
}

/// Gaussian: exp(-u^2 / 2). Optimal for clean data, ruined by one wild bearing.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Gaussian;

impl Likelihood for Gaussian {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        -0.5 * u * u
    }
    #[inline]
    fn ln_at(&self, sigma: f32) -> impl Fn(f32) -> f32 {
        let k = -0.5 / (sigma * sigma);
        move |r| k * r * r
    }
    #[inline]
    fn irls_weight(&self, _r: f32, _sigma: f32) -> f32 {
        1.0
    }
    #[inline]
    fn ln_sum(&self, n: f32, mean: f32, scatter: f32, sigma: f32) -> Option<f32> {
        Some(-0.5 * (n * mean * mean + scatter) / (sigma * sigma))
    }
}

/// Huber: quadratic within `c` sigmas, linear beyond (c = 1.345 gives 95 % Gaussian efficiency).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Huber {
    /// Threshold in sigmas.
    pub c: f32,
}

impl Default for Huber {
    fn default() -> Self {
        Self { c: 1.345 }
    }
}

impl Likelihood for Huber {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let a = libm::fabsf(r / sigma);
        if a <= self.c {
            -0.5 * a * a
        } else {
            -self.c * a + 0.5 * self.c * self.c
        }
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        let a = libm::fabsf(r / sigma);
        if a <= self.c { 1.0 } else { self.c / a }
    }
}

/// Cauchy: 1 / (1 + u^2). Redescending: a wild bearing ends up with almost no say.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Cauchy;

impl Likelihood for Cauchy {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        -libm::log1pf(u * u)
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        1.0 / (1.0 + u * u)
    }
}

/// Tukey's biweight: rho(u) = c^2/6 (1 - (1 - (u/c)^2)^3) within `c` sigmas, constant beyond
/// (c = 4.685 gives 95 % Gaussian efficiency). Hard-redescending: a bearing beyond c sigmas has
/// no influence at all, so a consistent ghost cannot drag a fix that starts near the emitter
/// (the loss is not convex: start it from a robust search, never from the PLE).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tukey {
    /// Rejection point in sigmas (> 0).
    pub c: f32,
}

impl Default for Tukey {
    fn default() -> Self {
        Self { c: 4.685 }
    }
}

impl Likelihood for Tukey {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        let c2 = self.c * self.c;
        let t = 1.0 - (u * u / c2).min(1.0);
        -(c2 / 6.0) * (1.0 - t * t * t)
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        let t = 1.0 - (u * u / (self.c * self.c)).min(1.0);
        t * t
    }
}

/// Student-t with `nu` degrees of freedom: between Cauchy (nu = 1) and Gaussian (nu -> inf).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudentT {
    /// Degrees of freedom (> 0).
    pub nu: f32,
}

impl Default for StudentT {
    fn default() -> Self {
        Self { nu: 4.0 }
    }
}

impl Likelihood for StudentT {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        -0.5 * (self.nu + 1.0) * libm::log1pf(u * u / self.nu)
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        (self.nu + 1.0) / (self.nu + u * u)
    }
}

/// Gaussian plus uniform: (1 - eps) N(r; 0, sigma^2) + eps / (2 pi). The exact model of a DF
/// unit that reports a uniformly random bearing a fraction `eps` of the time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianUniform {
    /// Share of wild bearings, in [0, 1).
    pub eps: f32,
}

impl Default for GaussianUniform {
    fn default() -> Self {
        Self { eps: 0.1 }
    }
}

impl GaussianUniform {
    /// Ratio of the uniform density to the Gaussian peak, for a given sigma.
    fn outlier_ratio(&self, sigma: f32) -> f32 {
        let eps = self.eps.clamp(0.0, 0.999);
        let peak = (1.0 - eps) / (sigma * libm::sqrtf(2.0 * PI));
        (eps / (2.0 * PI)) / peak
    }
}

impl Likelihood for GaussianUniform {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        let u = r / sigma;
        // log(exp(-u^2/2) + k), relative to the Gaussian peak.
        libm::logf(libm::expf(-0.5 * u * u) + self.outlier_ratio(sigma))
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        // Posterior probability of being an inlier (the EM weight of the mixture): the ratio
        // of the uniform floor to the Gaussian peak depends on this bearing's own sigma.
        let u = r / sigma;
        let g = libm::expf(-0.5 * u * u);
        let k = self.outlier_ratio(sigma);
        g / (g + k)
    }
}

/// Any likelihood evaluated with its scale multiplied by `factor` (> 1 widens it).
///
/// When the likelihood is much sharper than the spacing of the particles (an RSSI reading good
/// to 0.5 dB, say), almost every particle gets a negligible weight and the filter starves. Widening
/// the likelihood the filter uses ("measurement-noise inflation") trades a little resolution for
/// a cloud that keeps enough particles alive to follow the target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Widened<L> {
    /// The likelihood being widened.
    pub inner: L,
    /// Scale multiplier (> 0).
    pub factor: f32,
}

impl<L: Likelihood> Likelihood for Widened<L> {
    #[inline]
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        self.inner.ln(r, sigma * self.factor)
    }
    #[inline]
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        self.inner.irls_weight(r, sigma * self.factor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<L: Likelihood>(l: L) {
        // Maximal at zero, symmetric, decreasing in |r|, finite for huge residuals.
        assert!(l.ln(0.0, 0.1) >= l.ln(0.05, 0.1));
        assert!((l.ln(0.05, 0.1) - l.ln(-0.05, 0.1)).abs() < 1e-6);
        assert!(l.ln(0.3, 0.1) < l.ln(0.1, 0.1));
        assert!(l.ln(3.0, 0.01).is_finite());
        let w = l.irls_weight(1.0, 0.1);
        assert!((0.0..=1.0).contains(&w));
        let w0 = l.irls_weight(0.0, 0.1);
        assert!(w0.is_finite() && w0 >= 0.0);
        // The hoisted form agrees with the plain one to a few ulp.
        for sigma in [0.001f32, 0.0195, 1.0, 30.0] {
            let ln = l.ln_at(sigma);
            for k in -200..=200 {
                let r = sigma * k as f32 * 0.05;
                let (a, b) = (ln(r), l.ln(r, sigma));
                assert!(
                    (a - b).abs() <= 4e-7 * b.abs().max(1.0),
                    "{r} {sigma}: {a} {b}"
                );
            }
        }
    }

    #[test]
    fn shapes() {
        check(Gaussian);
        check(Huber::default());
        check(Cauchy);
        check(StudentT::default());
        check(Tukey::default());
        check(GaussianUniform::default());
        check(Widened {
            inner: Cauchy,
            factor: 2.0,
        });
    }

    #[test]
    fn huber_matches_gaussian_in_core() {
        let h = Huber::default();
        assert_eq!(h.ln(0.1, 0.1), Gaussian.ln(0.1, 0.1));
        assert!((h.irls_weight(2.69, 1.0) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn mixture_floor_is_the_uniform() {
        let g = GaussianUniform { eps: 0.1 };
        // Far out the mixture is flat: a wild bearing costs a constant, not u^2.
        assert!((g.ln(2.0, 0.02) - g.ln(3.0, 0.02)).abs() < 1e-6);
    }

    #[test]
    fn documented_weight_ranges() {
        // Student-t weighs a zero residual above 1: (nu + 1) / nu.
        assert!((StudentT::default().irls_weight(0.0, 0.1) - 1.25).abs() < 1e-6);
        // Tukey: 1 at zero, 0 from c sigmas on, and its loss is flat there.
        let t = Tukey::default();
        assert_eq!(t.irls_weight(0.0, 0.1), 1.0);
        assert_eq!(t.irls_weight(0.47, 0.1), 0.0);
        assert_eq!(t.ln(0.5, 0.1), t.ln(5.0, 0.1));
    }

    #[test]
    fn mixture_weight_uses_the_bearings_own_sigma() {
        // The same normalised residual is likelier an inlier when sigma is small (the Gaussian
        // density stands higher above the same uniform floor): the weight must change with
        // sigma, which a fixed hidden sigma could not do.
        let g = GaussianUniform { eps: 0.1 };
        let narrow = g.irls_weight(3.0 * 0.005, 0.005);
        let wide = g.irls_weight(3.0 * 0.2, 0.2);
        assert!(narrow > wide, "{narrow} {wide}");
        // And the weight is the posterior inlier probability from the likelihood itself.
        for sigma in [0.005f32, 0.02, 0.2] {
            let r = 2.5 * sigma;
            let ratio = g.outlier_ratio(sigma);
            let inlier = libm::expf(-0.5 * 2.5 * 2.5);
            let expected = inlier / (inlier + ratio);
            assert!((g.irls_weight(r, sigma) - expected).abs() < 1e-6);
        }
    }
}
