//! Integrands: functions on `[0,1)^D` with a known (or reference) integral, evaluated by the
//! convergence test and, where their torus Fourier coefficients are known, by the variance prediction.

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
}
