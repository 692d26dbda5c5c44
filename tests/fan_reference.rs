//! The fan integrand's Fourier coefficients against an independent reference.
//!
//! The crate computes `f̂(k)` of `fan:s0,s1,c` as a quadrature over the shear `s` of the exact
//! coefficients of the steps `H(c − x1 − s x2)`. The reference here takes the other order: for each
//! `x2 = u` the fan is a clamped ramp in `x1`, whose integral against `exp(−2πi k1 x1)` is closed-form;
//! that is then integrated over `u` by Gauss–Legendre on pieces cut at the ramp's kinks and graded
//! towards them. The two share no code (the rule below is computed here, not taken from `quad`).
//!
//! The inner integral. For `u > 0` let `w = (s1 − s0) u`, `a = c − s0 u` and `b = a − w = c − s1 u`:
//! `f(x1, u) = 1` for `x1 ≤ b`, `(a − x1) / w` for `b ≤ x1 ≤ a`, 0 beyond. With `α = 2π k1` and, on
//! `[p, q]` (`L = q − p`, `z = iαL`),
//!
//! ```text
//! ∫_p^q e^{−iαx} dx         = e^{−iαp} L  E1(z),   E1(z) = (1 − e^{−z}) / z        = Σ_n (−z)^n / (n+1)!
//! ∫_p^q (x − p) e^{−iαx} dx = e^{−iαp} L² E2(z),   E2(z) = (1 − e^{−z}(1 + z)) / z² = Σ_n (−z)^n (n+1)/(n+2)!
//! ```
//!
//! (substitute `x = p + Lt`; the series come from expanding `e^{−zt}` under `∫_0^1 t^j dt`), the
//! inner integral is `J0(0, B) + [(a − p) J0(p, q) − J1(p, q)] / w` with `B = clamp(b, 0, 1)`,
//! `p = max(b, 0)`, `q = min(a, 1)` (the ramp term only when `p < q`). Both terms are `O(L)` with
//! `L ≤ w` and `a − p ≤ w`, so a narrow ramp loses nothing; the series is used for `|z| < 1`, where the
//! closed forms would cancel, and the closed forms elsewhere (their rounding is then a few `u`).
//!
//! The outer integral. `g(u)` is analytic between the `u` where `a` or `b` crosses 0 or 1
//! (`c/s`, `(c − 1)/s` for `s = s0, s1`), and near them (and near 0 for a wide fan, where `f` goes like
//! `1/u`) varies on the scale of the distance to them. So `[0, 1]` is cut there and at `β ± 2^−j`,
//! `j ≤ 40`, around each such `β` (and 0, 1): on each piece the nearest singularity is at least its own
//! width away, where an `m`-point rule converges like `(3 + √8)^{−2m}`. The `2^−40`-wide pieces at the
//! kinks are integrated like the others. Each piece gets panels by the phase its terms turn through
//! (`|k1|` times the distance `a` and `b` move within `[0, 1]`, plus `|k2|` times its width).
//!
//! The reference's error is estimated a posteriori as the difference between that rule and the same
//! with twice the panels, plus the rounding of its sum; the crate's coefficients must agree with it
//! within their documented bound (`Integrand::fourier_error`) plus that estimate.

use anisospec::integrands::shapes::Fan;
use anisospec::integrands::Integrand;
use rustfft::num_complex::Complex64;
use std::f64::consts::{PI, TAU};

/// Unit roundoff of f64.
const U: f64 = f64::EPSILON / 2.0;

/// Gauss–Legendre nodes and weights on `[−1, 1]`: Newton's method on the three-term recurrence of
/// `P_m`, from the usual cosine guesses.
fn gauss_legendre(m: usize) -> Vec<(f64, f64)> {
    (0..m)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (m as f64 + 0.5)).cos();
            loop {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=m {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                let dp = m as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    return (x, 2.0 / ((1.0 - x * x) * dp * dp));
                }
            }
        })
        .collect()
}

/// `(E1(z), E2(z))` for `z = i y` (see the module comment).
fn e1_e2(y: f64) -> (Complex64, Complex64) {
    let z = Complex64::new(0.0, y);
    if y.abs() < 1.0 {
        // |z|^n/(n+1)! < 2^−60 by n = 20.
        let (mut e1, mut e2) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
        let mut term = Complex64::new(1.0, 0.0); // (−z)^n / n!
        for n in 0..24 {
            let nf = n as f64;
            e1 += term / (nf + 1.0);
            e2 += term / (nf + 2.0);
            term *= -z / (nf + 1.0);
        }
        (e1, e2)
    } else {
        let ez = (-z).exp();
        ((1.0 - ez) / z, (1.0 - ez * (1.0 + z)) / (z * z))
    }
}

/// `∫_0^1 f(x1, u) e^{−2πi k1 x1} dx1` for `u > 0`.
fn inner(s0: f64, s1: f64, c: f64, u: f64, k1: i64) -> Complex64 {
    let alpha = TAU * k1 as f64;
    let w = (s1 - s0) * u;
    let a = c - s0 * u;
    let b = a - w;
    let phase = |p: f64| Complex64::from_polar(1.0, -alpha * p);
    let big_b = b.clamp(0.0, 1.0);
    let mut g = phase(0.0) * big_b * e1_e2(alpha * big_b).0;
    let (p, q) = (b.max(0.0), a.min(1.0));
    if p < q {
        let l = q - p;
        let (e1, e2) = e1_e2(alpha * l);
        g += phase(p) * ((a - p) * l * e1 - l * l * e2) / w;
    }
    g
}

/// The reference `f̂(k)` with `refine` times the panels, with `Σ |w g|` over its nodes and their
/// number (for the rounding bound of the sum).
fn reference(s0: f64, s1: f64, c: f64, k: [i64; 2], refine: usize) -> (Complex64, f64, usize) {
    let rule = gauss_legendre(12);
    let mut centres = vec![0.0, 1.0];
    for s in [s0, s1] {
        if s != 0.0 {
            centres.extend(
                [c / s, (c - 1.0) / s]
                    .into_iter()
                    .filter(|&v| v > 0.0 && v < 1.0),
            );
        }
    }
    let mut cuts = centres.clone();
    for &beta in &centres {
        for j in 1..=40 {
            let d = 2f64.powi(-j);
            cuts.extend(
                [beta - d, beta + d]
                    .into_iter()
                    .filter(|&v| v > 0.0 && v < 1.0),
            );
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let clamp = |x: f64| x.clamp(0.0, 1.0);
    let (mut sum, mut abs, mut nodes) = (Complex64::new(0.0, 0.0), 0.0, 0);
    for piece in cuts.windows(2) {
        let (lo, hi) = (piece[0], piece[1]);
        let moved = |s: f64| (clamp(c - s * hi) - clamp(c - s * lo)).abs();
        let turns = k[0].unsigned_abs() as f64 * (moved(s0) + moved(s1))
            + k[1].unsigned_abs() as f64 * (hi - lo);
        let panels = refine * (1 + (2.0 * turns).ceil() as usize);
        let h = (hi - lo) / panels as f64;
        for p in 0..panels {
            let (mid, half) = (lo + (p as f64 + 0.5) * h, 0.5 * h);
            for &(x, wt) in &rule {
                let u = mid + half * x;
                let term = inner(s0, s1, c, u, k[0])
                    * Complex64::from_polar(1.0, -TAU * k[1] as f64 * u)
                    * (wt * half);
                sum += term;
                abs += term.norm();
                nodes += 1;
            }
        }
    }
    (sum, abs, nodes)
}

/// The crate's coefficients of fans over wide, narrow, negative and straddling shear ranges, with
/// offsets near the ends of their ranges, agree with the reference within the crate's documented
/// error plus the reference's own (its change under twice the panels, and the rounding of its sum:
/// each term within `64u` of its value — a handful of complex products, exponentials and the series
/// — and recursive summation within `(n − 1) u Σ|term|`).
#[test]
fn fan_coefficients_match_an_independent_reference() {
    let cases: [(f64, f64, Option<f64>); 9] = [
        (0.3, 0.7, None),
        (-1e6, 1e6, None),
        (-0.9, -0.2, None),
        (-0.5, 0.5, Some(0.01)),
        (0.0, 1000.0, Some(1e-3)),
        (0.4, 0.4 + 1e-9, None),
        (0.3, 0.7, Some(0.999)),
        (0.3, 0.7, Some(1.699)),
        (-2.0, 3.0, Some(2.5)),
    ];
    let ks = [-24i64, -7, -1, 0, 1, 5, 24];
    let (mut worst, mut worst_own): (f64, f64) = (0.0, 0.0);
    for (s0, s1, c) in cases {
        let fan = Fan::new(s0, s1, c).unwrap();
        let c = c.unwrap_or(0.5 * (1.0 + 0.5 * (s0 + s1)));
        for k1 in ks {
            for k2 in ks {
                if (k1, k2) == (0, 0) {
                    continue;
                }
                let (coarse, _, _) = reference(s0, s1, c, [k1, k2], 1);
                let (fine, abs, nodes) = reference(s0, s1, c, [k1, k2], 2);
                let rounding = (nodes as f64 + 64.0) * U * abs;
                let own = (fine - coarse).norm() + rounding;
                let got = fan.fourier(&[k1, k2]).unwrap();
                let diff = (got - fine).norm();
                worst = worst.max(diff);
                worst_own = worst_own.max(own);
                assert!(
                    diff <= fan.fourier_error() + own,
                    "fan({s0}, {s1}, c={c}) k=({k1}, {k2}): crate {got} vs reference {fine} \
                     (differ by {diff:e}; reference error {own:e})"
                );
            }
        }
    }
    eprintln!(
        "largest |crate − reference| = {worst:e}, largest reference error estimate {worst_own:e}"
    );
}
