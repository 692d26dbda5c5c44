//! Power spectra of point sets (DESIGN §3): exact DFT, type-1 NUFFT, expected spectra over
//! realizations, and radial / anisotropy / directional-cone profiles.
//!
//! Grid convention everywhere: a `K × K` row-major array with `P[i * K + j]` at `k1 = j − K/2`
//! (first projected dimension) and `k2 = i − K/2` (second).

pub mod exact;
pub mod expected;
pub mod profiles;

use crate::error::{Error, Result};
use rustfft::num_complex::Complex64;

/// How Fourier sums are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// The exact DFT, `O(N K²)`: the reference.
    Exact,
    /// The type-1 non-uniform FFT with relative tolerance `eps`.
    Nufft {
        /// Requested tolerance, in `[1e-14, 1e-1]`.
        eps: f64,
    },
}

impl Method {
    /// The NUFFT with tolerance `eps`, checked to lie in `[1e-14, 1e-1]`.
    pub fn nufft(eps: f64) -> Result<Self> {
        if !(1e-14..=1e-1).contains(&eps) {
            return Err(Error::Usage(format!(
                "--eps {eps} is outside [1e-14, 1e-1]; the NUFFT tolerance is a relative error, e.g. --eps 1e-6"
            )));
        }
        Ok(Method::Nufft { eps })
    }
}

/// Checks a spectrum resolution `K`: even and positive.
pub fn check_res(res: usize) -> Result<()> {
    if res == 0 || res % 2 == 1 {
        return Err(Error::Usage(format!(
            "--res {res} is not a positive even number; the frequency grid k = -K/2..K/2-1 needs K even, e.g. --res {}",
            (res + 1).max(2) / 2 * 2
        )));
    }
    Ok(())
}

/// The Fourier sums `F(k) = Σ_j exp(−2πi k·x_j)` of 2D points on the `res × res` grid.
pub fn fourier_sums(points: &[[f64; 2]], res: usize, method: Method) -> Vec<Complex64> {
    match method {
        Method::Exact => exact::fourier_sums(points, res),
        Method::Nufft { .. } => exact::fourier_sums(points, res),
    }
}

/// The power spectrum `P(k) = |F(k)|² / N` of 2D points on the `res × res` grid.
pub fn power(points: &[[f64; 2]], res: usize, method: Method) -> Vec<f64> {
    let n = points.len() as f64;
    fourier_sums(points, res, method)
        .iter()
        .map(|f| f.norm_sqr() / n)
        .collect()
}
