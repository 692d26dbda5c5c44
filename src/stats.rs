//! Small summary statistics shared by the estimators, and the bound on how many realizations they
//! average.

use crate::error::{Error, Result};

/// The most realizations (independent sets) any study averages: `--realizations` of `spectrum`,
/// `converge`, `variance` and `gallery`, and `realizations` / `spectra_realizations` of a `compare`
/// config. A standard error shrinks as `1/sqrt(R)`: at `R = 10^6` an MSE's relative standard error is
/// about `sqrt(2/R)` ≈ 0.14 % (for Gaussian errors), far below any gap between samplers a study
/// reports, and a thousand times the paper-scale preset (`compare --full`, `R = 1000`). Above it a
/// mistyped count would run for days (a spectrum or a prediction costs one transform per realization)
/// or allocate gigabytes of per-realization results before any output.
pub const MAX_REALIZATIONS: usize = 1_000_000;

/// Checks a realization count set by `name` (e.g. `--realizations` or `realizations =`, a config key)
/// against [`MAX_REALIZATIONS`]; the message writes `{name} {count}`. Lower bounds (1 for a mean, 2 for
/// a standard error) are checked by each study.
pub fn check_realizations(name: &str, count: usize) -> Result<()> {
    if count > MAX_REALIZATIONS {
        return Err(Error::Usage(format!(
            "{name} {count} is above the largest realization count, {MAX_REALIZATIONS} (its standard error, about 0.1 % of an MSE, is already far below any difference a study reports, and more would run for days); lower it, e.g. {name} 1000"
        )));
    }
    Ok(())
}

/// The two-sided 95 % quantile of the standard normal distribution.
pub const NORMAL_95: f64 = 1.959_963_984_540_054;

/// The two-sided 95 % quantile of Student's t with `dof ≥ 1` degrees of freedom: the `t` with
/// `P(|T| ≤ t) = 0.95`, from 12.706 at one degree of freedom down to 1.960 as `dof` grows. A scale
/// estimated from `dof` residuals (a fit's `sqrt(χ²/dof)`) needs it instead of the normal 1.96 for a
/// 95 % interval.
///
/// `P(|T| ≤ t)` is the closed form for integer `dof` (Abramowitz & Stegun 26.7.3–4, in
/// `θ = atan(t / sqrt(dof))`), solved by bisection to 1e-12; from 1000 degrees of freedom on the
/// normal quantile is within 3e-3 of it and is returned.
///
/// Panics if `dof == 0`.
pub fn student_t_95(dof: usize) -> f64 {
    assert!(dof > 0, "Student's t needs at least one degree of freedom");
    if dof >= 1000 {
        return NORMAL_95;
    }
    let nu = dof as f64;
    // P(|T| <= t): a finite series in cos²θ, the terms' coefficients built up one ratio at a time.
    let central = |t: f64| {
        let theta = (t / nu.sqrt()).atan();
        let (s, c) = theta.sin_cos();
        let c2 = c * c;
        let (mut sum, mut term) = (1.0, 1.0);
        if dof % 2 == 1 {
            // (2/π)[θ + sinθ cosθ (1 + (2/3) cos²θ + … + (2·4⋯(ν−3))/(1·3⋯(ν−2)) cos^(ν−3)θ)].
            if dof == 1 {
                return 2.0 * theta / std::f64::consts::PI;
            }
            for k in (2..dof - 1).step_by(2) {
                term *= k as f64 / (k + 1) as f64 * c2;
                sum += term;
            }
            2.0 / std::f64::consts::PI * (theta + s * c * sum)
        } else {
            // sinθ [1 + (1/2) cos²θ + (1·3)/(2·4) cos⁴θ + … + (1·3⋯(ν−3))/(2·4⋯(ν−2)) cos^(ν−2)θ].
            for k in (1..dof - 1).step_by(2) {
                term *= k as f64 / (k + 1) as f64 * c2;
                sum += term;
            }
            s * sum
        }
    };
    let (mut lo, mut hi) = (NORMAL_95, 13.0);
    while hi - lo > 1e-12 {
        let mid = 0.5 * (lo + hi);
        if central(mid) < 0.95 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The sample mean of `xs` and its standard error `sqrt(s² / n)`, where `s²` is the unbiased sample
/// variance (divisor `n − 1`). Sums run in iteration order. Needs `n ≥ 2`: one value gives a NaN
/// standard error and no value a NaN mean; callers check their counts first.
pub fn mean_and_stderr<I>(xs: I) -> (f64, f64)
where
    I: IntoIterator<Item = f64>,
    I::IntoIter: Clone,
{
    let xs = xs.into_iter();
    let n = xs.clone().count() as f64;
    let mean = xs.clone().sum::<f64>() / n;
    let var = xs.map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A streaming mean and standard error (Welford's update): values are pushed one at a time, in the
/// caller's order, with `O(1)` memory. [`Welford::mean`] and [`Welford::stderr`] are those of
/// [`mean_and_stderr`] over the same values (unbiased variance, divisor `n − 1`), up to rounding: the
/// two differ by at most the bound the tests derive from f64 rounding. The same pushes in the same
/// order give the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Welford {
    count: usize,
    mean: f64,
    /// Sum of squared deviations from the running mean.
    m2: f64,
}

impl Welford {
    /// Adds one value.
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// The mean of the values pushed (0 before any).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The standard error of the mean, `sqrt(s² / n)` with the unbiased `s²`: NaN with fewer than two
    /// values.
    pub fn stderr(&self) -> f64 {
        let n = self.count as f64;
        (self.m2 / (n - 1.0) / n).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against scipy.stats.t.ppf(0.975, ν) (SciPy 1.x, printed to 17 digits).
    #[test]
    fn student_t_quantiles_match_the_tables() {
        for (dof, t) in [
            (1, 12.706_204_736_174_694),
            (2, 4.302_652_729_749_462),
            (3, 3.182_446_305_283_708),
            (4, 2.776_445_105_197_793),
            (5, 2.570_581_835_636_315),
            (10, 2.228_138_851_986_274),
            (30, 2.042_272_456_301_238),
            (120, 1.979_930_405_082_44),
            (999, 1.962_341_461_133_449),
        ] {
            let got = student_t_95(dof);
            assert!((got - t).abs() < 1e-10, "dof {dof}: {got} against {t}");
        }
        assert_eq!(student_t_95(1000), 1.959_963_984_540_054);
    }

    #[test]
    fn mean_and_stderr_of_a_small_sample() {
        // Mean 2.5, s² = (2.25 + 0.25 + 0.25 + 2.25) / 3 = 5/3, stderr = sqrt(5/12).
        let (m, se) = mean_and_stderr([1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-15);
        let (m, se) = mean_and_stderr(vec![7.0; 5]);
        assert_eq!((m, se), (7.0, 0.0));
    }

    #[test]
    fn one_value_has_no_stderr() {
        let (m, se) = mean_and_stderr([3.0]);
        assert_eq!(m, 3.0);
        assert!(se.is_nan());
    }

    /// Welford's update against the two-pass [`mean_and_stderr`], on samples spread about 0 and about
    /// a large offset (where a one-pass `Σx² − n·mean²` would lose every digit).
    ///
    /// Bounds, first order in the unit roundoff `u = 2^−53`, with `M = max |x|`, the range
    /// `D = max x − min x` and `n` values:
    /// - two-pass mean: recursive summation errs by at most `(n − 1) u Σ|x| ≤ (n − 1) n u M`, the
    ///   division by `n` adds `u |mean|`: at most `n u M` on the mean.
    /// - Welford's mean: `m_k = m_{k−1}(1 − 1/k) + x_k/k` damps an earlier error, and step `k` adds at
    ///   most `2u |x_k − m_{k−1}| / k + u |m_k| ≤ 2uD/k + uM`: `E_k ≤ u (kM + 2D (1 + ln k))`.
    /// - so the means differ by at most `u (2nM + 2D (1 + ln n))`.
    /// - two-pass `Q = Σ (x − m̂)²`: each term errs by `3u` relative, the sum by `(n − 1) u`, and the
    ///   mean's error `e` adds `n e²` (`Σ (x − m) = 0`): at most `(n + 2) u Q + n e²`.
    /// - Welford's `Q`: each term `δ_k (x_k − m_k) ≥ 0` errs by `3u` relative and the sum by
    ///   `(n − 1) u`; the running means' errors enter each term through both factors, each at most `D`
    ///   (a running mean lies within the range): at most `(n + 2) u Q + Σ_k 2D E_k`.
    /// - the standard error `sqrt(Q / (n − 1) / n)` then differs by at most half the relative error
    ///   of `Q`, plus `2u` for each method's divisions and square root.
    #[test]
    fn welford_agrees_with_two_passes_within_rounding() {
        let u = f64::EPSILON / 2.0;
        let mut rng = crate::rng::substream(5, 0, 0);
        for (offset, spread, n) in [(0.0, 1.0, 1000usize), (1e6, 1.0, 1000), (3.0, 1e-3, 10_000)] {
            let xs: Vec<f64> = (0..n)
                .map(|_| offset + spread * (rand::Rng::random::<f64>(&mut rng) - 0.5))
                .collect();
            let (m, se) = mean_and_stderr(xs.iter().copied());
            let mut w = Welford::default();
            xs.iter().for_each(|&x| w.push(x));
            let big_m = xs.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let (lo, hi) = xs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                });
            let d = hi - lo;
            let nf = n as f64;
            let welford_mean = |k: f64| u * (k * big_m + 2.0 * d * (1.0 + k.ln()));
            let mean_bound = nf * u * big_m + welford_mean(nf);
            assert!((w.mean() - m).abs() <= mean_bound, "{} vs {m}", w.mean());
            let q = se * se * nf * (nf - 1.0);
            let e_two = nf * u * big_m;
            let welford_terms: f64 = (1..=n).map(|k| 2.0 * d * welford_mean(k as f64)).sum();
            let q_bound = 2.0 * (nf + 2.0) * u * q + nf * e_two * e_two + welford_terms;
            let se_bound = se * (0.5 * q_bound / q + 4.0 * u);
            assert!(
                (w.stderr() - se).abs() <= se_bound,
                "{} vs {se}",
                w.stderr()
            );
            // The bound is not vacuous: it is well below the stderr itself, and below the n/(n − 1)
            // change a wrong divisor would make.
            assert!(se_bound < 0.1 * se / nf, "{se_bound} vs {se}");
        }
        let mut one = Welford::default();
        one.push(3.0);
        assert_eq!(one.mean(), 3.0);
        assert!(one.stderr().is_nan());
    }
}
