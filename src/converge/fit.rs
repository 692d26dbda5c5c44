//! Power-law fits `y = A N^slope` by weighted least squares on `(ln N, ln y)`.

use crate::error::{Error, Result};

/// A fitted power law `y ≈ A N^slope` (its exponent and the exponent's errors; `A` is not kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlopeFit {
    /// The exponent.
    pub slope: f64,
    /// Standard error of `slope`, from the points' standard errors, inflated by `sqrt(χ²/dof)` when the
    /// points scatter more than their errors allow (a curved, pre-asymptotic run).
    pub stderr: f64,
    /// 95% confidence interval of the slope: `slope ± 1.96 stderr` from the points' standard errors
    /// when `χ²/dof ≤ 1`, or, when `χ²/dof > 1` inflated `stderr`, `slope ± t stderr` with Student's
    /// `t` of the fit's `dof = points − 2` degrees of freedom ([`crate::stats::student_t_95`]: 4.30
    /// for 4 points), since the scale `sqrt(χ²/dof)` is then estimated from those few residuals. The
    /// switch is a jump: points that scatter just beyond their errors get the wider interval.
    pub ci95: (f64, f64),
    /// `χ² / dof` of the fit (NaN-free: 0 with two points).
    pub chi2_per_dof: f64,
    /// False when some point's relative standard error `se / y` is not above its floor (the
    /// `floor` of [`fit_power_law`]: what the values' own errors, of the method or of rounding, could
    /// give with no spread between realizations; 0 included): its weight would come from those errors,
    /// not from the realizations, so the slope is fitted with equal weights and `stderr`, `ci95` and
    /// `chi2_per_dof` mean nothing (they are set to 0, the interval to zero width). Read them through [`SlopeFit::interval`] and
    /// [`SlopeFit::chi2`], which say so, and show "—".
    pub errors_defined: bool,
}

impl SlopeFit {
    /// The 95% interval of the slope, or `None` when the points' errors do not define one.
    pub fn interval(&self) -> Option<(f64, f64)> {
        self.errors_defined.then_some(self.ci95)
    }

    /// `χ² / dof`, or `None` when it is undefined: no degree of freedom (two points) or points'
    /// errors that define no weights.
    pub fn chi2(&self, points: usize) -> Option<f64> {
        (self.errors_defined && points > 2).then_some(self.chi2_per_dof)
    }

    /// The interval as `[lo, hi]` with `decimals` digits, or `[—]` when it is undefined.
    pub fn interval_text(&self, decimals: usize) -> String {
        match self.interval() {
            Some((lo, hi)) => format!("[{lo:.decimals$}, {hi:.decimals$}]"),
            None => "[—]".into(),
        }
    }
}

/// Fits `y ∝ N^slope` to values `y` with standard errors `se`, weighting `ln y` by `(y / se)²`
/// (delta method). Needs at least two distinct positive `N` and positive finite `y`.
///
/// `floor[i]` is the relative standard error (`se / y`, dimensionless) that point `i` could show from
/// the errors of its own values alone (the spectrum method's tolerance, f64 rounding) if its
/// realizations did not differ at all; each caller derives it from its arithmetic. A standard error
/// not above its floor (0 included) defines no weight: the slope is then fitted with equal weights
/// and its interval and `χ²` are undefined ([`SlopeFit::errors_defined`] is false).
pub fn fit_power_law(n: &[f64], y: &[f64], se: &[f64], floor: &[f64]) -> Result<SlopeFit> {
    if n.len() != y.len() || n.len() != se.len() || n.len() != floor.len() || n.len() < 2 {
        return Err(Error::Usage(
            "a slope fit needs at least two values of N".into(),
        ));
    }
    if let Some(i) =
        (0..n.len()).find(|&i| !(n[i] > 0.0 && y[i] > 0.0 && y[i].is_finite() && se[i].is_finite()))
    {
        return Err(Error::Numerical(format!(
            "cannot fit a slope through N = {}, value {}: log-log fits need positive finite values",
            n[i], y[i]
        )));
    }
    let x: Vec<f64> = n.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let errors_defined = (0..n.len()).all(|i| se[i] / y[i] > floor[i]);
    let w: Vec<f64> = y
        .iter()
        .zip(se)
        .map(|(y, s)| {
            if errors_defined {
                let rel = s / y;
                1.0 / (rel * rel)
            } else {
                1.0
            }
        })
        .collect();
    let sw: f64 = w.iter().sum();
    let sx: f64 = w.iter().zip(&x).map(|(w, x)| w * x).sum();
    let sy: f64 = w.iter().zip(&ly).map(|(w, y)| w * y).sum();
    let mx = sx / sw;
    let my = sy / sw;
    let sxx: f64 = w.iter().zip(&x).map(|(w, x)| w * (x - mx).powi(2)).sum();
    if x.iter().all(|&v| v == x[0]) || sxx <= 0.0 {
        return Err(Error::Usage(
            "a slope fit needs at least two different values of N".into(),
        ));
    }
    let sxy: f64 = (0..x.len())
        .map(|i| w[i] * (x[i] - mx) * (ly[i] - my))
        .sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let chi2: f64 = (0..x.len())
        .map(|i| w[i] * (ly[i] - intercept - slope * x[i]).powi(2))
        .sum();
    let dof = x.len() as f64 - 2.0;
    let (chi2_per_dof, stderr) = if errors_defined {
        let chi2_per_dof = if dof > 0.0 { chi2 / dof } else { 0.0 };
        (
            chi2_per_dof,
            (1.0 / sxx).sqrt() * chi2_per_dof.max(1.0).sqrt(),
        )
    } else {
        (0.0, 0.0)
    };
    let quantile = if chi2_per_dof > 1.0 {
        crate::stats::student_t_95(x.len() - 2)
    } else {
        crate::stats::NORMAL_95
    };
    Ok(SlopeFit {
        slope,
        stderr,
        ci95: (slope - quantile * stderr, slope + quantile * stderr),
        chi2_per_dof,
        errors_defined,
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
        let f = fit_power_law(&n, &y, &se, &[1e-15; 4]).unwrap();
        assert!((f.slope + 1.5).abs() < 1e-12);
        // Relative errors of 0.1 on ln y: se(slope) = 0.1 / sqrt(Σ (ln N − mean)²).
        let x: Vec<f64> = n.iter().map(|n| n.ln()).collect();
        let m = x.iter().sum::<f64>() / 4.0;
        let want = 0.1 / x.iter().map(|x| (x - m).powi(2)).sum::<f64>().sqrt();
        assert!((f.stderr - want).abs() < 1e-12);
    }

    /// A standard error of 0 (two realizations that agree by chance), or one not above its floor,
    /// gives no weight: the slope is still fitted, but the interval and chi2 are undefined, not
    /// zero-width or astronomically large.
    #[test]
    fn a_zero_standard_error_leaves_the_interval_undefined() {
        let n = [1.0, 4.0, 16.0];
        let y = [0.1, 0.01, 2e-3];
        let floor = [1e-12; 3];
        let f = fit_power_law(&n[..2], &y[..2], &[0.0, 0.0], &floor[..2]).unwrap();
        assert!((f.slope - 0.1f64.ln() / 4f64.ln()).abs() < 1e-12);
        assert!(!f.errors_defined);
        assert_eq!(f.interval(), None);
        assert_eq!(f.chi2(2), None);
        assert_eq!(f.interval_text(3), "[—]");
        let f = fit_power_law(&n, &y, &[0.0, 1e-3, 1e-4], &floor).unwrap();
        assert!(!f.errors_defined && f.interval().is_none() && f.chi2(3).is_none());
        assert!(f.slope.is_finite() && f.chi2_per_dof == 0.0 && f.stderr == 0.0);
        // A relative error at or below its floor is no weight either; just above it, it is one.
        let f = fit_power_law(&n, &y, &[1e-13, 1e-3, 1e-4], &floor).unwrap();
        assert!(f.interval().is_none());
        let f = fit_power_law(&n, &y, &[1e-13, 1e-3, 1e-4], &[1e-12, 0.0, 0.0]).unwrap();
        assert!(f.interval().is_none());
        let f = fit_power_law(&n, &y, &[1e-13, 1e-3, 1e-4], &[0.9e-12, 0.0, 0.0]).unwrap();
        assert!(f.interval().is_some());
        // Honest errors define both.
        let f = fit_power_law(&n, &y, &[1e-2, 1e-3, 1e-4], &floor).unwrap();
        assert!(f.errors_defined);
        let (lo, hi) = f.interval().unwrap();
        assert!(lo < f.slope && f.slope < hi);
        assert!(f.chi2(3).is_some_and(f64::is_finite));
        assert_eq!(f.chi2(2), None);
    }

    /// When the points scatter more than their errors allow, the scale `sqrt(χ²/dof)` comes from
    /// `points − 2` residuals, and the 95 % interval takes Student's t of that many degrees of freedom
    /// (4.30 for four points, where 1.96 covered about 81 %); points within their errors keep 1.96.
    #[test]
    fn a_scattered_fit_widens_its_interval_by_students_t() {
        let n = [16.0, 64.0, 256.0, 1024.0];
        let se = [1e-3; 4];
        // ln y off a line by ±0.05 (50 standard errors): χ²/dof ≫ 1.
        let y: Vec<f64> = n
            .iter()
            .zip([0.05, -0.05, -0.05, 0.05])
            .map(|(n, d): (&f64, f64)| (n.powf(-1.5).ln() + d).exp())
            .collect();
        let se_abs: Vec<f64> = y.iter().zip(se).map(|(y, s)| y * s).collect();
        let f = fit_power_law(&n, &y, &se_abs, &[0.0; 4]).unwrap();
        assert!(f.chi2_per_dof > 100.0, "{f:?}");
        let half = f.ci95.1 - f.slope;
        assert!((half / f.stderr - 4.302_652_7).abs() < 1e-6, "{f:?}");
        // On the line, within the errors: the normal quantile.
        let y: Vec<f64> = n.iter().map(|n| n.powf(-1.5)).collect();
        let se_abs: Vec<f64> = y.iter().map(|y| y * 1e-3).collect();
        let f = fit_power_law(&n, &y, &se_abs, &[0.0; 4]).unwrap();
        assert!(f.chi2_per_dof <= 1.0, "{f:?}");
        assert!(
            ((f.ci95.1 - f.slope) / f.stderr - crate::stats::NORMAL_95).abs() < 1e-12,
            "{f:?}"
        );
    }

    #[test]
    fn bad_values_are_reported() {
        let floor = [1e-12; 2];
        assert!(fit_power_law(&[16.0], &[1.0], &[0.1], &floor[..1]).is_err());
        assert!(fit_power_law(&[16.0, 64.0], &[1.0, 0.0], &[0.1, 0.1], &floor).is_err());
        assert!(fit_power_law(&[16.0, 16.0], &[1.0, 2.0], &[0.1, 0.1], &floor).is_err());
        assert!(fit_power_law(&[16.0, 64.0], &[1.0, 2.0], &[0.1, 0.1], &floor[..1]).is_err());
    }
}
