//! Power spectra of point sets (DESIGN §3): exact DFT, type-1 NUFFT, expected spectra over
//! realizations, and radial / anisotropy / directional-cone profiles.
//!
//! Grid convention everywhere: a `K × K` row-major array with `P[i * K + j]` at `k1 = j − K/2`
//! (first projected dimension) and `k2 = i − K/2` (second); [`frequency`] maps an index to `(k1, k2)`.

pub mod exact;
pub mod expected;
pub mod nufft;
pub mod profiles;

use crate::error::{Error, Result};
use nufft::Nufft2d;
use rustfft::num_complex::Complex64;
use std::sync::{Arc, Mutex};

/// The frequency `(k1, k2)` of entry `idx = i * res + j` of a `res × res` grid: `k1 = j − res/2`,
/// `k2 = i − res/2` (the layout of the module doc), so `k1, k2 ∈ −res/2 … res/2 − 1`.
pub fn frequency(idx: usize, res: usize) -> (i64, i64) {
    let half = (res / 2) as i64;
    ((idx % res) as i64 - half, (idx / res) as i64 - half)
}

/// How Fourier sums are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// The exact DFT, `O(N K²)`: the reference.
    Exact,
    /// The type-1 non-uniform FFT with relative tolerance `eps`.
    Nufft {
        /// Requested tolerance, in `[1e-12, 1e-1]`.
        eps: f64,
    },
}

impl Method {
    /// The NUFFT method with tolerance `eps`, checked: `Error::Usage` unless `eps ∈ [1e-12, 1e-1]`.
    pub fn nufft(eps: f64) -> Result<Self> {
        // Planning validates eps (and a small even grid costs next to nothing).
        Nufft2d::new(2, eps)?;
        Ok(Method::Nufft { eps })
    }
}

/// Plans reused by [`fourier_sums`], [`type2`] and [`power`], keyed by `(res, eps)`: most recently used last.
static PLANS: Mutex<Vec<Arc<Nufft2d>>> = Mutex::new(Vec::new());
/// How many plans [`PLANS`] keeps.
const PLAN_CACHE: usize = 8;

/// A shared NUFFT plan for `(res, eps)`, built once and reused across calls and threads.
pub fn nufft_plan(res: usize, eps: f64) -> Result<Arc<Nufft2d>> {
    let mut plans = PLANS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(i) = plans
        .iter()
        .position(|p| p.res() == res && p.eps().to_bits() == eps.to_bits())
    {
        let plan = plans.remove(i);
        plans.push(plan.clone());
        return Ok(plan);
    }
    let plan = Arc::new(Nufft2d::new(res, eps)?);
    if plans.len() == PLAN_CACHE {
        plans.remove(0);
    }
    plans.push(plan.clone());
    Ok(plan)
}

/// The plan for `method = Nufft`, panicking on parameters no checked constructor lets through.
fn plan_or_panic(res: usize, eps: f64) -> Arc<Nufft2d> {
    nufft_plan(res, eps).unwrap_or_else(|e| {
        panic!("invalid NUFFT parameters (check them first with check_res and Method::nufft): {e}")
    })
}

/// The largest spectrum resolution `K`: a `K × K` grid of `f64` is then 512 MiB, and the transforms
/// hold a few of them.
pub const MAX_RES: usize = 8192;

/// Checks a spectrum resolution `K` given as `--res`: even, positive and at most [`MAX_RES`].
pub fn check_res(res: usize) -> Result<()> {
    check_res_named("--res", res)
}

/// [`check_res`] for a resolution set by `name`, e.g. `--res` or `spectra_res =` (a config key): the
/// message writes `{name} {res}`.
pub fn check_res_named(name: &str, res: usize) -> Result<()> {
    if res == 0 || res % 2 == 1 {
        return Err(Error::Usage(format!(
            "{name} {res} is not a positive even number; the frequency grid k = -K/2..K/2-1 needs K even, e.g. {name} {}",
            (res.min(MAX_RES) + 1).max(2) / 2 * 2
        )));
    }
    if res > MAX_RES {
        return Err(Error::Usage(format!(
            "{name} {res} is above the largest grid, {MAX_RES} (a {res} x {res} grid needs {:.1} GiB per array); lower it",
            (res as f64).powi(2) * 8.0 / (1u64 << 30) as f64
        )));
    }
    Ok(())
}

/// The Fourier sums `F(k) = Σ_j exp(−2πi k·x_j)` of 2D points on the `res × res` grid.
///
/// The NUFFT path runs on the calling thread (parallelise over point sets); the exact path is
/// parallel. Panics if `res` is odd or zero, or a NUFFT `eps` is out of range: check user input with
/// [`check_res`] and [`Method::nufft`] first.
pub fn fourier_sums(points: &[[f64; 2]], res: usize, method: Method) -> Vec<Complex64> {
    match method {
        Method::Exact => exact::fourier_sums(points, res),
        Method::Nufft { eps } => plan_or_panic(res, eps).type1(points),
    }
}

/// Type 2, the adjoint of [`fourier_sums`]: `g_j = Σ_k c(k) exp(+2πi (k1 x_j + k2 y_j))` for the
/// coefficients `coeffs` on the `res × res` grid. Panics as [`fourier_sums`] does, and if
/// `coeffs.len() != res²`.
pub fn type2(
    coeffs: &[Complex64],
    points: &[[f64; 2]],
    res: usize,
    method: Method,
) -> Vec<Complex64> {
    match method {
        Method::Exact => exact::type2(coeffs, points, res),
        Method::Nufft { eps } => plan_or_panic(res, eps).type2(coeffs, points),
    }
}

/// The power spectrum `P(k) = |F(k)|² / N` of 2D points on the `res × res` grid (`P = 0` for an
/// empty set). Panics as [`fourier_sums`] does.
pub fn power(points: &[[f64; 2]], res: usize, method: Method) -> Vec<f64> {
    match method {
        Method::Exact => {
            let n = points.len().max(1) as f64;
            exact::fourier_sums(points, res)
                .iter()
                .map(|f| f.norm_sqr() / n)
                .collect()
        }
        Method::Nufft { eps } => plan_or_panic(res, eps).power(points),
    }
}

/// Sums of `P` and of `(P − shift)²` over the realizations of an expected spectrum (see
/// [`expected`]), in the layout that is cheapest for the method: the `res²` grid for the exact DFT,
/// the half plane `k2 ≥ 0` for the NUFFT, whose `P(k) = P(−k)` is exact by construction
/// ([`Nufft2d::accumulate_power`]: half the sums read and written per set). The shift, one
/// realization's `P`, keeps the variance from cancelling where `P` varies little about a large mean
/// (a lattice's peaks `P = N`): `Σ P² − (Σ P)² / R` would leave about `sqrt(ε) E[P]` of rounding
/// (ε the machine epsilon) as the standard error there, or 0. [`PowerSums::mean_and_stderr`] gives
/// both on the grid, the mean with the bits of summing [`power`]'s output set by set in the same
/// order.
#[derive(Clone, Debug)]
pub struct PowerSums {
    res: usize,
    method: Method,
    shift: Arc<Vec<f64>>,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
}

impl PowerSums {
    /// Zero sums for spectra on the `res × res` grid, in the layout of `method` (the grid, or its
    /// half plane), shifted by 0. An invalid `res` or `eps` panics later, in [`PowerSums::add`], as
    /// [`power`] does.
    pub fn new(res: usize, method: Method) -> Self {
        let len = match method {
            Method::Exact => res * res,
            Method::Nufft { .. } => nufft::half_plane_len(res),
        };
        PowerSums {
            res,
            method,
            shift: Arc::new(vec![0.0; len]),
            sum: vec![0.0; len],
            sum_sq: vec![0.0; len],
        }
    }

    /// Zero sums as [`PowerSums::new`], shifted by the power spectrum of `points`.
    pub fn shifted_by(res: usize, method: Method, points: &[[f64; 2]]) -> Self {
        let mut sums = PowerSums::new(res, method);
        sums.add(points);
        sums.shift = Arc::new(std::mem::replace(
            &mut sums.sum,
            vec![0.0; sums.sum_sq.len()],
        ));
        sums.sum_sq.fill(0.0);
        sums
    }

    /// Adds the spectrum the shift was taken from, as [`PowerSums::add`] of its points would, bit
    /// for bit (`P` is the shift, `(P − shift)²` is 0), without computing it again.
    pub fn add_shift(&mut self) {
        for (s, c) in self.sum.iter_mut().zip(self.shift.iter()) {
            *s += c;
        }
    }

    /// Zero sums of the same grid, method and shift.
    pub fn zeroed_like(&self) -> Self {
        PowerSums {
            res: self.res,
            method: self.method,
            shift: self.shift.clone(),
            sum: vec![0.0; self.sum.len()],
            sum_sq: vec![0.0; self.sum_sq.len()],
        }
    }

    /// Bytes the two sums hold (the shift is shared).
    pub fn bytes(&self) -> usize {
        (self.sum.len() + self.sum_sq.len()) * std::mem::size_of::<f64>()
    }

    /// Sets both sums back to zero, keeping their memory and the shift.
    pub fn clear(&mut self) {
        self.sum.fill(0.0);
        self.sum_sq.fill(0.0);
    }

    /// Adds the power spectrum `P` of `points` (that of [`power`], bit for bit) and `(P − shift)²`.
    pub fn add(&mut self, points: &[[f64; 2]]) {
        match self.method {
            Method::Exact => {
                let p = power(points, self.res, self.method);
                for (((s, q), c), p) in self
                    .sum
                    .iter_mut()
                    .zip(&mut self.sum_sq)
                    .zip(self.shift.iter())
                    .zip(p)
                {
                    let d = p - c;
                    *s += p;
                    *q += d * d;
                }
            }
            Method::Nufft { eps } => plan_or_panic(self.res, eps).accumulate_power(
                points,
                &self.shift,
                &mut self.sum,
                &mut self.sum_sq,
            ),
        }
    }

    /// Adds another set of sums of the same grid, method and shift, entry by entry.
    ///
    /// Panics if `other` has another grid, method or shift.
    pub fn add_sums(&mut self, other: &PowerSums) {
        assert!(
            self.res == other.res
                && self.method == other.method
                && Arc::ptr_eq(&self.shift, &other.shift),
            "PowerSums of different grids, methods or shifts cannot be added"
        );
        self.sum
            .iter_mut()
            .zip(&other.sum)
            .for_each(|(a, b)| *a += b);
        self.sum_sq
            .iter_mut()
            .zip(&other.sum_sq)
            .for_each(|(a, b)| *a += b);
    }

    /// The mean `Σ P / R` over `realizations` = R sets and its standard error `sqrt(s² / R)`, with
    /// the unbiased sample variance `s² = (Σ (P − c)² − (Σ P − R c)² / R) / (R − 1)` about the
    /// shift `c`, both on the `res × res` grid (layout of this module). The standard error is 0 for
    /// `R < 2`, where it is unknown.
    pub fn mean_and_stderr(self, realizations: usize) -> (Vec<f64>, Vec<f64>) {
        let r = realizations as f64;
        let mean: Vec<f64> = self.sum.iter().map(|s| s / r).collect();
        let stderr: Vec<f64> = if realizations < 2 {
            vec![0.0; self.sum.len()]
        } else {
            self.sum
                .iter()
                .zip(&self.sum_sq)
                .zip(self.shift.iter())
                .map(|((s, q), c)| {
                    let off = s - r * c;
                    ((q - off * off / r).max(0.0) / (r - 1.0) / r).sqrt()
                })
                .collect()
        };
        match self.method {
            Method::Exact => (mean, stderr),
            Method::Nufft { .. } => (
                nufft::expand_half_plane(&mean, self.res),
                nufft::expand_half_plane(&stderr, self.res),
            ),
        }
    }
}
