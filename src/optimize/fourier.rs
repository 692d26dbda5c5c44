//! The two Fourier transforms the optimizer needs, on the `K × K` grid of DESIGN §3:
//!
//! - type 1 (points to grid): `F(k) = Σ_j exp(−2πi k·x_j)`;
//! - type 2 (grid to points): `g_j = Σ_k c(k) exp(+2πi k·x_j)`.
//!
//! [`Method::Exact`] evaluates both directly in `O(N K²)` (the reference); [`Method::Nufft`] uses the
//! shared plans of [`crate::spectrum::nufft_plan`].

use crate::spectrum::{self, exact, Method};
use rustfft::num_complex::Complex64;

/// Type 1: `F(k) = Σ_j exp(−2πi k·x_j)` for 2D points on the `res × res` grid.
pub fn type1(points: &[[f64; 2]], res: usize, method: Method) -> Vec<Complex64> {
    spectrum::fourier_sums(points, res, method)
}

/// Type 2: `g_j = Σ_k c(k) exp(+2πi (k1 x_j + k2 y_j))` for the `res × res` grid `coeffs`. Panics on
/// NUFFT parameters that [`Method::nufft`] would refuse.
pub fn type2(
    coeffs: &[Complex64],
    points: &[[f64; 2]],
    res: usize,
    method: Method,
) -> Vec<Complex64> {
    match method {
        Method::Exact => exact::type2(coeffs, points, res),
        Method::Nufft { eps } => spectrum::nufft_plan(res, eps)
            .unwrap_or_else(|e| panic!("invalid NUFFT parameters: {e}"))
            .type2(coeffs, points),
    }
}
