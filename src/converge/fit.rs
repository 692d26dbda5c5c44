//! Power-law fits `y = A N^slope` by weighted least squares on `(ln N, ln y)`.

use crate::error::{Error, Result};

/// A fitted power law `y ≈ exp(intercept) · N^slope`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlopeFit {
    /// The exponent.
    pub slope: f64,
    /// Standard error of `slope`, from the points' standard errors, inflated by `sqrt(χ²/dof)` when the
    /// points scatter more than their errors allow (a curved, pre-asymptotic run).
    pub stderr: f64,
    /// `ln A`.
    pub intercept: f64,
    /// 95% confidence interval of the slope: `slope ± 1.96 stderr`.
    pub ci95: (f64, f64),
    /// `χ² / dof` of the fit (NaN-free: 0 with two points).
    pub chi2_per_dof: f64,
}

/// Fits `y ∝ N^slope` to values `y` with standard errors `se`, weighting `ln y` by `(y / se)²`
/// (delta method). Needs at least two distinct positive `N` and positive finite `y`; a zero standard
/// error is replaced by `1e-12 y` (a point known exactly).
pub fn fit_power_law(n: &[f64], y: &[f64], se: &[f64]) -> Result<SlopeFit> {
    if n.len() != y.len() || n.len() != se.len() || n.len() < 2 {
        return Err(Error::Usage("a slope fit needs at least two values of N".into()));
    }
    if let Some(i) = (0..n.len()).find(|&i| !(n[i] > 0.0 && y[i] > 0.0 && y[i].is_finite() && se[i].is_finite())) {
        return Err(Error::Numerical(format!(
            "cannot fit a slope through N = {}, value {}: log-log fits need positive finite values",
            n[i], y[i]
        )));
    }
    let x: Vec<f64> = n.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let w: Vec<f64> = y
        .iter()
        .zip(se)
        .map(|(y, s)| {
            let rel = (s / y).max(1e-12);
            1.0 / (rel * rel)
        })
        .collect();
    let sw: f64 = w.iter().sum();
    let sx: f64 = w.iter().zip(&x).map(|(w, x)| w * x).sum();
    let sy: f64 = w.iter().zip(&ly).map(|(w, y)| w * y).sum();
    let mx = sx / sw;
    let my = sy / sw;
    let sxx: f64 = w.iter().zip(&x).map(|(w, x)| w * (x - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return Err(Error::Usage("a slope fit needs at least two different values of N".into()));
    }
    let sxy: f64 = (0..x.len()).map(|i| w[i] * (x[i] - mx) * (ly[i] - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let chi2: f64 = (0..x.len()).map(|i| w[i] * (ly[i] - intercept - slope * x[i]).powi(2)).sum();
    let dof = x.len() as f64 - 2.0;
    let chi2_per_dof = if dof > 0.0 { chi2 / dof } else { 0.0 };
    let stderr = (1.0 / sxx).sqrt() * chi2_per_dof.max(1.0).sqrt();
    Ok(SlopeFit {
        slope,
        stderr,
        intercept,
        ci95: (slope - 1.96 * stderr, slope + 1.96 * stderr),
        chi2_per_dof,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_power_law_is_recovered() {
        let n = [16.0, 64.0, 256.0, 1024.0];
        let y: Vec<f64> = n.iter().map(|n: &f64| 3.0 * n.powf(-1.5)).collect();
        let se: Vec<f64> = y.iter().map(|y| 0.1 * y).collect();
        let f = fit_power_law(&n, &y, &se).unwrap();
        assert!((f.slope + 1.5).abs() < 1e-12);
        assert!((f.intercept - 3f64.ln()).abs() < 1e-10);
        // Relative errors of 0.1 on ln y: se(slope) = 0.1 / sqrt(Σ (ln N − mean)²).
        let x: Vec<f64> = n.iter().map(|n| n.ln()).collect();
        let m = x.iter().sum::<f64>() / 4.0;
        let want = 0.1 / x.iter().map(|x| (x - m).powi(2)).sum::<f64>().sqrt();
        assert!((f.stderr - want).abs() < 1e-12);
    }

    #[test]
    fn bad_values_are_reported() {
        assert!(fit_power_law(&[16.0], &[1.0], &[0.1]).is_err());
        assert!(fit_power_law(&[16.0, 64.0], &[1.0, 0.0], &[0.1, 0.1]).is_err());
        assert!(fit_power_law(&[16.0, 16.0], &[1.0, 2.0], &[0.1, 0.1]).is_err());
    }
}
