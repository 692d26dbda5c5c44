//! Convex polygons inside the unit square: the region `{x : n·x < c}` of a half-plane clipped to
//! `[0,1)²`, its area and its exact torus Fourier coefficients (divergence theorem, one closed-form term
//! per edge).

use crate::spectrum::exact::turn;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// A convex polygon inside the unit square with at most five vertices, counter-clockwise: the square
/// cut by one line (held inline: a fan's quadrature builds one per node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polygon {
    corners: [[f64; 2]; MAX_VERTICES],
    len: usize,
}

/// Most vertices of the unit square cut by one line.
const MAX_VERTICES: usize = 5;

impl Polygon {
    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[[f64; 2]] {
        &self.corners[..self.len]
    }
}

/// Vertices, counter-clockwise, of the unit square clipped to the half-plane `n·x ≤ c` (empty if the
/// half-plane misses the square).
pub fn clip_square(n: [f64; 2], c: f64) -> Polygon {
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let side = |p: &[f64; 2]| n[0] * p[0] + n[1] * p[1] - c;
    let mut out = Polygon {
        corners: [[0.0; 2]; MAX_VERTICES],
        len: 0,
    };
    let mut push = |v: [f64; 2]| {
        out.corners[out.len] = v;
        out.len += 1;
    };
    for i in 0..4 {
        let (p, q) = (square[i], square[(i + 1) % 4]);
        let (sp, sq) = (side(&p), side(&q));
        if sp <= 0.0 {
            push(p);
        }
        if (sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0) {
            let t = sp / (sp - sq);
            push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
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

/// Below this `|k·d|` an edge takes the midpoint form of [`fourier`]: the vertex form divides a
/// difference of two unit phasors by `k·d`, which would amplify their rounding.
const SMALL_PHASE: f64 = 0.125;

/// `∫_poly exp(−2πi k·x) dx` for an integer frequency `k`, exact.
///
/// For `k ≠ 0`, `exp(−2πi k·x) = ∇·(i k exp(−2πi k·x) / (2π|k|²))`, so the integral is a sum over
/// edges `p → q` (direction `d = q − p`, midpoint `m`) of
/// `i (k1 d2 − k2 d1) exp(−2πi k·m) sinc(π k·d) / (2π|k|²)` (the midpoint form). Since
/// `exp(−2πi k·m) sinc(π k·d) = (e_p − e_q) / (2πi k·d)` with `e_v = exp(−2πi k·v)`, an edge with
/// `|k·d| ≥ 1/8` takes `(k1 d2 − k2 d1)(e_p − e_q) / (4π² |k|² k·d)` instead (the vertex form): one
/// phasor per vertex, shared by its two edges, and none at the square's corners, where `e_v = 1`.
/// The two forms agree to rounding (`vertex_and_midpoint_forms_agree`).
pub fn fourier(poly: &Polygon, k: [i64; 2]) -> Complex64 {
    let poly = poly.vertices();
    if k == [0, 0] {
        return Complex64::new(area(poly), 0.0);
    }
    let (k1, k2) = (k[0] as f64, k[1] as f64);
    let m = poly.len();
    let mut phasors = [Complex64::new(0.0, 0.0); MAX_VERTICES];
    for (e, v) in phasors.iter_mut().zip(poly) {
        *e = turn(k1 * v[0] + k2 * v[1]);
    }
    let (mut vertex_sum, mut midpoint_sum) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
    for i in 0..m {
        let j = (i + 1) % m;
        let (p, q) = (poly[i], poly[j]);
        let d = [q[0] - p[0], q[1] - p[1]];
        let flux = k1 * d[1] - k2 * d[0];
        if flux == 0.0 {
            continue;
        }
        let kd = k1 * d[0] + k2 * d[1];
        if kd.abs() >= SMALL_PHASE {
            vertex_sum += (phasors[i] - phasors[j]) * (flux / kd);
        } else {
            midpoint_sum += midpoint_term(p, q, k1, k2, flux);
        }
    }
    let k_sq = k1 * k1 + k2 * k2;
    vertex_sum / (4.0 * PI * PI * k_sq)
        + midpoint_sum * Complex64::new(0.0, 1.0 / (2.0 * PI * k_sq))
}

/// The edge `p → q`'s `(k1 d2 − k2 d1) exp(−2πi k·m) sinc(π k·d)` (the midpoint form of [`fourier`],
/// without its common factor `i / (2π|k|²)`).
fn midpoint_term(p: [f64; 2], q: [f64; 2], k1: f64, k2: f64, flux: f64) -> Complex64 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
    turn(k1 * mid[0] + k2 * mid[1]) * (flux * sinc(PI * (k1 * d[0] + k2 * d[1])))
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

    /// `∫ exp(−2πi k·x)` over `{n·x < c}` in the unit square, independently of the divergence
    /// theorem: the inner integral over `x1` in closed form, the outer over `x2` by Gauss–Legendre,
    /// cut where the line crosses `x1 = 0` and `x1 = 1` (smooth between), with `panels` 16-point
    /// panels per piece.
    fn by_rows(n: [f64; 2], c: f64, k: [i64; 2], panels: usize) -> Complex64 {
        let (k1, k2) = (k[0] as f64, k[1] as f64);
        let span = |a: f64, b: f64| {
            if b <= a {
                Complex64::new(0.0, 0.0)
            } else if k1 == 0.0 {
                Complex64::new(b - a, 0.0)
            } else {
                let e = |x: f64| Complex64::new(0.0, -2.0 * PI * k1 * x).exp();
                (e(a) - e(b)) / Complex64::new(0.0, 2.0 * PI * k1)
            }
        };
        let row = |y: f64| {
            // x1 on the side n0 x1 < c − n1 y.
            let r = c - n[1] * y;
            let inner = if n[0] > 0.0 {
                span(0.0, (r / n[0]).clamp(0.0, 1.0))
            } else {
                span((r / n[0]).clamp(0.0, 1.0), 1.0)
            };
            inner * Complex64::new(0.0, -2.0 * PI * k2 * y).exp()
        };
        let breaks = [c / n[1], (c - n[0]) / n[1]];
        crate::quad::integrate(
            &crate::quad::gauss_legendre(16),
            0.0,
            1.0,
            &breaks,
            panels,
            row,
        )
    }

    #[test]
    fn polygon_coefficients_match_a_quadrature_by_rows() {
        // Normals at many angles (none on an axis: the rows' breaks need n1 ≠ 0, and n0 ≠ 0 picks a
        // side), offsets across the square, frequencies up to 40 per axis. The rows' integrand turns
        // at most |k2| + |k1 n1 / n0| times; 8 + 4 panels per turn put that reference at rounding
        // (checked against twice the panels). Both sides sum about ten terms of size up to 1/(2π|k|)
        // with phases rounded to |k|₁ · 2.2e-16, so they may differ by a few 1e-16; 1e-14 leaves room
        // for that and no more.
        let mut worst: f64 = 0.0;
        for (t, c) in [
            (30.0, 0.6),
            (100.0, 0.2),
            (-63.0, 0.1),
            (171.0, -0.3),
            (45.0, 1.2),
        ] {
            let t = f64::to_radians(t);
            let n = [t.cos(), t.sin()];
            let poly = clip_square(n, c);
            for k in [
                [1, 0],
                [0, 1],
                [2, -3],
                [17, 5],
                [-40, 23],
                [0, -40],
                [39, 40],
            ] {
                let turns = (k[1] as f64).abs() + (k[0] as f64 * n[1] / n[0]).abs();
                let panels = 8 + (4.0 * turns).ceil() as usize;
                let reference = by_rows(n, c, k, panels);
                assert!((reference - by_rows(n, c, k, 2 * panels)).norm() < 1e-15);
                worst = worst.max((fourier(&poly, k) - reference).norm());
            }
        }
        assert!(worst < 1e-14, "largest difference {worst:e}");
    }

    #[test]
    fn vertex_and_midpoint_forms_agree() {
        // The vertex form against the midpoint form of every edge, on the polygons of sheared steps
        // (the fan's) up to frequencies of 1e4. A phase k·v carries rounding of about |k|₁ u
        // (u = 1.1e-16), and the vertex form divides a difference of phasors by k·d ≥ 1/8: each edge
        // term's error is at most (flux / |k·d|) · 2π |k|₁ u / (4π²|k|²) ≤ (16/π) u ≈ 5.6e-16
        // (flux ≤ |k||d|, |d| ≤ √2, |k|₁ ≤ √2 |k|), the midpoint form's about 2.2e-16; over five
        // edges the sums may differ by 4e-15 and no more.
        let mut worst: f64 = 0.0;
        for s in [-0.7, -0.31, 0.0, 0.2, 0.5, 0.93] {
            for c in [0.13, 0.5, 0.77] {
                let polygon = clip_square([1.0, s], c);
                let poly = polygon.vertices();
                for k in [
                    [1, 1],
                    [3, -8],
                    [250, 7],
                    [-1000, 333],
                    [10_000, -2],
                    [5, 9_999],
                ] {
                    let (k1, k2) = (k[0] as f64, k[1] as f64);
                    let midpoint: Complex64 = (0..poly.len())
                        .map(|i| {
                            let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                            let flux = k1 * (q[1] - p[1]) - k2 * (q[0] - p[0]);
                            midpoint_term(p, q, k1, k2, flux)
                        })
                        .sum::<Complex64>()
                        * Complex64::new(0.0, 1.0 / (2.0 * PI * (k1 * k1 + k2 * k2)));
                    worst = worst.max((fourier(&polygon, k) - midpoint).norm());
                }
            }
        }
        assert!(worst < 4e-15, "largest difference {worst:e}");
    }

    #[test]
    fn half_square_matches_1d_integral() {
        let polygon = clip_square([1.0, 0.0], 0.3);
        assert!((area(polygon.vertices()) - 0.3).abs() < 1e-15);
        for k1 in [-3i64, 1, 5] {
            let f = fourier(&polygon, [k1, 0]);
            // ∫_0^0.3 exp(−2πi k x) dx = (1 − exp(−2πi k 0.3)) / (2πi k)
            let e = Complex64::new(0.0, -2.0 * PI * k1 as f64 * 0.3).exp();
            let exact = (Complex64::new(1.0, 0.0) - e) / Complex64::new(0.0, 2.0 * PI * k1 as f64);
            assert!((f - exact).norm() < 1e-15);
            assert!(fourier(&polygon, [k1, 2]).norm() < 1e-15);
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
