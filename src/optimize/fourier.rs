//! The two Fourier transforms the optimizer needs, on the `K × K` grid of DESIGN §3:
//!
//! - type 1 (points to grid): `F(k) = Σ_j exp(−2πi k·x_j)`;
//! - type 2 (grid to points): `g_j = Σ_k c(k) exp(+2πi k·x_j)`.
//!
//! [`Method::Exact`] evaluates both directly in `O(N K²)` (the reference); the NUFFT is the fast path.

use crate::spectrum::{self, Method};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::f64::consts::TAU;

/// `exp(+2πi k c)` for `k = −K/2 … K/2−1`, each reduced mod 1 before scaling.
fn phases_plus(c: f64, res: usize) -> Vec<Complex64> {
    let half = (res / 2) as i64;
    (0..res as i64)
        .map(|j| {
            let t = ((j - half) as f64 * c).rem_euclid(1.0);
            let (s, co) = (TAU * t).sin_cos();
            Complex64::new(co, s)
        })
        .collect()
}

/// Type 1: `F(k) = Σ_j exp(−2πi k·x_j)` for 2D points on the `res × res` grid.
pub fn type1(points: &[[f64; 2]], res: usize, method: Method) -> Vec<Complex64> {
    spectrum::fourier_sums(points, res, method)
}

/// Type 2, exactly: `g_j = Σ_k c(k) exp(+2πi (k1 x_j + k2 y_j))` for the `res × res` grid `coeffs`.
pub fn type2_exact(coeffs: &[Complex64], points: &[[f64; 2]], res: usize) -> Vec<Complex64> {
    debug_assert_eq!(coeffs.len(), res * res);
    points
        .par_iter()
        .map(|p| {
            let e1 = phases_plus(p[0], res);
            let e2 = phases_plus(p[1], res);
            coeffs
                .chunks_exact(res)
                .zip(&e2)
                .map(|(row, w)| {
                    let inner: Complex64 = row.iter().zip(&e1).map(|(c, e)| c * e).sum();
                    inner * w
                })
                .sum()
        })
        .collect()
}

/// Type 2 by the chosen method.
pub fn type2(
    coeffs: &[Complex64],
    points: &[[f64; 2]],
    res: usize,
    method: Method,
) -> Vec<Complex64> {
    match method {
        Method::Exact | Method::Nufft { .. } => type2_exact(coeffs, points, res),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Type 2 is the adjoint of type 1: `Σ_j conj(g_j) = Σ_k conj(c(k)) F(k)` for unit point weights.
    #[test]
    fn type2_is_adjoint_of_type1() {
        let pts = [[0.1, 0.7], [0.33, 0.25], [0.9, 0.05]];
        let res = 8;
        let c: Vec<Complex64> = (0..res * res)
            .map(|i| Complex64::new((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
            .collect();
        let f = type1(&pts, res, Method::Exact);
        let g = type2_exact(&c, &pts, res);
        let lhs: Complex64 = g.iter().map(|x| x.conj()).sum();
        let rhs: Complex64 = c.iter().zip(&f).map(|(a, b)| a.conj() * b).sum();
        assert!((lhs - rhs).norm() < 1e-12 * rhs.norm().max(1.0));
    }
}
