//! A 2D non-uniform FFT on the unit torus (DESIGN §3), written on rustfft.
//!
//! Type 1 (points → modes) spreads each point onto an upsampled `n × n` grid with the "exponential of
//! semicircle" kernel `φ(z) = exp(β (sqrt(1 − z²) − 1))` of Barnett, Magland and af Klinteberg (2019),
//! takes an FFT, keeps the central `K × K` modes and divides by the kernel's Fourier transform.
//! Type 2 (modes → points) is its adjoint: divide, inverse FFT, interpolate with the same kernel.
//! Cost: `O(N w² + n² log n)` with `n ≈ σK` and `w` kernel points per dimension.
//!
//! Choice of grid: a plan holds up to three fine grids, `σ` = 1.25, 1.5 and 2, each with the kernel
//! width `w ≈ ln(safety/eps) / (π sqrt(1 − 1/σ))` and shape `β = 0.97 π w (1 − 1/(2σ))` of Barnett et
//! al. for that `σ`; the safety factor of each `σ` is calibrated against the exact DFT (see `GRIDS`).
//! A smaller `σ` means a smaller FFT but a wider kernel, so each call picks the grid with the smallest
//! modelled cost `n² log2 n + N w²` for its number of points `N` (both terms ≈ 0.25 ns per unit on the
//! development machine). For K = 256 and N = 4096: σ = 1.25 (n = 320) up to eps = 1e-7, σ = 1.5
//! (n = 384) at 1e-8, σ = 2 (n = 512) below, where the narrower grids would need w > 16 or leave the
//! error model; from N ≈ 5 500 (eps = 1e-6) the larger grids win.
//!
//! Implementation notes: the point weights of type 1 are real, so the fine grid is real. The grid is
//! stored x-major (rows follow the first coordinate). Row stage: two real rows make one complex line
//! `a + i b`, 16 such lines go through one batched complex FFT (rustfft) along y, and Hermitian
//! symmetry separates them again, `â(k) = (Z(k) + conj Z(−k))/2`, `b̂(k) = (Z(k) − conj Z(−k))/(2i)`;
//! the separation writes only the kept `k2 = 0 ..= K/2`, transposed into one contiguous line over x
//! per `k2` (measured at n = 320: 0.10 ms, against 0.12 ms for the row stage this replaced, one
//! realfft real-to-complex call per row and the same transpose). Column stage: one batched complex FFT of the `K/2 + 1` lines along
//! x; `k2 < 0` comes from Hermitian symmetry. Each output row is then a contiguous run of one
//! transformed line. The power spectrum needs no complex deconvolution, `P = |B|² corr(k1)²
//! corr(k2)² / N` with `B` the transformed fine grid, computed on the half plane `k2 ≥ 0` only
//! (`P(k) = P(−k)`): expected spectra sum it there, and a single spectrum mirrors it onto the grid.
//! The kernel is evaluated per point as `2w` values of fitted polynomials (Horner with fused
//! multiply-adds, degree chosen at planning time until the measured fit error is below the tolerance
//! scaled by the deconvolution's band-edge gain), then `w²` fused multiply-adds into a padded grid
//! whose margins are folded back once per transform. On CPUs with AVX-512 each point's `w` values per
//! dimension are one or two 8-lane vectors, the same operations in the same order as the portable
//! code, so the grid has the same bits on every CPU.
//!
//! Frequencies follow the grid convention of [`crate::spectrum`]: entry `i * K + j` holds
//! `k1 = j − K/2` (first coordinate) and `k2 = i − K/2` (second coordinate). Coordinates are periods of
//! the unit torus: any finite value is accepted and wrapped onto `[0, 1)`.

use crate::error::{Error, Result};
use crate::quad::gauss_legendre;
use crate::spectrum::check_res;
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};
use std::cell::RefCell;
use std::f64::consts::PI;
use std::sync::Arc;

/// Runs `$body` with the const generic `$W` equal to the runtime width `$w` (2 ..= MAX_WIDTH), so that
/// the `W × W` spreading and interpolation loops are unrolled for each width.
macro_rules! with_width {
    ($w:expr, $W:ident => $body:expr) => {
        match $w {
            2 => {
                const $W: usize = 2;
                $body
            }
            3 => {
                const $W: usize = 3;
                $body
            }
            4 => {
                const $W: usize = 4;
                $body
            }
            5 => {
                const $W: usize = 5;
                $body
            }
            6 => {
                const $W: usize = 6;
                $body
            }
            7 => {
                const $W: usize = 7;
                $body
            }
            8 => {
                const $W: usize = 8;
                $body
            }
            9 => {
                const $W: usize = 9;
                $body
            }
            10 => {
                const $W: usize = 10;
                $body
            }
            11 => {
                const $W: usize = 11;
                $body
            }
            12 => {
                const $W: usize = 12;
                $body
            }
            13 => {
                const $W: usize = 13;
                $body
            }
            14 => {
                const $W: usize = 14;
                $body
            }
            15 => {
                const $W: usize = 15;
                $body
            }
            16 => {
                const $W: usize = 16;
                $body
            }
            w => unreachable!("kernel width {w} outside 2..=16"),
        }
    };
}

/// Panics with a clear message on a non-finite coordinate (points must be finite).
#[inline(always)]
fn check_finite(j: usize, p: &[f64; 2]) {
    assert!(
        p[0].is_finite() && p[1].is_finite(),
        "point {j} has a non-finite coordinate ({}, {}); points must be finite",
        p[0],
        p[1]
    );
}

/// Smallest tolerance accepted by [`Nufft2d::new`].
pub const EPS_MIN: f64 = 1e-12;
/// Largest tolerance accepted by [`Nufft2d::new`].
pub const EPS_MAX: f64 = 1e-1;

/// The fine grids a plan can use: upsampling factor `σ`, kernel safety factor, largest kernel width.
///
/// The kernel of each grid is designed for `eps / safety`: the accuracy contract is a per-bin relative
/// error of `P = |F|²/N` (≤ 10·eps in every bin above 1e-3 of the mean), which is stricter than the
/// global relative l2 error the kernel formulas of Barnett et al. aim at: a bin at the threshold has
/// `|F| ≈ 0.03 sqrt(N)` while the error is `≈ eps sqrt(N)`, and lower `σ` leaves less room at the band
/// edge, where `ψ̂` is smallest. Calibration against the exact DFT (K = 64, 96 and 256 with N = K²/16;
/// random and jittered sets; widths 6 … 16 with an exact kernel fit): the worst per-bin relative error
/// of `P` is `C exp(−π w sqrt(1 − 1/σ))` with `C` at most 1500 (σ = 2), 2300 (σ = 1.5) and 1800
/// (σ = 1.25). The safety factors 300, 460 and 340 put the predicted worst error at 5, 5 and 5.3 eps,
/// about half the contract, before the rounding up of `w` (the tests in tests/nufft.rs and the table of
/// benches/spectrum.rs check the contract). At σ = 1.5 the error stops following the model beyond
/// w = 14 (7e-9 at w = 14, 8e-10 at w = 16 against a predicted 5.7e-10), hence its cap.
const GRIDS: [(f64, f64, usize); 3] = [(1.25, 340.0, 16), (1.5, 460.0, 14), (2.0, 300.0, 16)];
/// Grid rows per batch of the row stage of type 1 (even: packed in pairs; see `Grid::type1_lines`).
const BLOCK: usize = 32;
/// Largest kernel width (grid points per dimension).
const MAX_WIDTH: usize = 16;
/// Kernel values per point and dimension in the AVX-512 spreading path: two vectors of 8 `f64`.
const LANES: usize = 16;

/// A reusable plan for 2D type-1 and type-2 NUFFTs on a `res × res` frequency grid with tolerance `eps`.
///
/// The plan holds one fine grid per upsampling factor `σ` that can meet the tolerance (see
/// [`Nufft2d::grid`]); each transform uses the one with the smallest modelled cost for its number of
/// points. The plan is immutable and `Sync`: share one plan between threads; each call uses
/// thread-local scratch memory.
pub struct Nufft2d {
    res: usize,
    eps: f64,
    /// Candidate fine grids, in increasing `σ`.
    grids: Vec<Grid>,
}

/// The fine grid a transform of a given number of points runs on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FineGrid {
    /// Upsampling factor `σ` (nominal; the side is rounded up to a 2-3-5-smooth even number).
    pub sigma: f64,
    /// Fine grid side `n`.
    pub size: usize,
    /// Kernel width `w` in fine-grid points per dimension.
    pub kernel_width: usize,
}

/// One upsampled grid with its kernel and FFT plans.
struct Grid {
    res: usize,
    sigma: f64,
    /// Fine grid side.
    n: usize,
    /// Kernel width in fine-grid points.
    w: usize,
    /// Kernel shape parameter.
    beta: f64,
    /// `1 / ψ̂(k)` for `k = 0 ..= res/2`: the deconvolution factors (even in `k`).
    corr: Vec<f64>,
    /// `corr[|k1|]²` at `k1 = j − K/2` for `j = 0 ..= K`: the squared factors of one run of the power
    /// spectrum, in run order (see `power_runs`).
    corr_sq_run: Vec<f64>,
    /// Piecewise-polynomial kernel (see `fit_kernel`); empty when the kernel is evaluated directly.
    coef: Vec<f64>,
    /// `coef` with each degree's row padded with zeros to `LANES` entries, for the AVX-512 path.
    coef_lanes: Vec<f64>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
}

/// Per-thread work buffers, grown on demand and reused across calls and plans.
#[derive(Default)]
struct Scratch {
    real: Vec<f64>,
    cplx: Vec<Complex64>,
    row: Vec<Complex64>,
    fft: Vec<Complex64>,
    /// Real work vector of the power path (see `Grid::power_runs`).
    power: Vec<f64>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Resizes `v` to `len` and sets every entry to `value`, reusing its allocation.
fn reset<T: Copy>(v: &mut Vec<T>, len: usize, value: T) {
    v.clear();
    v.resize(len, value);
}

/// Writes `src` reversed into `dst` (same length), four values at a time so that the loop compiles to
/// vector loads, shuffles and stores (an element-wise reversed copy stays scalar).
fn copy_reversed(dst: &mut [f64], src: &[f64]) {
    assert_eq!(dst.len(), src.len());
    let mut d = dst.chunks_exact_mut(4);
    let mut s = src.rchunks_exact(4);
    for (d, s) in (&mut d).zip(&mut s) {
        d.copy_from_slice(&[s[3], s[2], s[1], s[0]]);
    }
    for (d, s) in d
        .into_remainder()
        .iter_mut()
        .zip(s.remainder().iter().rev())
    {
        *d = *s;
    }
}

/// Resizes `v` to `len`, keeping old contents: for buffers that are then overwritten entirely.
fn fit<T: Copy + Default>(v: &mut Vec<T>, len: usize) {
    v.resize(len, T::default());
}

/// The smallest even number `≥ m` whose only prime factors are 2, 3 and 5.
fn next_smooth_even(m: usize) -> usize {
    let mut c = m.max(2);
    c += c % 2;
    loop {
        let mut r = c;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return c;
        }
        c += 2;
    }
}

/// The number of values of a half-plane spectrum on the `res × res` grid: `(K/2 + 1)(K + 1)` (see
/// [`expand_half_plane`]).
pub fn half_plane_len(res: usize) -> usize {
    (res / 2 + 1) * (res + 1)
}

/// The `res × res` grid (layout of [`crate::spectrum`]) of an even function `P(k) = P(−k)` held as its
/// half plane `k2 ≥ 0`: entry `a (K + 1) + j` of `half_plane` is `P(j − K/2, a)` for `a = 0 ..= K/2`
/// and `j = 0 ..= K`. Row `K/2 + a` of the grid is run `a`'s first `K` values, and row `K/2 − a`
/// (`a > 0`) is run `a` reversed, its entry `j` being `P(K/2 − j, a)`; the values are copied, not
/// recomputed, so the two mirrored bins have the same bits.
///
/// Panics if `half_plane` does not hold [`half_plane_len`]`(res)` values.
pub fn expand_half_plane(half_plane: &[f64], res: usize) -> Vec<f64> {
    let (k, half) = (res, res / 2);
    assert_eq!(
        half_plane.len(),
        half_plane_len(k),
        "a half plane on the {k} x {k} grid holds (K/2 + 1)(K + 1) values"
    );
    let mut full = vec![0.0; k * k];
    for (a, run) in half_plane.chunks_exact(k + 1).enumerate() {
        if a < half {
            full[(half + a) * k..(half + a + 1) * k].copy_from_slice(&run[..k]);
        }
        if a > 0 {
            copy_reversed(&mut full[(half - a) * k..(half - a + 1) * k], &run[1..]);
        }
    }
    full
}

impl Nufft2d {
    /// Plans transforms on the `res × res` grid (`res` even) with relative tolerance `eps` in
    /// `[1e-12, 1e-1]`.
    ///
    /// Accuracy contract: for type 1, over every bin whose exact power `P = |F|²/N` is at least 1e-3
    /// of the mean power, the relative error of `P` is at most `10 · eps`. Smaller tolerances are
    /// refused: there the double-precision rounding of the transform, amplified by the deconvolution,
    /// sets a floor (measured 1.3e-12 to 1.7e-12 for eps = 1e-13 and 1e-14, N = 4096, K = 256), so the
    /// contract could not hold; eps = 1e-12 still meets it. Use the exact DFT below that.
    pub fn new(res: usize, eps: f64) -> Result<Self> {
        check_res(res)?;
        if !(EPS_MIN..=EPS_MAX).contains(&eps) {
            return Err(Error::Usage(format!(
                "NUFFT tolerance {} is out of range; choose eps in [{EPS_MIN:e}, {EPS_MAX:e}] (e.g. 1e-6)",
                crate::error::number(eps)
            )));
        }
        let grids = GRIDS
            .iter()
            .filter_map(|&(sigma, safety, max_w)| Grid::new(res, eps, sigma, safety, max_w))
            .collect::<Vec<_>>();
        // σ = 2 has a kernel within MAX_WIDTH for every accepted eps.
        debug_assert!(!grids.is_empty());
        Ok(Nufft2d { res, eps, grids })
    }

    /// The frequency grid side `K`.
    pub fn res(&self) -> usize {
        self.res
    }

    /// The requested tolerance.
    pub fn eps(&self) -> f64 {
        self.eps
    }

    /// The fine grid that a transform of `n_points` points uses: among the grids whose kernel meets
    /// the tolerance, the one with the smallest modelled cost `n² log2 n + N w²` (FFT and spreading;
    /// one time unit each, ≈ 0.25 ns on the development machine for both, measured at K = 256).
    pub fn grid(&self, n_points: usize) -> FineGrid {
        let g = self.pick(n_points);
        FineGrid {
            sigma: g.sigma,
            size: g.n,
            kernel_width: g.w,
        }
    }

    /// The cheapest grid for `n_points` points (ties go to the smaller σ).
    fn pick(&self, n_points: usize) -> &Grid {
        let cost = |g: &Grid| {
            let n = g.n as f64;
            n * n * n.log2() + n_points as f64 * (g.w * g.w) as f64
        };
        self.grids
            .iter()
            .reduce(|best, g| if cost(g) < cost(best) { g } else { best })
            .expect("a plan has at least one grid")
    }

    /// Type 1: `F(k) = Σ_j exp(−2πi k·x_j)` on the `K × K` grid (layout of [`crate::spectrum`]).
    pub fn type1(&self, points: &[[f64; 2]]) -> Vec<Complex64> {
        let k = self.res;
        let mut out = vec![Complex64::new(0.0, 0.0); k * k];
        self.pick(points.len()).type1_into(
            points,
            |_| 1.0,
            |i, f| out[i * k..(i + 1) * k].copy_from_slice(f),
        );
        out
    }

    /// Weighted type 1: `F(k) = Σ_j a_j exp(−2πi k·x_j)` with real weights `a_j`.
    ///
    /// Panics if `weights.len() != points.len()`.
    pub fn type1_weighted(&self, points: &[[f64; 2]], weights: &[f64]) -> Vec<Complex64> {
        assert_eq!(
            weights.len(),
            points.len(),
            "type1_weighted needs one weight per point"
        );
        let k = self.res;
        let mut out = vec![Complex64::new(0.0, 0.0); k * k];
        self.pick(points.len()).type1_into(
            points,
            |j| weights[j],
            |i, f| out[i * k..(i + 1) * k].copy_from_slice(f),
        );
        out
    }

    /// The power spectrum `P(k) = |F(k)|² / N` (layout of [`crate::spectrum`]). An empty set has
    /// `P = 0` everywhere.
    pub fn power(&self, points: &[[f64; 2]]) -> Vec<f64> {
        self.power_on(self.pick(points.len()), points)
    }

    /// Adds the power spectrum `P` of `points` to `sum` and `(P − shift)²` to `sum_sq`, all three held
    /// as the half plane `k2 ≥ 0` ([`half_plane_len`] values each; layout of [`expand_half_plane`]),
    /// for sums over realizations (see [`crate::spectrum::PowerSums`]: a shift near the mean keeps
    /// the variance from cancelling). `P(k) = P(−k)`, so the half plane holds the whole spectrum,
    /// and expanded, `sum` gives, bit for bit, the sums of [`Nufft2d::power`]'s output. Each run of
    /// `P` goes into the sums while it is in cache, and only half the spectrum is read and written
    /// per set. An empty set has `P = 0`.
    ///
    /// Panics if `shift`, `sum` or `sum_sq` does not hold [`half_plane_len`] values.
    pub fn accumulate_power(
        &self,
        points: &[[f64; 2]],
        shift: &[f64],
        sum: &mut [f64],
        sum_sq: &mut [f64],
    ) {
        let k = self.res;
        let len = half_plane_len(k);
        assert!(
            shift.len() == len && sum.len() == len && sum_sq.len() == len,
            "accumulate_power needs half-plane shift and sums of (K/2 + 1)(K + 1) = {len} values"
        );
        if points.is_empty() {
            for (q, c) in sum_sq.iter_mut().zip(shift) {
                *q += c * c;
            }
            return;
        }
        let grid = self.pick(points.len());
        grid.power_runs(points, 1.0 / points.len() as f64, |a, p| {
            let run = a * (k + 1)..(a + 1) * (k + 1);
            for (((s, q), c), p) in sum[run.clone()]
                .iter_mut()
                .zip(&mut sum_sq[run.clone()])
                .zip(&shift[run])
                .zip(p)
            {
                let d = p - c;
                *s += p;
                *q += d * d;
            }
        });
    }

    /// [`Nufft2d::power`] on a given grid.
    /// The runs of the half plane `k2 ≥ 0`, expanded onto the grid by `P(k) = P(−k)`
    /// ([`expand_half_plane`]).
    fn power_on(&self, grid: &Grid, points: &[[f64; 2]]) -> Vec<f64> {
        let k = self.res;
        let mut half = vec![0.0; half_plane_len(k)];
        if !points.is_empty() {
            grid.power_runs(points, 1.0 / points.len() as f64, |a, run| {
                half[a * (k + 1)..(a + 1) * (k + 1)].copy_from_slice(run)
            });
        }
        expand_half_plane(&half, k)
    }

    /// Type 2 (the adjoint of type 1): `g_j = Σ_k c(k) exp(+2πi k·x_j)` for coefficients `c` on the
    /// `K × K` grid (layout of [`crate::spectrum`]).
    ///
    /// Panics if `coeffs.len() != K²`.
    pub fn type2(&self, coeffs: &[Complex64], points: &[[f64; 2]]) -> Vec<Complex64> {
        let k = self.res;
        assert_eq!(
            coeffs.len(),
            k * k,
            "type2 needs K² = {} coefficients on the K × K grid",
            k * k
        );
        self.pick(points.len()).type2(coeffs, points)
    }
}

impl Grid {
    /// The grid of upsampling factor `sigma` for tolerance `eps`, or `None` if its kernel would be
    /// wider than `max_w`.
    fn new(res: usize, eps: f64, sigma: f64, safety: f64, max_w: usize) -> Option<Self> {
        let tol = eps / safety;
        // w ≈ ln(1/tol) / (π sqrt(1 − 1/σ)) (Barnett et al. 2019, §4).
        let w = ((1.0 / tol).ln() / (PI * (1.0 - 1.0 / sigma).sqrt())).ceil() as usize;
        if w > max_w.min(MAX_WIDTH) {
            return None;
        }
        let w = w.max(2);
        // β = γ π w (1 − 1/(2σ)) with γ slightly below 1 (Barnett et al. 2019, §4).
        let beta = 0.97 * PI * (1.0 - 0.5 / sigma) * w as f64;
        let n = next_smooth_even(((sigma * res as f64).ceil() as usize).max(2 * w));
        let mut grid = Grid {
            res,
            sigma,
            n,
            w,
            beta,
            corr: Vec::new(),
            corr_sq_run: Vec::new(),
            coef: Vec::new(),
            coef_lanes: Vec::new(),
            fwd: FftPlanner::new().plan_fft_forward(n),
            inv: FftPlanner::new().plan_fft_inverse(n),
        };
        grid.corr = grid.deconvolution();
        grid.corr_sq_run = (0..=res)
            .map(|j| {
                let c = grid.corr[j.abs_diff(res / 2)];
                c * c
            })
            .collect();
        // A kernel-value error δ changes each point's contribution by about δ, which the deconvolution
        // amplifies by up to corr[K/2] / corr[0] relative to the centre (measured: 3 to 8 at σ = 2, up
        // to 700 at σ = 1.25): fit to tol / 10 divided by that. No fit can beat the jump e^{−β} of the
        // kernel at the ends of its support, nor 1e-14 in monomial Horner form; neither matters against
        // the truncation error of the kernel itself (measured: the same errors as the exact kernel).
        let amplification = grid.corr[res / 2] / grid.corr[0];
        let target = (tol / (10.0 * amplification)).max((-beta).exp()).max(1e-14);
        if let Some((_, coef)) = grid.fit_kernel(target) {
            grid.coef_lanes = coef
                .chunks_exact(w)
                .flat_map(|row| (0..LANES).map(|l| row.get(l).copied().unwrap_or(0.0)))
                .collect();
            grid.coef = coef;
        }
        Some(grid)
    }

    /// The kernel `φ(z) = exp(β (sqrt(1 − z²) − 1))` on `|z| ≤ 1`.
    fn phi(&self, z: f64) -> f64 {
        (self.beta * ((1.0 - z * z).max(0.0).sqrt() - 1.0)).exp()
    }

    /// `1 / ψ̂(k)`, `k = 0 ..= K/2`, where `ψ̂(k) = ∫ φ(2t/w) exp(−2πi k t / n) dt` (t in fine-grid
    /// units) is the Fourier transform of the kernel as spread, by Gauss–Legendre quadrature.
    fn deconvolution(&self) -> Vec<f64> {
        let half_w = self.w as f64 / 2.0;
        let rule = gauss_legendre(4 * self.w + 80);
        let f: Vec<f64> = rule.iter().map(|&(z, q)| q * self.phi(z)).collect();
        (0..=self.res / 2)
            .map(|k| {
                let a = 2.0 * PI * k as f64 * half_w / self.n as f64;
                let s: f64 = rule
                    .iter()
                    .zip(&f)
                    .map(|(&(z, _), &f)| f * (a * z).cos())
                    .sum();
                1.0 / (half_w * s)
            })
            .collect()
    }

    /// Fits, for each kernel point `l`, a polynomial in `u ∈ [−1, 1]` to `φ(−1 + (s + l) / (w/2))`
    /// with `s = (u + 1)/2` the offset of the point from the first grid node. Chebyshev interpolation,
    /// then monomial coefficients for Horner's rule; the degree grows until the measured maximum error
    /// is below `target`. Layout: `coef[deg * w + l]`, highest degree first. `None` if no degree up to
    /// 30 reaches `target` (then the kernel is evaluated directly).
    fn fit_kernel(&self, target: f64) -> Option<(usize, Vec<f64>)> {
        let w = self.w;
        let half_w = w as f64 / 2.0;
        let f = |l: usize, u: f64| self.phi(-1.0 + ((u + 1.0) / 2.0 + l as f64) / half_w);
        for d in 4..=30 {
            let m = d + 1;
            let mut coef = vec![0.0; m * w];
            for l in 0..w {
                // Chebyshev coefficients of the degree-d interpolant at the Chebyshev points.
                let vals: Vec<f64> = (0..m)
                    .map(|i| f(l, (PI * (i as f64 + 0.5) / m as f64).cos()))
                    .collect();
                let cheb: Vec<f64> = (0..m)
                    .map(|k| {
                        let c: f64 = vals
                            .iter()
                            .enumerate()
                            .map(|(i, v)| v * (PI * k as f64 * (i as f64 + 0.5) / m as f64).cos())
                            .sum();
                        c * if k == 0 { 1.0 } else { 2.0 } / m as f64
                    })
                    .collect();
                // Monomial coefficients: T_{k+1} = 2u T_k − T_{k−1}.
                let mut mono = vec![0.0; m];
                let (mut t0, mut t1) = (vec![0.0; m], vec![0.0; m]);
                t0[0] = 1.0;
                if m > 1 {
                    t1[1] = 1.0;
                }
                for (k, &a) in cheb.iter().enumerate() {
                    let tk = if k == 0 { &t0 } else { &t1 };
                    for (mc, t) in mono.iter_mut().zip(tk) {
                        *mc += a * t;
                    }
                    if k >= 1 {
                        let mut t2 = vec![0.0; m];
                        for i in 0..m {
                            t2[i] = if i > 0 { 2.0 * t1[i - 1] } else { 0.0 } - t0[i];
                        }
                        t0 = std::mem::replace(&mut t1, t2);
                    }
                }
                for (deg, c) in mono.iter().enumerate() {
                    coef[(d - deg) * w + l] = *c;
                }
            }
            let worst = (0..=200)
                .map(|i| -1.0 + i as f64 / 100.0)
                .flat_map(|u| (0..w).map(move |l| (l, u)))
                .map(|(l, u)| {
                    let h = coef.chunks_exact(w).fold(0.0, |acc, row| acc * u + row[l]);
                    (h - f(l, u)).abs()
                })
                .fold(0.0, f64::max);
            if worst <= target {
                return Some((d, coef));
            }
        }
        None
    }

    /// Padded-grid index of the first kernel point for coordinate `x`, and the offset `s ∈ [0, 1)` of
    /// that node from the left end of the kernel's support.
    ///
    /// The padded grid has side `n + W`; padded index `p` is fine index `(p − W/2) mod n`.
    #[inline(always)]
    fn node<const W: usize>(&self, x: f64) -> (usize, f64) {
        let n = self.n as f64;
        let half_w = W as f64 / 2.0;
        let mut t = (x - x.floor()) * n;
        if t >= n {
            t -= n;
        }
        let i0 = (t - half_w).ceil();
        ((i0 as isize + (W / 2) as isize) as usize, i0 - (t - half_w))
    }

    /// The `W` kernel values at the nodes of `Q` coordinates with offsets `s` (see [`Grid::node`]).
    /// The `Q` Horner recurrences are independent and interleaved, so that their latencies overlap;
    /// each value goes through the same operations as with `Q = 1`.
    #[inline(always)]
    fn values<const W: usize, const Q: usize>(&self, s: [f64; Q]) -> [[f64; W]; Q] {
        let mut v = [[0.0; W]; Q];
        if self.coef.is_empty() {
            let half_w = W as f64 / 2.0;
            for (v, s) in v.iter_mut().zip(s) {
                for (l, v) in v.iter_mut().enumerate() {
                    *v = self.phi(-1.0 + (s + l as f64) / half_w);
                }
            }
        } else {
            let mut u = s;
            for u in u.iter_mut() {
                *u = 2.0 * *u - 1.0;
            }
            let mut rows = self.coef.chunks_exact(W);
            let lead = rows.next().expect("kernel fit has a leading row");
            for v in v.iter_mut() {
                v.copy_from_slice(lead);
            }
            for row in rows {
                for (v, u) in v.iter_mut().zip(u) {
                    for (v, c) in v.iter_mut().zip(row) {
                        *v = v.mul_add(u, *c);
                    }
                }
            }
        }
        v
    }

    /// Padded-grid index of the first kernel point and the `W` kernel values for coordinate `x`.
    #[inline(always)]
    fn kernel_w<const W: usize>(&self, x: f64) -> (usize, [f64; W]) {
        let (i, s) = self.node::<W>(x);
        let [v] = self.values::<W, 1>([s]);
        (i, v)
    }

    /// Spreads points with weights `weight(j)` onto the padded real grid `grid` (side `n + w`, zeroed)
    /// and folds the padding back onto the periodic `n × n` core.
    fn spread(&self, points: &[[f64; 2]], weight: impl Fn(usize) -> f64, grid: &mut [f64]) {
        with_width!(self.w, W => self.spread_w::<W>(points, &weight, grid));
        self.fold(grid);
    }

    /// Spreads with the widest vector unit the CPU has. The arithmetic is the same IEEE operations
    /// in the same order on every path, with fused multiply-adds (`f64::mul_add`: one correctly
    /// rounded instruction with FMA, the C library's correctly rounded `fma` without), so the bits do
    /// not depend on the CPU.
    fn spread_w<const W: usize>(
        &self,
        points: &[[f64; 2]],
        weight: &impl Fn(usize) -> f64,
        grid: &mut [f64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if !self.coef_lanes.is_empty() && std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F, checked just above.
            unsafe { self.spread_w_avx512::<W>(points, weight, grid) };
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            unsafe { self.spread_w_avx2::<W>(points, weight, grid) };
            return;
        }
        self.spread_w_body::<W>(points, weight, grid);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn spread_w_avx2<const W: usize>(
        &self,
        points: &[[f64; 2]],
        weight: &impl Fn(usize) -> f64,
        grid: &mut [f64],
    ) {
        self.spread_w_body::<W>(points, weight, grid);
    }

    /// [`Grid::spread_w_body`] written with AVX-512 intrinsics: each dimension's `W` kernel values
    /// are one or two 8-lane vectors (rows of `coef_lanes`), so a Horner step is one or two fused
    /// multiply-adds, and a grid row of `W` values one or two masked fused multiply-adds. Each value
    /// goes through the same IEEE operations in the same order as in the body (lanes beyond `W` are
    /// computed on zero coefficients and never stored), so the grid has the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn spread_w_avx512<const W: usize>(
        &self,
        points: &[[f64; 2]],
        weight: &impl Fn(usize) -> f64,
        grid: &mut [f64],
    ) {
        use std::arch::x86_64::*;
        let side = self.n + W;
        let two_vectors = W > 8;
        let lo_mask: __mmask8 = if W >= 8 { 0xff } else { (1u8 << W) - 1 };
        let hi_mask: __mmask8 = if two_vectors {
            ((1u16 << (W - 8)) - 1) as u8
        } else {
            0
        };
        let (lead, rows) = self
            .coef_lanes
            .split_first_chunk::<LANES>()
            .expect("a kernel fit has a leading row");
        let (rows, _) = rows.as_chunks::<LANES>();
        let load = |c: &[f64; LANES]| -> (__m512d, __m512d) {
            // SAFETY: `c` holds LANES = 16 values.
            unsafe {
                (
                    _mm512_loadu_pd(c.as_ptr()),
                    _mm512_loadu_pd(c[8..].as_ptr()),
                )
            }
        };
        let (lead_lo, lead_hi) = load(lead);
        let mut kx = [0.0; LANES];
        for (j, p) in points.iter().enumerate() {
            check_finite(j, p);
            let (ax, sx) = self.node::<W>(p[0]);
            let (ay, sy) = self.node::<W>(p[1]);
            // The same u = 2s − 1 as in `values` (a product, then a difference).
            let ux = _mm512_set1_pd(2.0 * sx - 1.0);
            let uy = _mm512_set1_pd(2.0 * sy - 1.0);
            let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (lead_lo, lead_hi, lead_lo, lead_hi);
            for row in rows {
                let (c_lo, c_hi) = load(row);
                x_lo = _mm512_fmadd_pd(x_lo, ux, c_lo);
                y_lo = _mm512_fmadd_pd(y_lo, uy, c_lo);
                if two_vectors {
                    x_hi = _mm512_fmadd_pd(x_hi, ux, c_hi);
                    y_hi = _mm512_fmadd_pd(y_hi, uy, c_hi);
                }
            }
            // SAFETY: kx holds 16 values.
            unsafe {
                _mm512_storeu_pd(kx.as_mut_ptr(), x_lo);
                _mm512_storeu_pd(kx[8..].as_mut_ptr(), x_hi);
            }
            let c = weight(j);
            // The block of rows ax.., columns ay.. that the body writes (checked once per point).
            let first = ax * side + ay;
            assert!(
                first + (W - 1) * side + W <= grid.len(),
                "kernel block inside the grid"
            );
            for (l1, &vx) in kx[..W].iter().enumerate() {
                let cx = _mm512_set1_pd(c * vx);
                // SAFETY: the masked loads and stores touch entries first + l1·side + (0..W), inside
                // the grid (asserted above); masked-off lanes are not accessed.
                unsafe {
                    let at = grid.as_mut_ptr().add(first + l1 * side);
                    let g = _mm512_maskz_loadu_pd(lo_mask, at);
                    _mm512_mask_storeu_pd(at, lo_mask, _mm512_fmadd_pd(cx, y_lo, g));
                    if two_vectors {
                        let g = _mm512_maskz_loadu_pd(hi_mask, at.add(8));
                        _mm512_mask_storeu_pd(at.add(8), hi_mask, _mm512_fmadd_pd(cx, y_hi, g));
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn spread_w_body<const W: usize>(
        &self,
        points: &[[f64; 2]],
        weight: &impl Fn(usize) -> f64,
        grid: &mut [f64],
    ) {
        let side = self.n + W;
        // No closures in here: they might not be inlined, and would then lose the target features
        // of the caller (a libm call per fused multiply-add).
        for (j, p) in points.iter().enumerate() {
            check_finite(j, p);
            let mut at = [0; 2];
            let mut s = [0.0; 2];
            for d in 0..2 {
                (at[d], s[d]) = self.node::<W>(p[d]);
            }
            // One loop for both coordinates: two interleaved Horner recurrences (measured 10 % faster
            // than one after the other; more points at a time were slower).
            let [kx, ky] = self.values::<W, 2>(s);
            let c = weight(j);
            // Add c·kx ⊗ ky at rows at[0].., columns at[1].. of the padded grid. Grid rows follow x
            // (first coordinate), columns y (second, contiguous).
            let block = &mut grid[at[0] * side + at[1]..(at[0] + W - 1) * side + at[1] + W];
            for (l1, &vx) in kx.iter().enumerate() {
                let row: &mut [f64; W] = (&mut block[l1 * side..l1 * side + W])
                    .try_into()
                    .expect("W values");
                let cx = c * vx;
                for (g, &vy) in row.iter_mut().zip(&ky) {
                    *g = cx.mul_add(vy, *g);
                }
            }
        }
    }

    /// Interpolates the padded complex grid (side `n + W`) at each point.
    ///
    /// AVX2 with FMA where the CPU has them, else portable code (no AVX-512 path: vectorizing its
    /// sums would change their order, hence the bits).
    fn interp_w<const W: usize>(&self, grid: &[Complex64], points: &[[f64; 2]]) -> Vec<Complex64> {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            return unsafe { self.interp_w_avx2::<W>(grid, points) };
        }
        self.interp_w_body::<W>(grid, points)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn interp_w_avx2<const W: usize>(
        &self,
        grid: &[Complex64],
        points: &[[f64; 2]],
    ) -> Vec<Complex64> {
        self.interp_w_body::<W>(grid, points)
    }

    #[inline(always)]
    fn interp_w_body<const W: usize>(
        &self,
        grid: &[Complex64],
        points: &[[f64; 2]],
    ) -> Vec<Complex64> {
        let side = self.n + W;
        // A loop, not a closure: see spread_w_body.
        let mut out = Vec::with_capacity(points.len());
        for (j, p) in points.iter().enumerate() {
            check_finite(j, p);
            let (px, kx) = self.kernel_w::<W>(p[0]);
            let (py, ky) = self.kernel_w::<W>(p[1]);
            let mut g = Complex64::new(0.0, 0.0);
            for (l2, &vy) in ky.iter().enumerate() {
                let row = &grid[(py + l2) * side + px..][..W];
                let mut acc = Complex64::new(0.0, 0.0);
                for (u, &vx) in row.iter().zip(&kx) {
                    acc += u * vx;
                }
                g += acc * vy;
            }
            out.push(g);
        }
        out
    }

    /// Adds the padding rows and columns of a padded grid onto the periodic core they alias.
    fn fold(&self, grid: &mut [f64]) {
        let (n, off) = (self.n, self.w / 2);
        let side = n + self.w;
        for p in (0..off).chain(off + n..side) {
            let q = if p < off { p + n } else { p - n };
            let (src, dst) = (p * side, q * side);
            for c in 0..side {
                grid[dst + c] += grid[src + c];
            }
        }
        for r in off..off + n {
            let row = &mut grid[r * side..(r + 1) * side];
            for p in (0..off).chain(off + n..side) {
                let q = if p < off { p + n } else { p - n };
                row[q] += row[p];
            }
        }
    }

    /// Type 1 core: hands each output row `i` (all `k1`, `k2 = i − K/2`) to `emit_row(i, F)`.
    fn type1_into(
        &self,
        points: &[[f64; 2]],
        weight: impl Fn(usize) -> f64,
        mut emit_row: impl FnMut(usize, &[Complex64]),
    ) {
        let (n, k) = (self.n, self.res);
        let half = k / 2;
        self.type1_lines(points, weight, |lines, fft, row, _| {
            // Complex FFT along x for each kept k2 (batched: the buffer is K/2 + 1 lines of n).
            self.fwd.process_with_scratch(lines, fft);
            // Deconvolve and emit row by row: line k2 ≥ 0 holds B(k1, k2) at k1 mod n; a row with
            // k2 < 0 is the mirror of line −k2, since the grid is real: B(k1, k2) = conj(B(−k1, −k2)).
            // The work vector holds BLOCK / 2 packed lines of n ≥ K values.
            let g = &mut row[..k];
            for i in 0..k {
                let k2 = i as isize - half as isize;
                let a = k2.unsigned_abs();
                let line = &lines[a * n..(a + 1) * n];
                let c2 = self.corr[a];
                let (lo, hi) = g.split_at_mut(half);
                if k2 >= 0 {
                    // j < half: k1 = j − half < 0 at index n − half + j; j ≥ half: k1 = j − half.
                    for ((o, f), c) in lo
                        .iter_mut()
                        .zip(&line[n - half..])
                        .zip(self.corr[1..=half].iter().rev())
                    {
                        *o = f * (c * c2);
                    }
                    for ((o, f), c) in hi.iter_mut().zip(&line[..half]).zip(&self.corr[..half]) {
                        *o = f * (c * c2);
                    }
                } else {
                    // F(k1, k2) = conj(B(−k1, −k2)): −k1 = half − j, at index half − j for j ≤ half
                    // and n + half − j for j > half.
                    for ((o, f), c) in lo
                        .iter_mut()
                        .zip(line[1..=half].iter().rev())
                        .zip(self.corr[1..=half].iter().rev())
                    {
                        *o = f.conj() * (c * c2);
                    }
                    hi[0] = line[0].conj() * (self.corr[0] * c2);
                    for ((o, f), c) in hi[1..]
                        .iter_mut()
                        .zip(line[n - half + 1..].iter().rev())
                        .zip(&self.corr[1..half])
                    {
                        *o = f.conj() * (c * c2);
                    }
                }
                emit_row(i, g);
            }
        });
    }

    /// The power spectrum `P = |F|² / N` of type 1 with unit weights, as the `K/2 + 1` runs of the
    /// half plane `k2 ≥ 0`: `emit(a, run)` gets, for each `a = 0 ..= K/2` exactly once and in no
    /// particular order, `run[j] = P(j − K/2, a)` for `j = 0 ..= K` (one more value than a row, so
    /// that each row of the grid, `k2 ≥ 0` or its mirror `k2 < 0`, is a contiguous part of one run:
    /// see [`expand_half_plane`]); `inv_n = 1/N`.
    ///
    /// Only the modulus matters, so each bin takes one real factor instead of a complex
    /// deconvolution: `P = |B|² · (corr[|k1|]² · corr[|k2|]² / N)` with `B` the transformed fine grid
    /// (the squares `corr[|k1|]²` are tabulated at planning time, in run order, so that the loops run
    /// forward and vectorize).
    fn power_runs(&self, points: &[[f64; 2]], inv_n: f64, mut emit: impl FnMut(usize, &[f64])) {
        let (n, k) = (self.n, self.res);
        let half = k / 2;
        self.type1_lines(
            points,
            |_| 1.0,
            |lines, fft, _, work| {
                // Complex FFT along x for each kept k2 (batched: K/2 + 1 lines of n).
                self.fwd.process_with_scratch(lines, fft);
                fit(work, k + 1);
                let fac = &self.corr_sq_run;
                for a in 0..=half {
                    let line = &lines[a * n..(a + 1) * n];
                    let r = self.corr[a] * self.corr[a] * inv_n;
                    // k1 < 0 is at index n + k1 of the line, k1 ≥ 0 at index k1.
                    let (lo, hi) = work.split_at_mut(half);
                    for ((o, f), c) in lo.iter_mut().zip(&line[n - half..]).zip(&fac[..half]) {
                        *o = f.norm_sqr() * (c * r);
                    }
                    for ((o, f), c) in hi.iter_mut().zip(&line[..=half]).zip(&fac[half..]) {
                        *o = f.norm_sqr() * (c * r);
                    }
                    emit(a, &work[..]);
                }
            },
        );
    }

    /// Spreads the points and runs the row stage, then hands `body` the `K/2 + 1` lines (line `k2`
    /// holds, over x, the transform along y of the grid at `k2`; `n` values each), the FFT scratch
    /// (long enough for `fwd` in place), a free complex work slice of `BLOCK / 2 · n ≥ K` values and
    /// a free real work vector.
    ///
    /// Row stage: the grid is real, so two rows `a`, `b` go through one complex FFT as `z = a + i b`
    /// and are separated by Hermitian symmetry, `â(k) = (Z(k) + conj Z(−k)) / 2` and
    /// `b̂(k) = (Z(k) − conj Z(−k)) / (2i)` (exact halvings). [`BLOCK`] rows (`BLOCK / 2` packed lines)
    /// go through one batched rustfft call, and their separation is fused with the transpose into
    /// the lines, which then receive `BLOCK` contiguous values per `k2`. Measured on the development
    /// machine (n = 320, K = 256): 0.10 ms for the stage, against 0.12 ms for one realfft
    /// real-to-complex call per row followed by the same transpose (the row stage until 2026-11-23).
    fn type1_lines(
        &self,
        points: &[[f64; 2]],
        weight: impl Fn(usize) -> f64,
        body: impl FnOnce(&mut [Complex64], &mut [Complex64], &mut [Complex64], &mut Vec<f64>),
    ) {
        let (n, k, off) = (self.n, self.res, self.w / 2);
        let side = n + self.w;
        let ncols = k / 2 + 1;
        SCRATCH.with(|s| {
            let s = &mut *s.borrow_mut();
            reset(&mut s.real, side * side, 0.0);
            // Grid rows follow x (first coordinate), columns y (second, contiguous).
            self.spread(points, weight, &mut s.real);
            fit(&mut s.cplx, ncols * n);
            fit(&mut s.row, BLOCK / 2 * n);
            let zero = Complex64::new(0.0, 0.0);
            reset(&mut s.fft, self.fwd.get_inplace_scratch_len(), zero);
            // n is even, so every block holds whole pairs of rows.
            for m0 in (0..n).step_by(BLOCK) {
                let pairs = BLOCK.min(n - m0) / 2;
                let packed = &mut s.row[..pairs * n];
                for (p, z) in packed.chunks_exact_mut(n).enumerate() {
                    let r = (m0 + 2 * p + off) * side + off;
                    let (a, b) = (&s.real[r..r + n], &s.real[r + side..r + side + n]);
                    for ((z, a), b) in z.iter_mut().zip(a).zip(b) {
                        *z = Complex64::new(*a, *b);
                    }
                }
                self.fwd.process_with_scratch(packed, &mut s.fft);
                for k2 in 0..ncols {
                    // K/2 < n/2, so −k2 never aliases k2 except at 0.
                    let neg = (n - k2) % n;
                    let line = &mut s.cplx[k2 * n + m0..][..2 * pairs];
                    for (ab, z) in line.chunks_exact_mut(2).zip(packed.chunks_exact(n)) {
                        let (z, zc) = (z[k2], z[neg].conj());
                        let (sum, dif) = (z + zc, z - zc);
                        ab[0] = sum * 0.5;
                        ab[1] = Complex64::new(0.5 * dif.im, -0.5 * dif.re);
                    }
                }
            }
            body(&mut s.cplx, &mut s.fft, &mut s.row, &mut s.power)
        })
    }

    /// Type 2 on this grid (`coeffs` holds `K²` values; see [`Nufft2d::type2`]).
    fn type2(&self, coeffs: &[Complex64], points: &[[f64; 2]]) -> Vec<Complex64> {
        let (n, k, w, off) = (self.n, self.res, self.w, self.w / 2);
        let side = n + w;
        let half = k / 2;
        let zero = Complex64::new(0.0, 0.0);
        SCRATCH.with(|s| {
            let s = &mut *s.borrow_mut();
            // Stage 1: for each k1 (column j), the deconvolved coefficients over k2 on a length-n
            // vector, inverse FFT along y.
            reset(&mut s.row, k * n, zero);
            for i in 0..k {
                let k2 = i as isize - half as isize;
                let c2 = self.corr[k2.unsigned_abs()];
                let pos = k2.rem_euclid(n as isize) as usize;
                for j in 0..k {
                    let a = (j as isize - half as isize).unsigned_abs();
                    s.row[j * n + pos] = coeffs[i * k + j] * (c2 * self.corr[a]);
                }
            }
            let scratch_len = self.inv.get_inplace_scratch_len();
            reset(&mut s.fft, scratch_len, zero);
            self.inv.process_with_scratch(&mut s.row, &mut s.fft);
            // Stage 2: for each fine row y, scatter the k1 values and inverse FFT along x, straight into
            // the core of the padded grid; then extend the padding periodically.
            reset(&mut s.cplx, side * side, zero);
            for m2 in 0..n {
                let r = (m2 + off) * side;
                let line = &mut s.cplx[r + off..r + off + n];
                for j in 0..k {
                    let k1 = j as isize - half as isize;
                    line[k1.rem_euclid(n as isize) as usize] = s.row[j * n + m2];
                }
                self.inv.process_with_scratch(line, &mut s.fft);
                let row = &mut s.cplx[r..r + side];
                for p in (0..off).chain(off + n..side) {
                    row[p] = if p < off { row[p + n] } else { row[p - n] };
                }
            }
            for p in (0..off).chain(off + n..side) {
                let q = if p < off { p + n } else { p - n };
                s.cplx.copy_within(q * side..(q + 1) * side, p * side);
            }
            // Interpolate.
            let grid = &s.cplx;
            with_width!(w, W => self.interp_w::<W>(grid, points))
        })
    }
}

/// The error the accuracy contract of [`Nufft2d::new`] bounds: the maximum relative error of a power
/// spectrum `p` against the exact one, over the bins whose exact power is at least 1e-3 of the mean.
/// The one definition the tests (tests/nufft.rs) and the speed-against-error benchmark measure.
pub fn contract_error(p: &[f64], exact: &[f64]) -> f64 {
    let mean = exact.iter().sum::<f64>() / exact.len() as f64;
    p.iter()
        .zip(exact)
        .filter(|(_, e)| **e >= 1e-3 * mean)
        .map(|(a, e)| (a - e).abs() / e)
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::exact;
    use rand::Rng as _;

    #[test]
    fn every_grid_meets_the_contract() {
        // The cost model decides which grid a call uses; each grid a plan holds must meet the
        // contract on its own (random and jittered sets, K = 64 and 50).
        let mut rng = crate::rng::stream(51, 0);
        let random: Vec<[f64; 2]> = (0..600)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let m = 24;
        let jittered: Vec<[f64; 2]> = (0..m * m)
            .map(|c| {
                let (i, j) = ((c / m) as f64, (c % m) as f64);
                [
                    (j + rng.random::<f64>()) / m as f64,
                    (i + rng.random::<f64>()) / m as f64,
                ]
            })
            .collect();
        for res in [64, 50] {
            for pts in [&random, &jittered] {
                let n = pts.len() as f64;
                let reference: Vec<f64> = exact::fourier_sums(pts, res)
                    .iter()
                    .map(|f| f.norm_sqr() / n)
                    .collect();
                for eps in [1e-3, 1e-6, 1e-9] {
                    let plan = Nufft2d::new(res, eps).unwrap();
                    for g in &plan.grids {
                        let err = contract_error(&plan.power_on(g, pts), &reference);
                        assert!(
                            err <= 10.0 * eps,
                            "K={res} eps={eps:e} σ={} w={}: {err:e}",
                            g.sigma,
                            g.w
                        );
                    }
                }
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx512_spreading_has_the_bits_of_the_portable_one() {
        if !std::is_x86_feature_detected!("avx512f") {
            eprintln!("no AVX-512F on this CPU: nothing to compare");
            return;
        }
        let mut rng = crate::rng::stream(54, 0);
        let mut pts: Vec<[f64; 2]> = (0..500)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        // Points on grid nodes, at the torus' seam and outside [0, 1).
        pts.extend([[0.0, 0.0], [1.0 - 1e-17, 0.5], [-0.25, 3.75], [0.5, 0.5]]);
        let weights: Vec<f64> = (0..pts.len()).map(|_| rng.random::<f64>() - 0.3).collect();
        let mut widths = Vec::new();
        for eps in [1e-1, 3e-2, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8, 1e-10, 1e-12] {
            for g in Nufft2d::new(40, eps).unwrap().grids {
                if g.coef_lanes.is_empty() || widths.contains(&g.w) {
                    continue;
                }
                widths.push(g.w);
                let side = g.n + g.w;
                let (mut portable, mut wide) = (vec![0.0; side * side], vec![0.0; side * side]);
                with_width!(g.w, W => {
                    g.spread_w_body::<W>(&pts, &|j| weights[j], &mut portable);
                    // SAFETY: AVX-512F is available (checked above).
                    unsafe { g.spread_w_avx512::<W>(&pts, &|j| weights[j], &mut wide) };
                });
                assert!(
                    portable
                        .iter()
                        .zip(&wide)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "w = {}: the two paths differ",
                    g.w
                );
            }
        }
        widths.sort();
        // Both the one-vector (w ≤ 8) and the two-vector (w > 8) layouts, up to the widest kernel.
        assert!(
            widths.iter().any(|&w| w <= 8) && widths.contains(&16),
            "{widths:?}"
        );
    }

    #[test]
    fn power_is_the_squared_modulus_of_type1() {
        // The power path (real factors, rows k2 < 0 mirrored) against |F|²/N from the complex
        // type 1 on the same grid, for every grid, including K = 2 where row 0 is the only k2 < 0.
        let mut rng = crate::rng::stream(53, 0);
        let pts: Vec<[f64; 2]> = (0..200)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let inv_n = 1.0 / pts.len() as f64;
        for res in [2, 6, 50] {
            let plan = Nufft2d::new(res, 1e-6).unwrap();
            for g in &plan.grids {
                let mut reference = vec![0.0; res * res];
                g.type1_into(
                    &pts,
                    |_| 1.0,
                    |i, f| {
                        for (o, f) in reference[i * res..].iter_mut().zip(f) {
                            *o = f.norm_sqr() * inv_n;
                        }
                    },
                );
                let got = plan.power_on(g, &pts);
                for (i, (a, b)) in got.iter().zip(&reference).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
                        "K={res} σ={} bin {i}: {a} vs {b}",
                        g.sigma
                    );
                }
            }
        }
    }

    #[test]
    fn accumulated_power_has_the_bits_of_power() {
        // Half-plane sums of P and (P − shift)² over sets (one empty), expanded, against the sums of
        // `power`'s output, bit for bit.
        let mut rng = crate::rng::stream(55, 0);
        let sets: Vec<Vec<[f64; 2]>> = [150, 0, 90]
            .iter()
            .map(|&m| {
                (0..m)
                    .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
                    .collect()
            })
            .collect();
        for res in [2, 6, 50] {
            let plan = Nufft2d::new(res, 1e-6).unwrap();
            let len = half_plane_len(res);
            let (mut sum, mut sum_sq) = (vec![0.0; len], vec![0.0; len]);
            let shift: Vec<f64> = (0..len).map(|i| 0.5 + i as f64).collect();
            let shift_grid = expand_half_plane(&shift, res);
            let (mut want, mut want_sq) = (vec![0.0; res * res], vec![0.0; res * res]);
            for pts in &sets {
                plan.accumulate_power(pts, &shift, &mut sum, &mut sum_sq);
                let p = plan.power(pts);
                for (((s, q), c), p) in want.iter_mut().zip(&mut want_sq).zip(&shift_grid).zip(p) {
                    *s += p;
                    *q += (p - c) * (p - c);
                }
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let full = expand_half_plane(&sum, res);
            let full_sq = expand_half_plane(&sum_sq, res);
            assert_eq!(bits(&full), bits(&want), "K={res}: sums");
            assert_eq!(bits(&full_sq), bits(&want_sq), "K={res}: sums of squares");
        }
    }

    #[test]
    fn every_grid_matches_the_exact_type2() {
        let mut rng = crate::rng::stream(52, 0);
        let pts: Vec<[f64; 2]> = (0..300)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let res = 48;
        let coeffs: Vec<Complex64> = (0..res * res)
            .map(|_| Complex64::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5))
            .collect();
        let reference = exact::type2(&coeffs, &pts, res);
        let den: f64 = reference.iter().map(|y| y.norm_sqr()).sum();
        for eps in [1e-3, 1e-6, 1e-9] {
            let plan = Nufft2d::new(res, eps).unwrap();
            for g in &plan.grids {
                let got = g.type2(&coeffs, &pts);
                let num: f64 = got
                    .iter()
                    .zip(&reference)
                    .map(|(x, y)| (x - y).norm_sqr())
                    .sum();
                let err = (num / den).sqrt();
                assert!(err <= 10.0 * eps, "eps={eps:e} σ={}: {err:e}", g.sigma);
            }
        }
    }

    #[test]
    fn deconvolution_quadrature_is_converged() {
        let plan = Nufft2d::new(64, 1e-6).unwrap();
        assert_eq!(plan.grids.len(), GRIDS.len(), "every σ can reach 1e-6");
        for g in &plan.grids {
            let half_w = g.w as f64 / 2.0;
            let rule = gauss_legendre(8 * g.w + 200);
            for k in 0..=32 {
                let a = 2.0 * PI * k as f64 * half_w / g.n as f64;
                let s: f64 = rule
                    .iter()
                    .map(|&(z, q)| q * g.phi(z) * (a * z).cos())
                    .sum();
                let fine = 1.0 / (half_w * s);
                // The quadrature sums terms of total size ≈ ψ̂(0) to get ψ̂(k): the rounding error,
                // relative to ψ̂(k), grows like ψ̂(0)/ψ̂(k) = corr[k]/corr[0] (large at the band edge
                // when σ is small).
                let cancellation = (g.corr[k] / g.corr[0]).max(1.0);
                assert!(
                    (fine - g.corr[k]).abs() <= 1e-13 * cancellation * fine.abs(),
                    "σ={} k={k}: {fine} vs {}",
                    g.sigma,
                    g.corr[k]
                );
            }
        }
    }

    #[test]
    fn the_cost_model_trades_fft_size_for_kernel_width() {
        // K = 256, eps = 1e-6: few points favour the smallest grid, many points the narrowest kernel.
        let plan = Nufft2d::new(256, 1e-6).unwrap();
        let few = plan.grid(4096);
        let many = plan.grid(1 << 20);
        assert_eq!(few.sigma, 1.25, "{few:?}");
        assert_eq!(many.sigma, 2.0, "{many:?}");
        assert!(few.size < many.size && few.kernel_width > many.kernel_width);
        // eps = 1e-12 is beyond the σ < 2 kernels.
        let strict = Nufft2d::new(256, 1e-12).unwrap();
        assert_eq!(strict.grid(10).sigma, 2.0);
    }

    #[test]
    fn smooth_sizes() {
        assert_eq!(next_smooth_even(512), 512);
        assert_eq!(next_smooth_even(513), 540);
        assert_eq!(next_smooth_even(7), 8);
        assert_eq!(next_smooth_even(14), 16);
    }
}
