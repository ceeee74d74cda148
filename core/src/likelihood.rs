//! Likelihoods of a residual, as a type parameter of every filter and of the robust ML fix.
//!
//! Each works on the normalised residual u = r / sigma and gives the log-likelihood up to a
//! constant, plus the iteratively-reweighted-least-squares weight psi(u)/u that the robust ML
//! fix uses. Heavy tails are how a filter survives wild bearings (reflections, a wrong lobe).

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
    /// IRLS weight -d ln L / du / u in [0, 1] for the normalised residual u = r / sigma
    /// (1 for a Gaussian).
    fn irls_weight(&self, u: f32) -> f32;
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
    fn irls_weight(&self, _u: f32) -> f32 {
        1.0
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
    fn irls_weight(&self, u: f32) -> f32 {
        let a = libm::fabsf(u);
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
    fn irls_weight(&self, u: f32) -> f32 {
        1.0 / (1.0 + u * u)
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
    fn irls_weight(&self, u: f32) -> f32 {
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
    fn irls_weight(&self, u: f32) -> f32 {
        // Posterior probability of being an inlier; sigma enters only through the ratio, and
        // a typical DF sigma of 1 degree is used for it.
        let g = libm::expf(-0.5 * u * u);
        let k = self.outlier_ratio(0.02);
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
    fn irls_weight(&self, u: f32) -> f32 {
        self.inner.irls_weight(u / self.factor)
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
        let w = l.irls_weight(10.0);
        assert!((0.0..=1.0).contains(&w));
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
        assert!((h.irls_weight(2.69) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn mixture_floor_is_the_uniform() {
        let g = GaussianUniform { eps: 0.1 };
        // Far out the mixture is flat: a wild bearing costs a constant, not u^2.
        assert!((g.ln(2.0, 0.02) - g.ln(3.0, 0.02)).abs() < 1e-6);
    }
}
