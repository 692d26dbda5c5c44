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

#[cfg(test)]
mod tests {
    use super::*;

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
}
