//! Variance in the Fourier domain (DESIGN §4): with a random toroidal shift,
//! `Var(I_N) = (1/N) Σ_{k≠0} |f̂(k)|² E[P_N(k)]`, split by directional cone, with the part of the sum
//! beyond the frequency grid estimated by Parseval, and the predicted slope.
//!
//! The expectation is taken over `R` realizations of the sampler, and the prediction's standard error is
//! that of the per-realization sums `V_r = (1/N) Σ_k |f̂(k)|² P_r(k)`, which accounts for the
//! correlation between frequencies exactly.
//!
//! Only the 2D spectra of the projections that carry `f̂` are needed ([`Integrand::spectral_planes`]);
//! a frequency shared by two planes (a common axis) is counted once.
//!
//! A sheared sampler ([`Sampler::shear_frame`]) shifts its pattern before it shears it, so the formula
//! holds in the pattern's frame: `P` is the unsheared pattern's spectrum and `f̂` becomes `ĝ` of the
//! integrand pulled back through the shear, `g = f ∘ S`, which has no closed form. `ĝ` is then sampled
//! ([`crate::integrands::sampled::sampled_power`]) on an `m × m` grid per plane, `m` the power of two
//! at least `max(256, 4K)` and at most [`MAX_PULLBACK_SAMPLES`], good to about `|k| / m` relative
//! where `g` jumps. The shear preserves area, so `∫g² = ∫f²` and the tail is estimated as before.

use crate::converge::{check_plan, fit_power_law, SlopeFit};
use crate::error::{Error, Result};
use crate::integrands::sampled::sampled_power;
use crate::integrands::{variance_reference, Integrand, Reference};
use crate::points::shear::shear_pair;
use crate::points::{project, Projection};
use crate::rng;
use crate::samplers::{Sampler, ShearFrame};
use crate::spectrum::profiles::cone_index;
use crate::spectrum::{check_res, fourier_sums, frequency, Method};
use crate::stats::Welford;
use indicatif::ProgressBar;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// How to predict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VarianceConfig {
    /// Frequency grid `K` (even): `k1, k2 ∈ {−K/2 … K/2−1}` in each plane.
    pub res: usize,
    /// If set to `m`, the grid at size `N` is `max(res, m·N)` (rounded up to even): a discontinuous
    /// integrand's variance under a stratified sampler comes from `|k|` up to a few `N`, so a grid that
    /// grows with `N` keeps the white-noise tail estimate honest. The sums over points are cheap when
    /// `f̂` is sparse (an aligned edge lives on one axis), `O(N K²)` otherwise; `f̂` itself is evaluated
    /// on the whole grid (at most 2^26 cells over all planes).
    pub res_per_n: Option<usize>,
    /// Realizations of the sampler over which `E[P]` is averaged (at least 2).
    pub realizations: usize,
    /// Number of directional cones (cone `c` centred on `c·180°/cones`; cone 0 holds the `k1` axis).
    pub cones: usize,
    /// Seed of the sampler's realizations.
    pub seed: u64,
    /// How full-grid Fourier sums are computed (sparse spectra are summed exactly at their frequencies).
    pub method: Method,
}

/// The prediction at one `N`.
#[derive(Clone, Debug, PartialEq)]
pub struct VariancePoint {
    /// Points per set.
    pub n: usize,
    /// Frequency grid side `K` used at this `N` (grows with `N` under `res_per_n`).
    pub res: usize,
    /// Predicted variance: `grid + tail`.
    pub variance: f64,
    /// Standard error of `variance`: the realizations' spread, and the tail's standard error where
    /// `∫f²` is estimated.
    pub stderr: f64,
    /// The sum over the frequency grid.
    pub grid: f64,
    /// The part beyond the grid (and below the `|f̂|²` threshold), estimated as
    /// `(Var(f) − Σ_grid |f̂|²) / N`: white noise (`E[P] = 1`) there. `Var(f)` in closed form where
    /// the integrand has it, else by randomized QMC ([`crate::integrands::variance_reference`]).
    pub tail: f64,
    /// Standard error of `tail`: 0 when `Var(f)` is exact.
    pub tail_stderr: f64,
    /// The grid sum split by directional cone (sums to `grid`).
    pub cones: Vec<f64>,
    /// Standard error of each cone's share.
    pub cone_stderr: Vec<f64>,
    /// A bound on what f64 rounding can put into `variance` (absolute: [`bin_error`] over the grid,
    /// and the tail's rounding): a `variance` not above it is zero within rounding, and has no slope
    /// or interval.
    pub rounding: f64,
    /// The same bound for each cone's share.
    pub cone_rounding: Vec<f64>,
}

impl VariancePoint {
    /// Whether the predicted variance is zero within rounding (not above [`VariancePoint::rounding`]).
    pub fn is_rounding(&self) -> bool {
        self.variance <= self.rounding
    }

    /// The tail's share of the predicted variance (`tail / variance`, a fraction in [0, 1]); `None`
    /// when the prediction is zero.
    pub fn tail_share(&self) -> Option<f64> {
        (self.variance > 0.0).then(|| self.tail / self.variance)
    }
}

/// Predictions for a list of `N`.
#[derive(Clone, Debug, PartialEq)]
pub struct VariancePrediction {
    /// Sampler name.
    pub sampler: String,
    /// Integrand name.
    pub integrand: String,
    /// The projections summed over.
    pub planes: Vec<Projection>,
    /// One entry per `N`.
    pub points: Vec<VariancePoint>,
    /// Predicted `Var ∝ N^slope` over all `N` (`None` with fewer than two `N`).
    pub fit: Option<SlopeFit>,
    /// Slope of each cone's share (`None` where a share is zero).
    pub cone_fits: Vec<Option<SlopeFit>>,
}

/// Frequencies with non-negligible `|f̂|²`, grouped by plane.
struct Spectrum {
    planes: Vec<Projection>,
    /// Per plane: `(grid index i·K + j, |f̂|², cone)`.
    active: Vec<Vec<(usize, f64, usize)>>,
    /// `Σ |f̂|²` over all active frequencies.
    total: f64,
}

impl Spectrum {
    /// The spectrum of per-plane frequency lists, without those below [`NEGLIGIBLE`] of the largest
    /// `|f̂|²` (left to the tail).
    fn from_active(planes: Vec<Projection>, mut active: Vec<Vec<(usize, f64, usize)>>) -> Self {
        let max_w = active.iter().flatten().fold(0.0_f64, |m, e| m.max(e.1));
        for list in &mut active {
            list.retain(|e| e.1 > NEGLIGIBLE * max_w);
        }
        let total = active.iter().flatten().map(|e| e.1).sum();
        Spectrum {
            planes,
            active,
            total,
        }
    }
}

/// Largest number of Fourier coefficients evaluated per prediction (grid cells summed over planes).
const MAX_GRID: usize = 1 << 26;

/// Frequencies below this fraction of the largest `|f̂|²` are left to the tail.
const NEGLIGIBLE: f64 = 1e-20;

/// Largest side of the grid a pulled-back integrand is sampled on (256 MiB of complex samples), so
/// the largest frequency grid of a sheared sampler's prediction is `K = 1024`.
pub const MAX_PULLBACK_SAMPLES: usize = 4096;

/// The planes that carry `f̂`, or a usage error when it spreads over all frequencies.
fn planes_of(f: &dyn Integrand) -> Result<Vec<Projection>> {
    f.spectral_planes().ok_or_else(|| {
        Error::Usage(format!(
            "the spectrum of {} is not known on 2D projections of its {}D frequencies (a pixel of the scene, or a product over two projections); the Fourier prediction needs it there (single integrands or sums of @proj terms); measure it with `anisospec converge` instead",
            f.name(),
            f.dims()
        ))
    })
}

/// Refuses a `res × res` grid on `planes` planes beyond [`MAX_GRID`] coefficients.
fn check_grid(res: usize, planes: usize) -> Result<()> {
    if res.saturating_mul(res).saturating_mul(planes) > MAX_GRID {
        return Err(Error::Usage(format!(
            "a {res} x {res} frequency grid on {planes} plane(s) is more than the {MAX_GRID} coefficients the prediction evaluates; lower --res or --res-per-n"
        )));
    }
    Ok(())
}

/// The side `m` of the grid a sheared sampler's pulled-back integrand is sampled on for a
/// `res × res` frequency grid (`max(256, 4K)`, rounded up to a power of two); refused beyond
/// [`MAX_PULLBACK_SAMPLES`].
fn pullback_samples(res: usize) -> Result<usize> {
    // Saturating: a grid beyond the limit is refused below, whatever --res-per-n asked for.
    let m = res
        .saturating_mul(4)
        .max(256)
        .checked_next_power_of_two()
        .unwrap_or(usize::MAX);
    if m > MAX_PULLBACK_SAMPLES {
        return Err(Error::Usage(format!(
            "a sheared sampler's prediction samples the pulled-back integrand on {m} x {m} points for a {res} x {res} frequency grid, more than the largest, {MAX_PULLBACK_SAMPLES} x {MAX_PULLBACK_SAMPLES}; lower --res or --res-per-n so that K is at most {}",
            MAX_PULLBACK_SAMPLES / 4
        )));
    }
    Ok(m)
}

fn integrand_spectrum(f: &dyn Integrand, res: usize, cones: usize) -> Result<Spectrum> {
    let planes = planes_of(f)?;
    check_grid(res, planes.len())?;
    let dims = f.dims();
    let mut active = Vec::with_capacity(planes.len());
    for (pi, p) in planes.iter().enumerate() {
        let list: Vec<(usize, f64, usize)> = (0..res * res)
            .into_par_iter()
            .filter_map(|idx| {
                let (k1, k2) = frequency(idx, res);
                if k1 == 0 && k2 == 0 {
                    return None;
                }
                let mut k = vec![0i64; dims];
                k[p.a] = k1;
                k[p.b] = k2;
                // Counted already in an earlier plane that also contains this frequency.
                let nonzero: Vec<usize> = (0..dims).filter(|&d| k[d] != 0).collect();
                if planes[..pi].iter().any(|q| nonzero.iter().all(|&d| d == q.a || d == q.b)) {
                    return None;
                }
                match f.fourier(&k).map(|c| c.norm_sqr()) {
                    Some(w) if w > 0.0 => Some(Some((idx, w, cone_index(k1, k2, cones)))),
                    Some(_) => None,
                    None => Some(None),
                }
            })
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| {
                Error::Usage(format!(
                    "{} has no Fourier coefficients; the prediction needs them (measure it with `anisospec converge`)",
                    f.name()
                ))
            })?;
        active.push(list);
    }
    Ok(Spectrum::from_active(planes, active))
}

/// The active frequencies of `ĝ` for `g = f ∘ S`, the integrand seen from the pattern of a sheared
/// sampler (see the module doc). The shear moves `x` with `u` and `y` with `v`, so `f̂` must lie on
/// the `xu` and `yv` planes; a plane's `ĝ` is sampled with the other two coordinates held at ½ (they
/// shift `g` by a constant there, which changes only `k = 0`).
fn pulled_back_spectrum(
    f: &dyn Integrand,
    frame: &ShearFrame,
    res: usize,
    cones: usize,
) -> Result<Spectrum> {
    let planes = planes_of(f)?;
    if let Some(p) = planes
        .iter()
        .find(|p| **p != Projection::XU && **p != Projection::YV)
    {
        return Err(Error::Usage(format!(
            "{} has spectrum on the {} plane; the prediction for a sheared sampler needs an integrand on the xu and yv planes, in that order (the shear moves x with u and y with v; @ux and @vy swap the axes: write the integrand for @xu or @yv), e.g. sheared:s=0.5@xu; predict the unsheared sampler, or measure it with `anisospec converge`",
            f.name(),
            p.name()
        )));
    }
    let m = pullback_samples(res)?;
    let mut active = Vec::with_capacity(planes.len());
    for p in &planes {
        let s = if *p == Projection::XU {
            frame.sx
        } else {
            frame.sy
        };
        let power = sampled_power(
            |a, b| {
                let (x, u) = shear_pair(a, b, s, frame.mode);
                let mut at = [0.5; 4];
                at[p.a] = x;
                at[p.b] = u;
                f.eval(&at)
            },
            res,
            m,
        );
        if power.iter().any(|w| !w.is_finite()) {
            return Err(Error::Input(format!(
                "{} has a non-finite value in the unit square, so its spectrum is undefined",
                f.name()
            )));
        }
        let list: Vec<(usize, f64, usize)> = power
            .iter()
            .enumerate()
            .filter_map(|(idx, &w)| {
                let (k1, k2) = frequency(idx, res);
                ((k1, k2) != (0, 0) && w > 0.0).then(|| (idx, w, cone_index(k1, k2, cones)))
            })
            .collect();
        active.push(list);
    }
    Ok(Spectrum::from_active(planes, active))
}

/// `exp(−2πi k c)` for each `k` of `ks`: runs of consecutive `k` by recurrence, recomputed directly
/// (argument reduced mod 1) every 32 steps so that rounding cannot drift.
fn phases(c: f64, ks: &[i64]) -> Vec<Complex64> {
    let direct = |k: i64| crate::spectrum::exact::phase(k, c);
    let step = direct(1);
    let mut out: Vec<Complex64> = Vec::with_capacity(ks.len());
    let mut run = 0usize;
    for (i, &k) in ks.iter().enumerate() {
        let next = if i > 0 && ks[i - 1] + 1 == k && run < 32 {
            run += 1;
            out[i - 1] * step
        } else {
            run = 0;
            direct(k)
        };
        out.push(next);
    }
    out
}

/// Whether [`power_at`] takes the full-grid sums (of the configured [`Method`]) for `active`
/// frequencies on a `res × res` grid: when more than a quarter of it is active.
fn full_grid(active: usize, res: usize) -> bool {
    active * 4 > res * res
}

/// `|F(k)|² / N` at the active frequencies of one plane: the full-grid sums when more than a quarter
/// of the grid is active ([`full_grid`]), else exact sums at the active frequencies only.
fn power_at(
    points: &[[f64; 2]],
    res: usize,
    active: &[(usize, f64, usize)],
    method: Method,
) -> Vec<f64> {
    let n = points.len() as f64;
    if full_grid(active.len(), res) {
        let sums = fourier_sums(points, res, method);
        return active.iter().map(|e| sums[e.0].norm_sqr() / n).collect();
    }
    // Distinct columns and rows used, and each active frequency's position among them.
    let mut col = vec![usize::MAX; res];
    let mut row = vec![usize::MAX; res];
    let (mut k1s, mut k2s) = (Vec::new(), Vec::new());
    for e in active {
        let (j, i) = (e.0 % res, e.0 / res);
        let (k1, k2) = frequency(e.0, res);
        if col[j] == usize::MAX {
            col[j] = k1s.len();
            k1s.push(k1);
        }
        if row[i] == usize::MAX {
            row[i] = k2s.len();
            k2s.push(k2);
        }
    }
    let at: Vec<(usize, usize)> = active
        .iter()
        .map(|e| (col[e.0 % res], row[e.0 / res]))
        .collect();
    let mut sums = vec![Complex64::new(0.0, 0.0); active.len()];
    for p in points {
        let (e1, e2) = (phases(p[0], &k1s), phases(p[1], &k2s));
        for (s, &(a, b)) in sums.iter_mut().zip(&at) {
            *s += e1[a] * e2[b];
        }
    }
    sums.iter().map(|s| s.norm_sqr() / n).collect()
}

fn check_config(cfg: &VarianceConfig) -> Result<()> {
    check_res(cfg.res)?;
    if cfg.cones == 0 {
        return Err(Error::Usage(
            "--cones 0: use at least one cone (1 = no split)".into(),
        ));
    }
    crate::spectrum::profiles::check_cones(cfg.cones)?;
    if cfg.res_per_n == Some(0) {
        return Err(Error::Usage(
            "--res-per-n 0 grows no grid (K = max(--res, 0·N) = --res); give M = 1 or more, e.g. --res-per-n 4, or leave the flag out".into(),
        ));
    }
    Ok(())
}

/// Realizations whose per-cone sums are held in memory at once: each batch is folded into running
/// means as it ends, so memory does not grow with `R`.
const REALIZATION_BATCH: usize = 1024;

/// The per-realization sums at one `N`, accumulated over the realizations.
struct RealizationSums {
    /// `V_r`: its mean is the grid sum, its standard error the prediction's.
    total: Welford,
    /// Per cone: its share of `V_r`.
    cones: Vec<Welford>,
    /// Per cone: the mean over realizations of the bound on its share's absolute error
    /// ([`bin_error`] weighted by `|f̂|² / N`), which bounds the error of the mean.
    cone_errors: Vec<f64>,
}

/// Per-realization `V_r` at size `n`, and per cone its share, each as a running mean and standard
/// error. Realizations run in parallel in batches of [`REALIZATION_BATCH`] and are pushed in
/// realization order, so a seed gives the same bits whatever the thread count.
fn realizations(
    sampler: &dyn Sampler,
    spec: &Spectrum,
    n: usize,
    res: usize,
    cfg: &VarianceConfig,
    bar: &ProgressBar,
) -> RealizationSums {
    let rho_exact = crate::spectrum::exact::sum_error(n, res);
    // The error bound of a plane's sums relative to N: the full-grid NUFFT's where it is used.
    let rho_of = |active: usize| match cfg.method {
        Method::Nufft { eps } if full_grid(active, res) => rho_exact.max(NUFFT_SUM_ERROR * eps),
        _ => rho_exact,
    };
    let one = |r: usize| {
        bar.inc(1);
        let set = sampler.generate(n, &mut rng::substream(cfg.seed, r as u64, n as u64));
        let mut cones = vec![0.0; cfg.cones];
        let mut errors = vec![0.0; cfg.cones];
        for (p, active) in spec.planes.iter().zip(&spec.active) {
            if active.is_empty() {
                continue;
            }
            let pts = project(&set, sampler.dims(), *p);
            let power = power_at(&pts, res, active, cfg.method);
            let rho_f = rho_of(active.len());
            for (e, pk) in active.iter().zip(power) {
                cones[e.2] += e.1 * pk / n as f64;
                errors[e.2] += e.1 * bin_error(pk, n, rho_f) / n as f64;
            }
        }
        (cones, errors)
    };
    let mut sums = RealizationSums {
        total: Welford::default(),
        cones: vec![Welford::default(); cfg.cones],
        cone_errors: vec![0.0; cfg.cones],
    };
    for start in (0..cfg.realizations).step_by(REALIZATION_BATCH) {
        let end = (start + REALIZATION_BATCH).min(cfg.realizations);
        let batch: Vec<(Vec<f64>, Vec<f64>)> = (start..end).into_par_iter().map(one).collect();
        for (cones, errors) in batch {
            sums.total.push(cones.iter().sum());
            for (w, &x) in sums.cones.iter_mut().zip(&cones) {
                w.push(x);
            }
            for (sum, e) in sums.cone_errors.iter_mut().zip(errors) {
                *sum += e;
            }
        }
    }
    let r = cfg.realizations as f64;
    for e in &mut sums.cone_errors {
        *e /= r;
    }
    sums
}

/// The relative error of each realization's `V_r` (and of each cone's share) that the spectrum's
/// computation allows, at `n` points on a `res × res` grid (`K = res`, `u = 2^−53`), for a set whose
/// spectrum is the same for every shift (a lattice): the floor under which a spread of `V_r` is
/// rounding, not sampling. First-order bounds, step by step:
/// - a phase `exp(−2πi k c)` computed directly: `k c` rounds by `u K / 2` turns (`|k| ≤ K / 2`,
///   `c < 1`), `2π t` by `2u` relative, sine and cosine by `u` each, so it errs by at most
///   `(π K + 4π + 2) u ≤ (π K + 15) u`; one step of the sparse recurrence (`phases`, at most 32 steps
///   between direct values) multiplies by `exp(−2πi c)`, itself within `(6π + 2) u ≤ 21 u`, with a
///   complex product's `√2·2 u ≤ 3 u`: `24 u` a step, `768 u` over 32;
/// - a term `e1 · e2` of `F` then errs by at most `2 (π K + 15 + 768) u + 3 u`, and the sum of `N`
///   terms of modulus 1 by `√2 (N − 1) u N` more (each component summed in order), so at the bins
///   where such a set puts its power (`|F| = N`) `F` errs by `ρ_F = (√2 N + 2 π K + 1569) u`
///   relative, and `P = |F|² / N` by `2 ρ_F + 2 u` (bins where `F` is 0 get `|ΔF|² / N`, second
///   order);
/// - full-grid NUFFT sums instead: `10 · eps`, the accuracy contract of
///   [`crate::spectrum::nufft::Nufft2d`] on bins above 1e-3 of the mean power (a bin far below
///   carries a negligible share of `V_r`);
/// - `V_r` sums `m` non-negative terms `|f̂|² P / N` (each rounded by `2 u`), which adds `(m + 1) u`.
fn relative_error(spec: &Spectrum, res: usize, n: usize, method: Method) -> f64 {
    let u = f64::EPSILON / 2.0;
    let f_error = crate::spectrum::exact::sum_error(n, res);
    let rounding = 2.0 * f_error + 2.0 * u;
    let nufft = match method {
        Method::Nufft { eps } => 10.0 * eps,
        Method::Exact => 0.0,
    };
    let uses_method = spec
        .active
        .iter()
        .any(|a| !a.is_empty() && full_grid(a.len(), res));
    let terms = spec.active.iter().map(Vec::len).sum::<usize>() as f64;
    let per_bin = if uses_method {
        rounding.max(nufft)
    } else {
        rounding
    };
    per_bin + (terms + 1.0) * u
}

/// The bound on a full-grid NUFFT sum's error relative to `N`, per unit of `eps`: a spreading
/// kernel accurate to `eps` errs by at most about `eps Σ_j |c_j| = eps N` at a bin (its aliased
/// terms can add up in phase on a lattice), and this allows 10 times that, as the accuracy contract
/// of [`crate::spectrum::nufft::Nufft2d`] allows `10 eps` on `P`. It is a worst case: measured
/// against the exact sums (lattice, Sobol and random sets, N = 256 to 4096, eps = 1e-3 to 1e-9,
/// `tests/spectrum.rs`), `P` errs by at most 7.5e-4 of [`bin_error`] with it. So a variance below
/// about `(10 eps)² Var f` is not told from 0 under the NUFFT.
const NUFFT_SUM_ERROR: f64 = 10.0;

/// What the computation can put into one bin's `P = |F|² / N` (absolute), at `n` points, given the
/// computed `P`: the bound [`relative_error`] calls second order, which is all there is where the
/// exact power is 0 (a lattice whose dual misses the integrand's energy). A bin's `F` errs by at
/// most `ρ_F N`, so `P` by `(2 |F| ρ_F N + ρ_F² N²) / N = 2 ρ_F sqrt(P N) + ρ_F² N`: `ρ_F` is f64
/// rounding's ([`crate::spectrum::exact::sum_error`]) for exact sums, at least
/// [`NUFFT_SUM_ERROR`]` · eps` for full-grid NUFFT sums, where a lattice's zero bins come out at
/// up to about `1e-4 eps² N` (exact sums: 1e-30).
fn bin_error(p: f64, n: usize, rho_f: f64) -> f64 {
    let n = n as f64;
    2.0 * rho_f * (p.max(0.0) * n).sqrt() + rho_f * rho_f * n
}

/// The floor of a point's relative standard error ([`fit_power_law`]) when each realization's value
/// is within a relative `rho` of the same value (a share `part` of the fitted one, the rest exact):
/// values within `± rho·v` of one another have a standard deviation of at most
/// `rho v sqrt(R / (R − 1))`, the running mean's rounding adds at most `R u v`, and the standard
/// error divides by `sqrt(R)`: `(rho + R u) · part / sqrt(R − 1)`.
fn stderr_floor(rho: f64, realizations: usize, part: f64) -> f64 {
    let r = realizations as f64;
    (rho + r * f64::EPSILON / 2.0) * part / (r - 1.0).sqrt()
}

/// The part of a point's relative standard-error floor that an absolute error bound adds, given as
/// `relative = bound / value`: realizations within `± bound` of one another have a standard
/// deviation of at most `bound sqrt(R / (R − 1))`, hence a standard error of `bound / sqrt(R − 1)`.
fn absolute_floor(relative: f64, realizations: usize) -> f64 {
    relative / (realizations as f64 - 1.0).sqrt()
}

/// Predicts the variance of `sampler` on `f` for every `N` of `ns`; a sheared sampler in its pattern's
/// frame (see the module doc).
pub fn predict(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    ns: &[usize],
    cfg: &VarianceConfig,
) -> Result<VariancePrediction> {
    predict_with_progress(sampler, f, ns, cfg, &ProgressBar::hidden())
}

/// [`predict`], advancing `bar` by one per realization at every `N` (`ns.len() × realizations` in
/// all).
pub fn predict_with_progress(
    sampler: &dyn Sampler,
    f: &dyn Integrand,
    ns: &[usize],
    cfg: &VarianceConfig,
    bar: &ProgressBar,
) -> Result<VariancePrediction> {
    check_plan(sampler, f, ns, cfg.realizations)?;
    check_config(cfg)?;
    // A sheared sampler is predicted in its pattern's frame (see the module doc).
    let frame = sampler.shear_frame();
    if frame
        .as_ref()
        .is_some_and(|fr| fr.pattern.shear_frame().is_some())
    {
        return Err(Error::Usage(format!(
            "{} is sheared twice; the prediction takes one shear: shear the pattern once",
            sampler.name()
        )));
    }
    let pattern = frame.as_ref().map_or(sampler, |fr| fr.pattern);
    // Before any work on f (a pixel's reference renders): the prediction needs f̂ on 2D planes.
    let planes = planes_of(f)?;
    let Reference {
        value: var_f,
        stderr: var_f_stderr,
    } = variance_reference(f);
    // The grid side at each N; the largest is checked before any N's work.
    let res_of = |n: usize| {
        cfg.res_per_n
            // Saturating: a grid beyond the limit is refused by the checks below.
            .map_or(cfg.res, |m| {
                cfg.res
                    .max(m.saturating_mul(n).div_ceil(2).saturating_mul(2))
            })
    };
    let largest = ns.iter().map(|&n| res_of(n)).max().unwrap_or(cfg.res);
    check_grid(largest, planes.len())?;
    if frame.is_some() {
        pullback_samples(largest)?;
    }
    let mut points = Vec::with_capacity(ns.len());
    // Per N, the relative error of each realization's values ([`relative_error`]).
    let mut rho = Vec::with_capacity(ns.len());
    let mut spec: Option<(usize, Spectrum)> = None;
    for &n in ns {
        let res = res_of(n);
        if spec.as_ref().is_none_or(|s| s.0 != res) {
            // The bar counts realizations; say what runs before them (a fan's coefficients on a
            // 1024 x 1024 grid take minutes).
            let label = bar.message();
            bar.set_message(format!("f̂ on {res} x {res}"));
            let computed = match &frame {
                Some(fr) => pulled_back_spectrum(f, fr, res, cfg.cones)?,
                None => integrand_spectrum(f, res, cfg.cones)?,
            };
            bar.set_message(label);
            spec = Some((res, computed));
        }
        let spec = &spec.as_ref().expect("computed above").1;
        let per = realizations(pattern, spec, n, res, cfg, bar);
        let (grid, stderr) = (per.total.mean(), per.total.stderr());
        let cones = per.cones.iter().map(Welford::mean).collect();
        let cone_stderr = per.cones.iter().map(Welford::stderr).collect();
        let tail = (var_f - spec.total).max(0.0) / n as f64;
        let tail_stderr = var_f_stderr / n as f64;
        rho.push(relative_error(spec, res, n, cfg.method));
        let cone_rounding = per.cone_errors.clone();
        let grid_rounding: f64 = cone_rounding.iter().sum();
        // The tail's difference of two sums of `terms` non-negative values (and Var(f)'s own
        // rounding) errs by `(terms + 2) u Var(f)`.
        let terms = spec.active.iter().map(Vec::len).sum::<usize>() as f64;
        let tail_rounding = (terms + 2.0) * (f64::EPSILON / 2.0) * var_f / n as f64;
        points.push(VariancePoint {
            n,
            res,
            variance: grid + tail,
            stderr: stderr.hypot(tail_stderr),
            grid,
            tail,
            tail_stderr,
            cones,
            cone_stderr,
            rounding: grid_rounding + tail_rounding,
            cone_rounding,
        });
    }
    let nf: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    // A value within its rounding has no slope: its logarithm would be rounding's.
    let fit = (!points.iter().any(VariancePoint::is_rounding)).then(|| {
        let v: Vec<f64> = points.iter().map(|p| p.variance).collect();
        let se: Vec<f64> = points.iter().map(|p| p.stderr).collect();
        let floor: Vec<f64> = points
            .iter()
            .zip(&rho)
            .map(|(p, &r)| {
                stderr_floor(r, cfg.realizations, p.grid / p.variance)
                    + absolute_floor(p.rounding / p.variance, cfg.realizations)
            })
            .collect();
        fit_power_law(&nf, &v, &se, &floor).ok()
    });
    let fit = fit.flatten();
    let cone_fits = (0..cfg.cones)
        .map(|c| {
            if points.iter().any(|p| p.cones[c] <= p.cone_rounding[c]) {
                return None;
            }
            let v: Vec<f64> = points.iter().map(|p| p.cones[c]).collect();
            let se: Vec<f64> = points.iter().map(|p| p.cone_stderr[c]).collect();
            let floor: Vec<f64> = rho
                .iter()
                .zip(&points)
                .map(|(&r, p)| {
                    stderr_floor(r, cfg.realizations, 1.0)
                        + absolute_floor(p.cone_rounding[c] / p.cones[c], cfg.realizations)
                })
                .collect();
            fit_power_law(&nf, &v, &se, &floor).ok()
        })
        .collect();
    Ok(VariancePrediction {
        sampler: sampler.name(),
        integrand: f.name(),
        points,
        fit,
        cone_fits,
        planes,
    })
}

/// Writes a prediction as CSV (atomically): `n, variance, stderr, grid, tail`, then `cone_c` and
/// `cone_c_stderr` for every cone.
pub fn write_csv(path: &std::path::Path, pred: &VariancePrediction) -> Result<()> {
    use std::io::Write;
    let cones = pred.points.first().map_or(0, |p| p.cones.len());
    crate::output::write_atomic(path, |w| {
        let mut header = vec![
            "n".to_string(),
            "variance".into(),
            "stderr".into(),
            "grid".into(),
            "tail".into(),
        ];
        for c in 0..cones {
            header.push(format!("cone_{c}"));
            header.push(format!("cone_{c}_stderr"));
        }
        writeln!(w, "{}", header.join(","))?;
        for p in &pred.points {
            let mut row = vec![
                p.n.to_string(),
                format!("{:e}", p.variance),
                format!("{:e}", p.stderr),
                format!("{:e}", p.grid),
                format!("{:e}", p.tail),
            ];
            for c in 0..cones {
                row.push(format!("{:e}", p.cones[c]));
                row.push(format!("{:e}", p.cone_stderr[c]));
            }
            writeln!(w, "{}", row.join(","))?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    /// The pulled-back spectrum of a sheared sampler ([`pulled_back_spectrum`]) against its
    /// definition, summed directly: `ĝ(k) = (1/m²) Σ_{i,j} g(a_i, b_j) e^{−2πi (k1 a_i + k2 b_j)}`
    /// over the `m × m` cell centres `a_i = (i + ½)/m`, `b_j = (j + ½)/m`, with `g` the integrand at
    /// the image of the pattern point (`a_i`, `b_j` on the plane, ½ elsewhere) under the sampler's
    /// own map ([`crate::points::shear::shear_set_4d`], what `generate` applies). The integrand has a
    /// different term on each plane and the shears differ in sign and size, at a moderate pair
    /// (0.5, −0.3) and an extreme one (−3, 8: beyond 1 the trapezoid's widths swap), in both modes:
    /// a shear of the wrong sign, from the other plane, or placed on the swapped axes fails.
    ///
    /// Rounding bound (first order, `u = 2^−53`, `G = max |g|` over the samples): the direct sum is
    /// taken as one over `j` then one over `i`, of `m` terms each; a phase (`t = k (2j + 1) mod 2m`
    /// is exact, then `π t / m`, cosine and sine) is within `15 u`, so a term within `17 u G`, and
    /// each sum of `m` terms adds `√2 (m − 1) u` of the sum of moduli: `|Δĝ| ≤ (2√2 m + 34) u G`.
    /// The two passes of `m`-point FFTs err by at most `log₂ m · 7 u` of `‖ĝ‖₂ ≤ G` each (Higham,
    /// Accuracy and Stability of Numerical Algorithms, Thm 24.2): `112 u G` at `m = 256`. So with
    /// `B = (2√2 m + 146) u G`, `|P − P_direct| ≤ 2 B max(|ĝ|) + B²` (`P = |ĝ|²`): `B` is about
    /// 1e-13 here, and the two differ by at most 2.2e-15 (measured). The pulled-back edge at the
    /// exact shear 0.5 is aligned (its power is on the k1 axis, 2e-35 elsewhere): with the shear's
    /// sign flipped, taken from the other plane, or placed on the swapped axes, the first frequency
    /// checked off that axis came out at 2e-8, 1.4e-7 and 1.1e-5, against bounds below 2e-15.
    #[test]
    fn the_pulled_back_spectrum_is_the_direct_sum_at_the_sheared_points() {
        use crate::points::shear::{shear_set_4d, ShearMode};
        let f =
            crate::integrands::parse("sheared:s=0.5,c=0.7@xu+gaussian:sigma=0.2,cx=0.4,cy=0.6@yv")
                .unwrap();
        let (res, cones) = (16, 4);
        let m = pullback_samples(res).unwrap();
        assert_eq!(m, 256);
        let u = f64::EPSILON / 2.0;
        let half = (res / 2) as i64;
        // e^{−2πi k (2j + 1) / (2m)} for k = −K/2 … K/2 − 1 (row k + K/2), j < m: the argument is
        // reduced mod 1 exactly, in integers.
        let phase: Vec<Complex64> = (0..res as i64)
            .flat_map(|c| {
                let k = c - half;
                (0..m as i64).map(move |j| {
                    let t = (k * (2 * j + 1)).rem_euclid(2 * m as i64);
                    Complex64::from_polar(1.0, -std::f64::consts::PI * t as f64 / m as f64)
                })
            })
            .collect();
        for mode in [ShearMode::Transported, ShearMode::Wrap] {
            for (sx, sy) in [(0.5, -0.3), (-3.0, 8.0)] {
                let sampler = crate::samplers::Sheared::new(
                    crate::samplers::build("padded-mj", 4).unwrap(),
                    sx,
                    sy,
                    mode,
                )
                .unwrap();
                let frame = sampler.shear_frame().expect("a nonzero shear");
                let spec = pulled_back_spectrum(f.as_ref(), &frame, res, cones).unwrap();
                assert_eq!(spec.planes, [Projection::XU, Projection::YV]);
                let max_w = spec
                    .active
                    .iter()
                    .flatten()
                    .fold(0.0_f64, |w, e| w.max(e.1));
                for (p, active) in spec.planes.iter().zip(&spec.active) {
                    let mut g = vec![0.0; m * m];
                    for (idx, v) in g.iter_mut().enumerate() {
                        let mut at = [0.5; 4];
                        at[p.a] = ((idx / m) as f64 + 0.5) / m as f64;
                        at[p.b] = ((idx % m) as f64 + 0.5) / m as f64;
                        shear_set_4d(&mut at, sx, sy, mode);
                        *v = f.eval(&at);
                    }
                    // inner[i · K + c]: row i summed over j at k2 = c − K/2.
                    let inner: Vec<Complex64> = (0..m * res)
                        .map(|e| {
                            let (i, c) = (e / res, e % res);
                            (0..m).map(|j| phase[c * m + j] * g[i * m + j]).sum()
                        })
                        .collect();
                    let direct: Vec<Complex64> = (0..res * res)
                        .map(|idx| {
                            let (r, c) = (idx / res, idx % res);
                            // Row r is k2, column c is k1 (DESIGN §3).
                            let sum: Complex64 =
                                (0..m).map(|i| phase[c * m + i] * inner[i * res + r]).sum();
                            sum / (m * m) as f64
                        })
                        .collect();
                    let big_g = g.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                    let b = (2.0 * 2f64.sqrt() * m as f64 + 146.0) * u * big_g;
                    let mut worst: f64 = 0.0;
                    for (idx, q) in direct.iter().map(|z| z.norm_sqr()).enumerate() {
                        let (k1, k2) = frequency(idx, res);
                        if (k1, k2) == (0, 0) {
                            continue;
                        }
                        let kept = active.iter().find(|e| e.0 == idx);
                        let w = kept.map_or(0.0, |e| e.1);
                        let bound = 2.0 * b * (w.max(q)).sqrt() + b * b;
                        if let Some(e) = kept {
                            assert_eq!(e.2, cone_index(k1, k2, cones));
                            assert!(
                                (w - q).abs() <= bound,
                                "{mode:?} ({sx}, {sy}) {} k = ({k1}, {k2}): pulled back {w:e}, direct {q:e}, bound {bound:e}",
                                p.name()
                            );
                        } else {
                            // Left to the tail: zero, or negligible beside the largest |ĝ|².
                            assert!(
                                q <= NEGLIGIBLE * max_w + bound,
                                "{mode:?} ({sx}, {sy}) {} k = ({k1}, {k2}): dropped, direct {q:e}",
                                p.name()
                            );
                        }
                        worst = worst.max((w - q).abs());
                    }
                    eprintln!(
                        "{mode:?} ({sx}, {sy}) {}: largest |P − P_direct| {worst:.1e} (largest P {max_w:.1e}), B {b:.1e}",
                        p.name()
                    );
                }
            }
        }
    }

    /// The sparse sums of [`power_at`] (phases by a recurrence re-seeded every 32 steps) against the
    /// exact DFT over the whole grid, bin by bin, within the bound both are held to: F within ρ_F N
    /// of the true sum, so `P = |F|²/N` within `2 ρ_F sqrt(P N) + ρ_F² N` each, twice that apart.
    /// The active set is sparse, as a hairline's is: the k1 axis (runs longer than 32) and scattered
    /// bins (runs of one).
    #[test]
    fn sparse_sums_meet_the_exact_dft() {
        let (n, res) = (1000, 128);
        let mut rng = crate::rng::stream(3, 0);
        let points: Vec<[f64; 2]> = (0..n).map(|_| [rng.random(), rng.random()]).collect();
        let half = res / 2;
        let mut active: Vec<(usize, f64, usize)> = (0..res)
            .map(|j| (half * res + j, 1.0, 0))
            .filter(|e| frequency(e.0, res) != (0, 0))
            .collect();
        active.extend((0..200).map(|_| (rng.random_range(0..res * res), 1.0, 0)));
        assert!(!full_grid(active.len(), res));
        let sparse = power_at(&points, res, &active, Method::Exact);
        let exact = fourier_sums(&points, res, Method::Exact);
        let rho = crate::spectrum::exact::sum_error(n, res);
        for (e, &p) in active.iter().zip(&sparse) {
            let q = exact[e.0].norm_sqr() / n as f64;
            let bound = 2.0 * (2.0 * rho * (p.max(q) * n as f64).sqrt() + rho * rho * n as f64);
            assert!(
                (p - q).abs() <= bound,
                "k = {:?}: sparse {p:e}, exact {q:e}, bound {bound:e}",
                frequency(e.0, res)
            );
        }
    }
}
