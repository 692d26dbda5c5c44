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

pub use spec::{parse, FAMILIES};

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
