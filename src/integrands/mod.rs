//! Integrands: functions on `[0,1)^D` with a known (or reference) integral, evaluated by the
//! convergence test and, where their torus Fourier coefficients are known, by the variance prediction.
//!
//! Families (see [`spec::FAMILIES`] and `anisospec integrands`): a periodic Gaussian (smooth), a disc, an
//! oriented step, a sheared step `x + s u < c`, a fan of sheared edges with shears over `[s0, s1]`
//! (a double-wedge spectrum), and sums and products of these placed on projections of 4D. Every family
//! has an exact integral; Fourier coefficients are in closed form except for the fan, whose coefficients
//! come from Gauss–Legendre quadrature with the error bound [`Integrand::fourier_error`].

pub mod compose;
pub mod polygon;
pub mod sampled;
pub mod shapes;
pub mod spec;

pub use spec::{parse, parse_with_cache, FAMILIES};

use crate::points::Projection;
use crate::rng::Rng;
use rustfft::num_complex::Complex64;

/// The integral an estimate is judged against, with its own standard error (0 when exact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// The integral over `[0,1)^D`.
    pub value: f64,
    /// Standard error of `value`: 0 for closed forms, positive for Monte Carlo references.
    pub stderr: f64,
}

/// Owen scramblings of the Sobol set [`estimate_variance`] averages over: their spread gives the
/// standard error.
const VARIANCE_SCRAMBLES: u32 = 32;
/// Points per scrambling in [`estimate_variance`]: `2^16`, so `2^21` evaluations in all.
const VARIANCE_POINTS: u32 = 1 << 16;

/// `Var(f) = ∫(f − ∫f)²` over `[0,1)^D`, with its standard error: [`Integrand::variance`] (standard
/// error 0) where it is known in closed form, otherwise [`estimate_variance`].
pub fn variance_reference(f: &dyn Integrand) -> Reference {
    match f.variance() {
        Some(value) => Reference { value, stderr: 0.0 },
        None => estimate_variance(f),
    }
}

/// `Var(f) = ∫(f − μ)²` over `[0,1)^D` by randomized quasi-Monte Carlo, with `μ` the integrand's
/// reference: the mean of `(f − μ)²` over 32 independent Owen scramblings (`sobol_burley`, fixed
/// seeds) of a Sobol set of `2^16` points, with the standard error of that mean from their spread.
/// Centred, it carries no noise of `2μ ∫(f − μ)`, and it is never the difference of `∫f²` and `μ²`,
/// which cancels when the variance is far below the squared mean (two broad Gaussians:
/// `Var f ≈ 1e-15` against `μ² ≈ 4`). The same bits on every run and thread count. For a sum of
/// overlapping shapes, whose cross terms `∫f_i f_j` have no closed form here.
pub fn estimate_variance(f: &dyn Integrand) -> Reference {
    use rayon::prelude::*;
    let dims = f.dims();
    let mu = f.reference().value;
    let means: Vec<f64> = (0..VARIANCE_SCRAMBLES)
        .into_par_iter()
        .map(|seed| {
            let mut x = [0.0; 4];
            let sum: f64 = (0..VARIANCE_POINTS)
                .map(|i| {
                    let p = sobol_burley::sample_4d(i, 0, seed);
                    for (xd, pd) in x.iter_mut().zip(p) {
                        *xd = f64::from(pd);
                    }
                    (f.eval(&x[..dims]) - mu).powi(2)
                })
                .sum();
            sum / f64::from(VARIANCE_POINTS)
        })
        .collect();
    let r = means.len() as f64;
    let value = means.iter().sum::<f64>() / r;
    let spread = means.iter().map(|m| (m - value).powi(2)).sum::<f64>() / (r - 1.0);
    Reference {
        value,
        stderr: (spread / r).sqrt(),
    }
}

/// A function on the unit torus `[0,1)^D` (`D` 2 or 4; in 4D the coordinates are `x, y, u, v`).
pub trait Integrand: Send + Sync {
    /// A short description with its parameters, e.g. `step:theta=30`.
    fn name(&self) -> String;

    /// Dimensions of the domain (2 or 4).
    fn dims(&self) -> usize;

    /// The value at a point `x` of `[0,1)^D`.
    fn eval(&self, x: &[f64]) -> f64;

    /// The integral over `[0,1)^D`.
    fn reference(&self) -> Reference;

    /// The torus Fourier coefficient `f̂(k) = ∫ f(x) exp(−2πi k·x) dx` at the integer frequency `k`
    /// (`D` entries), or `None` when the integrand has no usable spectrum.
    fn fourier(&self, _k: &[i64]) -> Option<Complex64> {
        None
    }

    /// A bound on the absolute error of every value [`Integrand::fourier`] returns: 0 for closed forms.
    fn fourier_error(&self) -> f64 {
        0.0
    }

    /// `∫ f² over [0,1)^D` where it is known exactly (to machine precision), for the Parseval bound of
    /// the spectrum's truncation tail: `Σ_{k≠0} |f̂(k)|² = ∫f² − (∫f)²`.
    fn mean_square(&self) -> Option<f64> {
        None
    }

    /// `Var(f) = ∫f² − (∫f)²` over `[0,1)^D` where [`Integrand::mean_square`] is known. Families whose
    /// variance can be far below their squared mean (a broad Gaussian: `Var f ≈ 1e-12` against
    /// `(∫f)² ≈ 30`) override it with a form free of that difference's cancellation.
    fn variance(&self) -> Option<f64> {
        Some(self.mean_square()? - self.reference().value.powi(2))
    }

    /// The dimensions `f` depends on (sorted); a product needs its factors on disjoint sets.
    fn support(&self) -> Vec<usize> {
        (0..self.dims()).collect()
    }

    /// The 2D projections whose frequency planes hold every `k` with `f̂(k) ≠ 0`, so that only those
    /// projections' 2D spectra matter for the variance (DESIGN §4); `None` when `f̂` spreads over all of
    /// `D`-dimensional frequency space (e.g. a product over two projections).
    fn spectral_planes(&self) -> Option<Vec<Projection>> {
        (self.dims() == 2).then(|| vec![Projection::XY])
    }

    /// Random placement hook: the same integrand moved to a random position (centre or offset, drawn
    /// from `rng` as the family documents), for the convergence test's "random placement per
    /// realization" option. `None` when the family has nothing to move.
    fn placed(&self, _rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The randomized-QMC `Var f` agrees with every closed form within 4 of its standard errors.
    #[test]
    fn estimated_variance_meets_the_closed_forms() {
        for spec in [
            "disc:r=0.3,cx=0.4",
            "step:theta=30,c=0.6",
            "gaussian:sigma=0.1",
            "fan:s0=0.3,s1=0.7@xu",
            "sheared:s=0.5@xu*disc:r=0.2@yv",
        ] {
            let f = parse(spec).unwrap();
            let exact = f.variance().unwrap();
            let e = estimate_variance(f.as_ref());
            eprintln!("{spec}: {exact:.8e} vs {:.8e} ± {:.1e}", e.value, e.stderr);
            assert!(e.stderr > 0.0, "{spec}: {e:?}");
            assert!((e.value - exact).abs() <= 4.0 * e.stderr, "{spec}: {e:?}");
        }
    }

    /// Two overlapping steps, one across x and one across y: the sum has no closed-form `∫f²`, but
    /// the steps are independent, so `Var(f) = 0.7·0.3 + 0.4·0.6 = 0.45`.
    #[test]
    fn overlapping_sum_gets_an_estimated_variance() {
        let f = parse("step:c=0.3+step:theta=90,c=0.6").unwrap();
        assert_eq!(f.variance(), None);
        let v = variance_reference(f.as_ref());
        assert!(v.stderr > 0.0);
        assert!((v.value - 0.45).abs() <= 4.0 * v.stderr, "{v:?}");
        let disc = parse("disc:r=0.3").unwrap();
        let exact = variance_reference(disc.as_ref());
        assert_eq!(exact.stderr, 0.0);
        assert_eq!(Some(exact.value), disc.variance());
    }

    /// Two overlapping broad Gaussians, whose variance is about 1e-15 of their squared mean: the
    /// centred estimate keeps it within 4 standard errors, where `∫f² − μ²` lost every digit (it gave
    /// 0). The reference is Parseval's `Σ_{k≠0} |f̂(k)|²` from the terms' exact coefficients over
    /// `|k1|, |k2| ≤ 8`, beyond which a Gaussian of σ = 1 has nothing left in double precision.
    #[test]
    fn a_variance_far_below_the_squared_mean_keeps_its_digits() {
        let f = parse("gaussian:sigma=1+gaussian:sigma=1,cx=0.2").unwrap();
        assert_eq!(f.variance(), None);
        let mut exact = 0.0;
        for k1 in -8i64..=8 {
            for k2 in -8i64..=8 {
                if (k1, k2) != (0, 0) {
                    exact += f.fourier(&[k1, k2]).unwrap().norm_sqr();
                }
            }
        }
        let v = estimate_variance(f.as_ref());
        assert!(exact > 1e-16 && v.value > 0.0, "{exact:e} {v:?}");
        assert!(
            (v.value - exact).abs() <= 4.0 * v.stderr,
            "{exact:e} vs {v:?}"
        );
    }
}
