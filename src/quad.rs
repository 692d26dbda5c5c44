//! Gauss–Legendre quadrature on intervals: for the integrands whose integrals or Fourier coefficients
//! have no closed form (the fan of edges), and for the NUFFT's deconvolution factors.

use std::f64::consts::PI;

/// Nodes and weights of the `m`-point Gauss–Legendre rule on `[-1, 1]`, by Newton's method on the
/// Legendre polynomial `P_m` (three-term recurrence); exact for polynomials of degree `< 2m`.
pub fn gauss_legendre(m: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(m);
    for i in 0..m {
        // Chebyshev-like initial guess for the i-th root (descending).
        let mut x = (PI * (i as f64 + 0.75) / (m as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre(m, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, d) = legendre(m, x);
        if d != 0.0 {
            dp = d;
        }
        rule.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    rule
}

/// `(P_m(x), P_m'(x))`.
fn legendre(m: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if m == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=m {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let d = m as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

/// `∫_a^b g` by the Gauss–Legendre `rule` on `panels` equal panels, with the interval first cut at the
/// `breaks` that fall inside it (where `g` has a kink, so that every panel sees a smooth function).
pub fn integrate<T, G>(
    rule: &[(f64, f64)],
    a: f64,
    b: f64,
    breaks: &[f64],
    panels: usize,
    mut g: G,
) -> T
where
    T: std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T> + Default,
    G: FnMut(f64) -> T,
{
    let mut cuts: Vec<f64> = vec![a, b];
    cuts.extend(breaks.iter().copied().filter(|&t| t > a && t < b));
    cuts.sort_by(f64::total_cmp);
    let mut total = T::default();
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let h = (hi - lo) / panels as f64;
        for p in 0..panels {
            let mid = lo + (p as f64 + 0.5) * h;
            for &(x, wt) in rule {
                total = total + g(mid + 0.5 * h * x) * (0.5 * h * wt);
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule_integrates_polynomials_exactly() {
        let rule = gauss_legendre(12);
        let wsum: f64 = rule.iter().map(|r| r.1).sum();
        assert!((wsum - 2.0).abs() < 1e-14);
        // ∫_0^2 x^23 = 2^24 / 24: degree 23 < 2·12.
        let v: f64 = integrate(&rule, 0.0, 2.0, &[], 1, |x| x.powi(23));
        let exact = 2f64.powi(24) / 24.0;
        assert!((v - exact).abs() / exact < 1e-13, "{v} vs {exact}");
    }

    #[test]
    fn odd_rule_is_exact_to_degree_2m_minus_1() {
        let rule = gauss_legendre(7);
        // Exact for degree ≤ 13: ∫_{-1}^{1} x^12 = 2/13.
        let s: f64 = rule.iter().map(|&(x, w)| w * x.powi(12)).sum();
        assert!((s - 2.0 / 13.0).abs() < 1e-15, "{s}");
        let total: f64 = rule.iter().map(|r| r.1).sum();
        assert!((total - 2.0).abs() < 1e-15);
    }

    #[test]
    fn breaks_make_kinks_exact() {
        let rule = gauss_legendre(8);
        let v: f64 = integrate(&rule, -1.0, 2.0, &[0.3], 1, |x: f64| (x - 0.3).abs());
        let exact = 0.5 * 1.3 * 1.3 + 0.5 * 1.7 * 1.7;
        assert!((v - exact).abs() < 1e-14);
    }
}
