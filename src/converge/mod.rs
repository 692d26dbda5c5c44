//! Empirical convergence (DESIGN §4): for each `N`, `R` realizations, each an independent set from the
//! sampler moved by its own random toroidal shift (and, optionally, the integrand placed at random);
//! the mean squared error against the integrand's reference integral (exact for closed forms; a
//! Monte Carlo estimate for pixels, whose squared standard error every MSE then contains on average)
//! with its standard error, the wall time, and a
//! power-law fit `MSE ∝ N^slope` with a confidence interval.
//!
//! Realization `r` at size `N` draws its points, its shift and its placement from sub-streams of
//! `rng::substream(seed, r, ·)` keyed by `N`; errors are collected in realization order and reduced
//! sequentially, so a seed gives the same bits whatever the thread count.

pub mod fit;

pub use fit::{fit_power_law, SlopeFit};

use crate::error::{Error, Result};
use crate::integrands::Integrand;
use crate::rng;
use crate::samplers::{validate_n, Sampler};
use crate::stats::mean_and_stderr;
use rand::Rng as _;
use rayon::prelude::*;
use std::time::Instant;

/// How to run a convergence study.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvergeConfig {
    /// Realizations per `N` (at least 2, for a standard error).
    pub realizations: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Move the integrand at random in each realization ([`Integrand::placed`]); each realization's
    /// error is then taken against its own placement's integral.
    pub random_placement: bool,
}

/// The measured error at one `N`.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergePoint {
    /// Points per set.
    pub n: usize,
    /// Mean squared error `mean_r (I_N,r − I)²`.
    pub mse: f64,
    /// Standard error of `mse` (sample standard deviation of the squared errors over `sqrt(R)`).
    pub mse_stderr: f64,
    /// Mean signed error `mean_r (I_N,r − I)`: near 0 for an unbiased estimator.
    pub mean_error: f64,
    /// Wall time of this `N` (sampling and integration of all realizations, on the rayon pool),
    /// seconds.
    pub seconds: f64,
    /// Median time of one estimate (generating, shifting and shearing its set, then evaluating the
    /// integrand), on one thread, seconds: the cost per pixel a renderer sees, steadier than
    /// `seconds / R` on a short batch.
    pub median_seconds: f64,
    /// Integrand evaluations made: `N · R`.
    pub evaluations: u64,
}

/// A convergence study of one sampler on one integrand.
#[derive(Clone, Debug, PartialEq)]
pub struct Convergence {
    /// Sampler name.
    pub sampler: String,
    /// Integrand name.
    pub integrand: String,
    /// One entry per requested `N`, in order.
    pub points: Vec<ConvergePoint>,
    /// `MSE ∝ N^slope` fitted over all points (`None` with fewer than two `N` or a zero MSE).
    pub fit: Option<SlopeFit>,
}

/// Checks a list of `N` and a realization count (2 to [`crate::stats::MAX_REALIZATIONS`]) shared by
/// the variance and convergence studies.
pub fn check_plan(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    ns: &[usize],
    realizations: usize,
) -> Result<()> {
    if sampler.dims() != f.dims() {
        return Err(Error::Usage(format!(
            "the sampler {} makes {}D points but the integrand {} is {}D; use a {}D sampler (e.g. padded-... for 4D) or place the integrand with @xy",
            sampler.name(),
            sampler.dims(),
            f.name(),
            f.dims(),
            f.dims()
        )));
    }
    if ns.is_empty() {
        return Err(Error::Usage(
            "--n lists no sizes; give e.g. --n 16,64,256".into(),
        ));
    }
    if realizations < 2 {
        return Err(Error::Usage(format!(
            "--realizations {realizations} gives no standard error; use at least 2 (e.g. 100)"
        )));
    }
    crate::stats::check_realizations("--realizations", realizations)?;
    for &n in ns {
        validate_n(sampler, n)?;
    }
    Ok(())
}

/// The error `I_N − I` of realization `r` at size `n`.
fn realization_error(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    n: usize,
    r: usize,
    cfg: &ConvergeConfig,
) -> f64 {
    let key = 3 * n as u64;
    let dims = sampler.dims();
    let mut shift_rng = rng::substream(cfg.seed, r as u64, key + 1);
    let shift: Vec<f64> = (0..dims).map(|_| shift_rng.random::<f64>()).collect();
    let set = sampler.generate_shifted(n, &mut rng::substream(cfg.seed, r as u64, key), &shift);
    let placed = if cfg.random_placement {
        f.placed(&mut rng::substream(cfg.seed, r as u64, key + 2))
    } else {
        None
    };
    let g: &dyn Integrand = placed.as_deref().unwrap_or(f);
    let sum: f64 = set.chunks_exact(dims).map(|p| g.eval(p)).sum();
    sum / n as f64 - g.reference().value
}

/// The mean squared error and its standard error at one `N`.
pub fn measure(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    n: usize,
    cfg: &ConvergeConfig,
) -> Result<ConvergePoint> {
    check_plan(sampler, f, &[n], cfg.realizations)?;
    let start = Instant::now();
    let (errors, mut times): (Vec<f64>, Vec<f64>) = (0..cfg.realizations)
        .into_par_iter()
        .map(|r| {
            let one = Instant::now();
            let error = realization_error(sampler, f, n, r, cfg);
            (error, one.elapsed().as_secs_f64())
        })
        .unzip();
    let seconds = start.elapsed().as_secs_f64();
    times.sort_by(f64::total_cmp);
    let median_seconds = times[times.len() / 2];
    let (mse, mse_stderr) = mean_and_stderr(errors.iter().map(|e| e * e));
    let point = ConvergePoint {
        n,
        mse,
        mse_stderr,
        mean_error: errors.iter().sum::<f64>() / errors.len() as f64,
        seconds,
        median_seconds,
        evaluations: (n * cfg.realizations) as u64,
    };
    if !point.mse.is_finite() {
        return Err(Error::Numerical(format!(
            "{} on {} at N = {n} gave a non-finite error; the integrand returned NaN or infinity",
            sampler.name(),
            f.name()
        )));
    }
    Ok(point)
}

/// Runs the study for every `N` of `ns` and fits the slope. `progress` is called after each `N`.
pub fn converge(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    ns: &[usize],
    cfg: &ConvergeConfig,
    mut progress: impl FnMut(&ConvergePoint),
) -> Result<Convergence> {
    check_plan(sampler, f, ns, cfg.realizations)?;
    let mut points = Vec::with_capacity(ns.len());
    for &n in ns {
        let p = measure(sampler, f, n, cfg)?;
        progress(&p);
        points.push(p);
    }
    let fit = fit_points(&points, cfg.realizations, f.reference().value);
    Ok(Convergence {
        sampler: sampler.name(),
        integrand: f.name(),
        points,
        fit,
    })
}

/// `MSE ∝ N^slope` fitted through measured points (`None` with fewer than two N, a zero MSE, or an
/// MSE that is rounding ([`error_within_rounding`]) at some N), each point's standard error weighed
/// against its [`rounding_floor`] for `realizations` per point and the integral `integral`. A
/// repeated N counts once (its first point): a sampler held at its largest N by several requested N
/// repeats one measurement, which must not narrow the fit's interval.
pub fn fit_points(
    points: &[ConvergePoint],
    realizations: usize,
    integral: f64,
) -> Option<SlopeFit> {
    if points
        .iter()
        .any(|p| p.mse > 0.0 && error_within_rounding(p.n, p.mse, integral))
    {
        return None;
    }
    let mut seen = std::collections::HashSet::new();
    let distinct: Vec<&ConvergePoint> = points.iter().filter(|p| seen.insert(p.n)).collect();
    let n: Vec<f64> = distinct.iter().map(|p| p.n as f64).collect();
    let v: Vec<f64> = distinct.iter().map(|p| p.mse).collect();
    let se: Vec<f64> = distinct.iter().map(|p| p.mse_stderr).collect();
    let floor: Vec<f64> = distinct
        .iter()
        .map(|p| rounding_floor(p.n, realizations, p.mse, integral))
        .collect();
    fit_power_law(&n, &v, &se, &floor).ok()
}

/// The error that f64 rounding of an estimate `Î = Σ f_j / N` at `n` points can make on its own,
/// against the integral `integral` (`I`), for an error `e` of the estimate: `(N + 1) u (|I| + |e|)`
/// (summation, division and the samples, as in [`rounding_floor`]) and `u |e|` for `Î − I`.
pub fn rounding_error(n: usize, integral: f64, error: f64) -> f64 {
    const U: f64 = f64::EPSILON / 2.0;
    let e = error.abs();
    U * ((n as f64 + 1.0) * (integral.abs() + e) + e)
}

/// Whether a point's root-mean-square error `sqrt(mse)` at `n` points is within what f64 rounding
/// of each estimate can make ([`rounding_error`]): its MSE is then rounding, not a value, and a slope
/// through it would be rounding's (e.g. a lattice on a smooth periodic integrand: 6e-31 against an
/// integral of 6.3).
pub fn error_within_rounding(n: usize, mse: f64, integral: f64) -> bool {
    let e = mse.sqrt();
    e <= rounding_error(n, integral, e)
}

/// The relative standard error (`mse_stderr / mse`) that f64 rounding alone can give a point of
/// [`measure`] at `n` points and `realizations` (`R`, at least 2) whose estimator has the same error
/// `e` in every realization (e.g. centred strata on an edge no shift moves): a standard error not
/// above it is no evidence of spread between realizations. `integral` is the integral `I` the errors
/// are taken against (for a random placement, that of the unplaced integrand).
///
/// With `u = 2^−53`, `|e| = sqrt(mse)` and a non-negative integrand (every integrand of the crate,
/// each sample taken to be within `u` of its value), an estimate `Î = Σ f_j / N` rounds by at most
/// `(N − 1) u Σ f_j / N + u Î + u Σ f_j / N ≤ (N + 1) u Î` (summation, division, the samples), and
/// `Î − I` adds `u |e|`; `I`'s own rounding is common to all realizations. With `Î ≤ |I| + |e|`, each
/// squared error is within `e² ρ` of `e²`, `ρ = 2u ((N + 1)(|I| + |e|) + |e|) / |e| + u`. Values within
/// `± ρ e²` of one another have a standard deviation of at most `ρ e² sqrt(R / (R − 1))`, and the
/// two-pass mean's rounding (at most `R u e²`) shifts every deviation alike, adding at most as much:
/// a standard error (over `sqrt(R)`) of at most `(ρ + R u) e² / sqrt(R − 1)`. The floor is that over
/// `e²`: `u (2 (N + 1)(|I| / |e| + 1) + R + 3) / sqrt(R − 1)`. It grows as the error shrinks against
/// the integral (the estimate's rounding is relative to `I`, not to `e`): about 1e-8 at `N = 4096`,
/// `R = 1000`, `I = 0.5`, `mse = 1e-12`. (A point placed within rounding of an edge by one shift and
/// not by another is not covered; that is a chance of order `N u` per realization.)
pub fn rounding_floor(n: usize, realizations: usize, mse: f64, integral: f64) -> f64 {
    const U: f64 = f64::EPSILON / 2.0;
    let (n, r) = (n as f64, realizations as f64);
    let e = mse.sqrt();
    U * (2.0 * (n + 1.0) * (integral.abs() / e + 1.0) + r + 3.0) / (r - 1.0).sqrt()
}

/// CSV rows for [`write_csv`]: one row per sampler and `N`.
const CSV_HEADER: &[&str] = &[
    "sampler",
    "integrand",
    "n",
    "mse",
    "mse_stderr",
    "mean_error",
    "seconds",
    "evaluations",
    "slope",
    "slope_ci_low",
    "slope_ci_high",
];

/// Writes studies as CSV (atomically): the columns of `CSV_HEADER`; the slope columns repeat the
/// sampler's fit on each of its rows (empty when there is no fit; the interval columns are empty
/// when the interval is undefined).
pub fn write_csv(path: &std::path::Path, studies: &[Convergence]) -> Result<()> {
    use crate::output::csv_number;
    use std::io::Write;
    crate::output::write_atomic(path, |w| {
        writeln!(w, "{}", CSV_HEADER.join(","))?;
        for s in studies {
            // An undefined interval (a standard error of 0) leaves its columns empty.
            let (slope, lo, hi) = match &s.fit {
                Some(f) => {
                    let (lo, hi) = f
                        .interval()
                        .map_or((String::new(), String::new()), |(lo, hi)| {
                            (csv_number(lo), csv_number(hi))
                        });
                    (csv_number(f.slope), lo, hi)
                }
                None => (String::new(), String::new(), String::new()),
            };
            for p in &s.points {
                writeln!(
                    w,
                    "{},{},{},{:e},{:e},{:e},{},{},{slope},{lo},{hi}",
                    csv_field(&s.sampler),
                    csv_field(&s.integrand),
                    p.n,
                    p.mse,
                    p.mse_stderr,
                    p.mean_error,
                    csv_number(p.seconds),
                    p.evaluations
                )?;
            }
        }
        Ok(())
    })
}

/// Quotes a CSV field that holds a comma or a `"` (doubling each `"` inside, as RFC 4180 asks);
/// other fields are written as they are.
fn csv_field(s: &str) -> String {
    if s.contains(',') || s.contains('"') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The log-log plot of studies: MSE against N with ±1 standard error bars, one line per sampler,
/// slopes (with 95% intervals) in the legend; study `i` drawn in palette colour `colours[i]` when
/// given (so that a sampler keeps its colour across plots), else in its own position's.
pub fn plot(
    path: &std::path::Path,
    studies: &[Convergence],
    colours: Option<&[usize]>,
    title: &str,
) -> Result<()> {
    use crate::output::plot::{write_loglog_png, LogLogPlot, Series, XScale};
    let series: Vec<Series> = studies
        .iter()
        .enumerate()
        .map(|(i, s)| Series {
            label: match &s.fit {
                Some(f) => format!(
                    "{}: slope {:.2}, 95% CI {}",
                    s.sampler,
                    f.slope,
                    f.interval_text(2)
                ),
                None => s.sampler.clone(),
            },
            points: s.points.iter().map(|p| (p.n as f64, p.mse)).collect(),
            errors: Some(s.points.iter().map(|p| p.mse_stderr).collect()),
            dashed: false,
            colour: colours.map(|c| c[i]),
        })
        .collect();
    write_loglog_png(
        path,
        &LogLogPlot {
            title: title.to_string(),
            x_label: "N (samples per estimate)".into(),
            y_label: "MSE (squared integrand units; bars: ±1 standard error, within the marker where shorter)".into(),
            series,
            width: 1000,
            height: 700,
            x_scale: XScale::Log,
        },
    )
}

/// Share of an MSE above which the reference floor is said to flatten it.
const FLOOR_SHARE: f64 = 0.1;

/// A note when a Monte Carlo reference's floor (`reference_stderr²`, which every MSE contains on
/// average) is at least [`FLOOR_SHARE`] of the MSE at some `N`: the MSE there, and the fitted slope,
/// measure the reference as much as the sampler.
pub fn floor_note(points: &[ConvergePoint], reference_stderr: f64) -> Option<String> {
    let floor = reference_stderr * reference_stderr;
    let hit: Vec<String> = points
        .iter()
        .filter(|p| floor > 0.0 && floor >= FLOOR_SHARE * p.mse)
        .map(|p| format!("{} ({:.0} %)", p.n, 100.0 * (floor / p.mse).min(1.0)))
        .collect();
    (!hit.is_empty()).then(|| {
        format!(
            "the reference floor {floor:.2e} is {} % or more of the MSE at N = {}, so those MSE and \
             the slope through them are flattened by the reference's own error; the floor falls as \
             1/refcount, so raise the pixel's refcount (at most refcount=16777216) or leave those N \
             out",
            100.0 * FLOOR_SHARE,
            hit.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(n: usize, mse: f64) -> ConvergePoint {
        ConvergePoint {
            n,
            mse,
            mse_stderr: 0.1 * mse,
            mean_error: 0.0,
            seconds: 0.0,
            median_seconds: 0.0,
            evaluations: 100 * n as u64,
        }
    }

    /// A lattice on a smooth Gaussian (integral 6.28) has MSEs of 6.3e-31 and 2.1e-30 at N = 16 and
    /// 64, errors of 8e-16 and 1.5e-15 that rounding of the estimates alone can make (up to 1.2e-14
    /// and 4.5e-14): no slope through them (before, "slope 0.877"). MSEs of 1e-20 and 1e-24 (errors
    /// of 1e-10 and 1e-12) are values, and fitted.
    #[test]
    fn an_mse_at_rounding_level_gets_no_slope() {
        let integral = std::f64::consts::TAU;
        assert!(error_within_rounding(16, 6.3e-31, integral));
        assert!(fit_points(&[point(16, 6.3e-31), point(64, 2.1e-30)], 10, integral).is_none());
        assert!(!error_within_rounding(64, 1e-24, integral));
        let fit = fit_points(&[point(16, 1e-20), point(64, 1e-24)], 10, integral).unwrap();
        assert!((fit.slope + 4.0 / 4f64.log10()).abs() < 1e-9, "{fit:?}");
    }

    #[test]
    fn a_repeated_n_counts_once_in_the_fit() {
        let distinct = [point(16, 1e-2), point(64, 2e-3), point(256, 3e-4)];
        let mut repeated = distinct.to_vec();
        repeated.push(point(256, 3e-4));
        repeated.push(point(256, 3e-4));
        assert!(fit_points(&distinct, 100, 0.5).is_some());
        assert_eq!(
            fit_points(&repeated, 100, 0.5),
            fit_points(&distinct, 100, 0.5)
        );
        assert!(fit_points(&[point(256, 3e-4), point(256, 3e-4)], 100, 0.5).is_none());
    }

    #[test]
    fn the_floor_note_names_the_n_whose_mse_the_reference_floor_flattens() {
        // Reference stderr 1e-3: floor 1e-6, 1 % of the first MSE, 20 % of the second, all of the
        // third.
        let points = [point(16, 1e-4), point(64, 5e-6), point(256, 1e-6)];
        let note = floor_note(&points, 1e-3).expect("a note");
        assert!(note.contains("N = 64 (20 %), 256 (100 %)"), "{note}");
        assert!(!note.contains("16 ("), "{note}");
        // An exact reference, or one far below every MSE, has no floor worth a note.
        assert_eq!(floor_note(&points, 0.0), None);
        assert_eq!(floor_note(&points, 1e-5), None);
    }
}
