//! Convex polygons inside the unit square: the region `{x : n·x < c}` of a half-plane clipped to
//! `[0,1)²`, its area and its exact torus Fourier coefficients (divergence theorem, one closed-form term
//! per edge).

use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// Vertices, counter-clockwise, of the unit square clipped to the half-plane `n·x ≤ c` (empty if the
/// half-plane misses the square).
pub fn clip_square(n: [f64; 2], c: f64) -> Vec<[f64; 2]> {
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let side = |p: &[f64; 2]| n[0] * p[0] + n[1] * p[1] - c;
    let mut out = Vec::with_capacity(5);
    for i in 0..4 {
        let (p, q) = (square[i], square[(i + 1) % 4]);
        let (sp, sq) = (side(&p), side(&q));
        if sp <= 0.0 {
            out.push(p);
        }
        if (sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0) {
            let t = sp / (sp - sq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    out
}

/// Area of a polygon given counter-clockwise (shoelace formula).
pub fn area(poly: &[[f64; 2]]) -> f64 {
    let m = poly.len();
    (0..m)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % m]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum::<f64>()
        * 0.5
}

/// `sin(t) / t`, 1 at 0.
fn sinc(t: f64) -> f64 {
    if t.abs() < 1e-8 {
        1.0 - t * t / 6.0
    } else {
        t.sin() / t
    }
}

/// `∫_poly exp(−2πi k·x) dx` for an integer frequency `k`, exact.
///
/// For `k ≠ 0`, `exp(−2πi k·x) = ∇·(i k exp(−2πi k·x) / (2π|k|²))`, so the integral is a sum over
/// edges `p → q` (direction `d = q − p`, midpoint `m`) of
/// `i (k1 d2 − k2 d1) exp(−2πi k·m) sinc(π k·d) / (2π|k|²)`.
pub fn fourier(poly: &[[f64; 2]], k: [i64; 2]) -> Complex64 {
    if k == [0, 0] {
        return Complex64::new(area(poly), 0.0);
    }
    let (k1, k2) = (k[0] as f64, k[1] as f64);
    let m = poly.len();
    let mut sum = Complex64::new(0.0, 0.0);
    for i in 0..m {
        let (p, q) = (poly[i], poly[(i + 1) % m]);
        let d = [q[0] - p[0], q[1] - p[1]];
        let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
        let flux = k1 * d[1] - k2 * d[0];
        if flux == 0.0 {
            continue;
        }
        // Reduce the phase mod 1 before scaling, for accuracy at large k.
        let phase = (k1 * mid[0] + k2 * mid[1]).rem_euclid(1.0);
        let (s, co) = (2.0 * PI * phase).sin_cos();
        sum += Complex64::new(co, -s) * (flux * sinc(PI * (k1 * d[0] + k2 * d[1])));
    }
    sum * Complex64::new(0.0, 1.0 / (2.0 * PI * (k1 * k1 + k2 * k2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint-rule reference on a fine grid (error O(h) at the edge, checked loosely against it).
    fn brute(n: [f64; 2], c: f64, k: [i64; 2], m: usize) -> Complex64 {
        let h = 1.0 / m as f64;
        let mut s = Complex64::new(0.0, 0.0);
        for i in 0..m {
            for j in 0..m {
                let (x, y) = ((j as f64 + 0.5) * h, (i as f64 + 0.5) * h);
                if n[0] * x + n[1] * y < c {
                    let ph = -2.0 * PI * (k[0] as f64 * x + k[1] as f64 * y);
                    s += Complex64::new(ph.cos(), ph.sin());
                }
            }
        }
        s * (h * h)
    }

    #[test]
    fn half_square_matches_1d_integral() {
        let poly = clip_square([1.0, 0.0], 0.3);
        assert!((area(&poly) - 0.3).abs() < 1e-15);
        for k1 in [-3i64, 1, 5] {
            let f = fourier(&poly, [k1, 0]);
            // ∫_0^0.3 exp(−2πi k x) dx = (1 − exp(−2πi k 0.3)) / (2πi k)
            let e = Complex64::new(0.0, -2.0 * PI * k1 as f64 * 0.3).exp();
            let exact = (Complex64::new(1.0, 0.0) - e) / Complex64::new(0.0, 2.0 * PI * k1 as f64);
            assert!((f - exact).norm() < 1e-15);
            assert!(fourier(&poly, [k1, 2]).norm() < 1e-15);
        }
    }

    #[test]
    fn oblique_polygon_matches_brute_force() {
        let t = 30f64.to_radians();
        let n = [t.cos(), t.sin()];
        let poly = clip_square(n, 0.6);
        for k in [[1, 0], [0, 1], [2, -3], [4, 4]] {
            let f = fourier(&poly, k);
            let b = brute(n, 0.6, k, 2000);
            // Midpoint rule with a discontinuous edge: error ~ h · perimeter ≈ 1e-3.
            assert!((f - b).norm() < 2e-3, "{k:?}: {f} vs {b}");
        }
    }
}
