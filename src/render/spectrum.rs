//! A pixel integrand's slice spectra (issue 4 item 5): `|f̂|²` on a 2D frequency grid for a projection
//! such as `xu` or `yv`.
//!
//! For a projection `(a, b)` the other two coordinates are **averaged**: the grid holds
//! `g(c_a, c_b) = ∫∫ f dc_other` estimated by the midpoint rule on an `m × m` grid of the other two
//! coordinates (`m = 1` fixes them to ½ instead). By the projection-slice theorem the 2D DFT of `g` is
//! the slice `k_other = 0` of the 4D spectrum: exactly the part of `f̂` that meets the `(a, b)`
//! projection of a sampling spectrum in the variance formula of DESIGN §4.
//!
//! `g` is sampled at the cell centres `(j + ½)/K, (i + ½)/K` of a `K × K` grid and transformed with
//! rustfft ([`sampled_power`]). The result is `|f̂(k1, k2)|²` with `f̂(k) ≈ (1/K²) Σ g e^{−2πi k·c}`,
//! laid out like every spectrum of the project: `P[i·K + j]` at `k1 = j − K/2` (first projected dim), `k2 = i − K/2`.
//! Sampled on the `K × K` grid itself, a pixel's edges alias, most near the grid's border and where
//! `|f̂|²` is small (measured at pixel (30, 40), `K = 64` against `K = 512`: −1 % at `k = (12, 0)`,
//! −5 % at `(10, −7)`, +17 % at `(5, 3)`, −13 % at `(30, −21)`, a factor 2.5 at `(31, 0)`), so values
//! up to `k_max` want `K ≥ 4 k_max`, as the variance code samples (`m ≥ 4K`).

use crate::error::Result;
use crate::integrands::sampled::sampled_power;
use crate::points::Projection;
use crate::spectrum::check_res;

/// The `res × res` slice spectrum of `f` (e.g. `|p| pixel.value(p)`) for `proj`, averaging the other two coordinates over an
/// `average × average` midpoint grid. `res` must be even and positive; `average ≥ 1`.
pub fn slice_spectrum<F>(f: F, proj: Projection, res: usize, average: usize) -> Result<Vec<f64>>
where
    F: Fn([f64; 4]) -> f64 + Sync,
{
    check_res(res)?;
    if average == 0 {
        return Err(crate::error::Error::Usage(
            "--average 0 averages over nothing; use 1 (fix the other coordinates to 1/2) or more"
                .into(),
        ));
    }
    let others: Vec<usize> = (0..4).filter(|&d| d != proj.a && d != proj.b).collect();
    let m = average as f64;
    let averaged = |a: f64, b: f64| {
        let mut p = [0.5; 4];
        p[proj.a] = a;
        p[proj.b] = b;
        let mut sum = 0.0;
        for i in 0..average {
            for j in 0..average {
                p[others[0]] = (i as f64 + 0.5) / m;
                p[others[1]] = (j as f64 + 0.5) / m;
                sum += f(p);
            }
        }
        sum / (m * m)
    };
    Ok(sampled_power(averaged, res, res))
}

/// Smallest side of the PNG view; smaller grids are scaled up by an integer factor (nearest).
pub const PNG_MIN_SIDE: usize = 512;

/// Decades below the largest `P` that the PNG view spans (black below them).
const PNG_DECADES: f64 = 6.0;

/// How the PNG view of an integrand's spectrum ([`spectrum_png_pixels`]) reads (ASCII); a point set's
/// spectrum PNG has a fixed range instead ([`crate::output::image::spectrum_png_key`]).
pub fn integrand_png_key() -> String {
    format!(
        "log10(P / max P) from -{PNG_DECADES} (black) to 0 (white), the max taken over k != 0; k1 right, k2 up, k = 0 at the centre"
    )
}

/// The PNG view of an integrand spectrum: `log10(P / max_{k≠0} P)` mapped from `[−6, 0]`
/// ([`PNG_DECADES`]) to 0..255,
/// largest `k2` on top, scaled up by an integer factor to at least [`PNG_MIN_SIDE`] pixels; the DC bin
/// (the squared mean) is left out of the maximum. Returns the side and the grey pixels.
pub fn spectrum_png_pixels(p: &[f64], res: usize) -> (usize, Vec<u8>) {
    let dc = (res / 2) * res + res / 2;
    let max = p
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != dc)
        .map(|(_, &v)| v)
        .fold(f64::MIN_POSITIVE, f64::max);
    let grey: Vec<u8> = crate::output::image::spectrum_image_rows(p, res)
        .iter()
        .map(|&v| {
            let l = if v > 0.0 {
                (v / max).log10()
            } else {
                -PNG_DECADES
            };
            (((l + PNG_DECADES) / PNG_DECADES).clamp(0.0, 1.0) * 255.0).round() as u8
        })
        .collect();
    crate::output::image::upscaled(&grey, res, PNG_MIN_SIDE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single Fourier mode in `xu` has `|f̂|² = 1/4` at `±k` and nothing elsewhere (it is band-limited
    /// below K/2, so the cell-centre DFT is exact); the averaged `y, v` do not matter.
    #[test]
    fn single_mode_lands_on_its_bins() {
        let f = |p: [f64; 4]| {
            (2.0 * std::f64::consts::PI * (3.0 * p[0] - 2.0 * p[2])).cos() + 0.1 * p[1]
        };
        let res = 16;
        let s = slice_spectrum(f, Projection::XU, res, 4).unwrap();
        for i in 0..res {
            for j in 0..res {
                let (k1, k2) = crate::spectrum::frequency(i * res + j, res);
                let v = s[i * res + j];
                let expect = if (k1, k2) == (3, -2) || (k1, k2) == (-3, 2) {
                    0.25
                } else if (k1, k2) == (0, 0) {
                    0.05f64.powi(2)
                } else {
                    0.0
                };
                assert!((v - expect).abs() < 1e-12, "k=({k1},{k2}): {v} vs {expect}");
            }
        }
        assert!(slice_spectrum(f, Projection::XU, 15, 4).is_err());
        assert!(slice_spectrum(f, Projection::XU, 16, 0).is_err());
    }
}
