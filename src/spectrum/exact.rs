//! The exact DFT of a point set on a frequency grid: `O(N K²)`, parallel, `f64`. The reference every
//! fast path is tested against.

use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::f64::consts::TAU;

/// The relative error `ρ_F = (√2 N + 2π K + 1569) u` (`u = 2^−53`) of the Fourier sums of `n` points
/// on a `res × res` grid at a bin where `|F| = N`, and `ρ_F N` the absolute error of any bin: the
/// first-order bound derived step by step in [`crate::variance`] (phases, their sparse recurrence,
/// the products and the sum over points).
pub fn sum_error(n: usize, res: usize) -> f64 {
    (std::f64::consts::SQRT_2 * n as f64 + 2.0 * std::f64::consts::PI * res as f64 + 1569.0)
        * (f64::EPSILON / 2.0)
}

/// `exp(−2πi t)`, with `t` reduced mod 1 before scaling by 2π, so the argument stays small whatever
/// `t`; exactly 1 at integers (e.g. a corner of the unit square at an integer frequency), without a
/// sine.
pub fn turn(t: f64) -> Complex64 {
    let t = t - t.floor();
    if t == 0.0 {
        return Complex64::new(1.0, 0.0);
    }
    let (s, co) = (TAU * t).sin_cos();
    Complex64::new(co, -s)
}

/// `exp(−2πi k c)`, computed directly ([`turn`] of `k·c`).
pub fn phase(k: i64, c: f64) -> Complex64 {
    turn(k as f64 * c)
}

/// `exp(−2πi k c)` for `k = −K/2 … K/2−1`, each computed directly (no recurrence, no drift).
fn phases(c: f64, res: usize) -> Vec<Complex64> {
    let half = (res / 2) as i64;
    (0..res as i64).map(|j| phase(j - half, c)).collect()
}

/// Bytes of phase tables held at once by [`fourier_sums`] (`32 K` per point): the points go through
/// in blocks of `PHASE_BYTES / (32 K)`, so memory stays `O(K²)` whatever `N`.
const PHASE_BYTES: usize = 8 << 20;

/// `F(k) = Σ_j exp(−2πi (k1 x_j + k2 y_j))` on the `res × res` grid (layout: see [`crate::spectrum`]).
/// Each bin adds its terms in point order, block after block, so the bits do not depend on the block
/// size or the thread count.
pub fn fourier_sums(points: &[[f64; 2]], res: usize) -> Vec<Complex64> {
    fourier_sums_in_blocks(points, res, (PHASE_BYTES / (32 * res.max(1))).max(1))
}

/// [`fourier_sums`] with the points taken `block` at a time.
fn fourier_sums_in_blocks(points: &[[f64; 2]], res: usize, block: usize) -> Vec<Complex64> {
    let mut out = vec![Complex64::new(0.0, 0.0); res * res];
    for chunk in points.chunks(block) {
        let e1: Vec<Vec<Complex64>> = chunk.par_iter().map(|p| phases(p[0], res)).collect();
        let e2: Vec<Vec<Complex64>> = chunk.par_iter().map(|p| phases(p[1], res)).collect();
        out.par_chunks_mut(res).enumerate().for_each(|(i, row)| {
            for (a, b) in e1.iter().zip(&e2) {
                let w = b[i];
                for (r, x) in row.iter_mut().zip(a) {
                    *r += w * x;
                }
            }
        });
    }
    out
}

/// Exact type 2 (the adjoint of [`fourier_sums`]): `g_j = Σ_k c(k) exp(+2πi k·x_j)` for coefficients
/// `c` on the `res × res` grid (layout: see [`crate::spectrum`]). `O(N K²)`, parallel over points.
///
/// Panics if `coeffs.len() != res²`.
pub fn type2(coeffs: &[Complex64], points: &[[f64; 2]], res: usize) -> Vec<Complex64> {
    assert_eq!(
        coeffs.len(),
        res * res,
        "type2 needs res² coefficients on the res × res grid"
    );
    points
        .par_iter()
        .map(|p| {
            // exp(+2πi k c) = conj(exp(−2πi k c)).
            let e1 = phases(p[0], res);
            let e2 = phases(p[1], res);
            coeffs
                .chunks_exact(res)
                .zip(&e2)
                .map(|(row, b)| {
                    let s: Complex64 = row.iter().zip(&e1).map(|(c, a)| c * a.conj()).sum();
                    s * b.conj()
                })
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_of_points_keep_the_bits() {
        let points: Vec<[f64; 2]> = (0..37)
            .map(|j| {
                [
                    (j as f64 * 0.618_034).fract(),
                    (j as f64 * 0.414_214).fract(),
                ]
            })
            .collect();
        let whole = fourier_sums_in_blocks(&points, 16, points.len());
        for block in [1, 5, 36] {
            assert_eq!(
                fourier_sums_in_blocks(&points, 16, block),
                whole,
                "block {block}"
            );
        }
    }
}
