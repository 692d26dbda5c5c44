//! Fourier coefficients of a function of two coordinates sampled on a grid: for integrands that have
//! no closed form in the frame where they are needed, e.g. an integrand pulled back through the shear
//! that moves a sample pattern (variance targets, the variance prediction of sheared samplers).

use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

/// `|ĝ(k)|²` on the `res × res` grid of DESIGN §3 (`[i * res + j]`, `k1 = j − res/2`,
/// `k2 = i − res/2`) for `g(a, b) = eval(a, b)` on the unit torus, from samples at the centres of an
/// `m × m` grid (`m ≥ res`), an FFT along the second coordinate, then along the first for the kept
/// `k2` only. A jump in `g` makes a sampled coefficient differ from the true one by about `|k| / m`
/// relative (aliasing), so callers take `m` several times the largest `|k|`.
pub fn sampled_power(eval: impl Fn(f64, f64) -> f64 + Sync, res: usize, m: usize) -> Vec<f64> {
    let fft = FftPlanner::new().plan_fft_forward(m);
    let scale = 1.0 / (m * m) as f64;
    let half = (res / 2) as i64;
    let bin = |k: i64| k.rem_euclid(m as i64) as usize;
    // kept[i * res + c]: the first coordinate at (i + ½)/m, transformed along the second, at the kept
    // k2 = c − res/2 alone. Keeping `res` of each row's `m` coefficients takes m/res times less
    // memory than the whole grid (268 MB at m = 4096), whose fresh pages cost more system time
    // than its transforms took.
    let mut kept: Vec<Complex64> = vec![Complex64::new(0.0, 0.0); m * res];
    kept.par_chunks_exact_mut(res).enumerate().for_each_init(
        || vec![Complex64::new(0.0, 0.0); m],
        |row, (i, out)| {
            let a = (i as f64 + 0.5) / m as f64;
            for (j, z) in row.iter_mut().enumerate() {
                let b = (j as f64 + 0.5) / m as f64;
                *z = Complex64::new(eval(a, b) * scale, 0.0);
            }
            fft.process(row);
            for (c, o) in out.iter_mut().enumerate() {
                *o = row[bin(c as i64 - half)];
            }
        },
    );
    // One column per kept k2, transformed along the first coordinate: row c of the output.
    let mut out = vec![0.0; res * res];
    out.par_chunks_exact_mut(res).enumerate().for_each_init(
        || vec![Complex64::new(0.0, 0.0); m],
        |col, (c, out)| {
            for (i, z) in col.iter_mut().enumerate() {
                *z = kept[i * res + c];
            }
            fft.process(col);
            for (j, v) in out.iter_mut().enumerate() {
                *v = col[bin(j as i64 - half)].norm_sqr();
            }
        },
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FFT path against the definition it computes, a direct sum over the samples:
    /// `ĝ(k) = (1/m²) Σ g((i + ½)/m, (j + ½)/m) e^{−2πi (k1 (i + ½) + k2 (j + ½)) / m}`, for a step
    /// (every frequency lit) on a grid small enough to sum directly. Rounding of the 1024-term sums
    /// is about 1e-16 of the largest |ĝ|² (g's mean², here 0.3²).
    #[test]
    fn the_transform_is_the_direct_sum_of_the_samples() {
        let g = |a: f64, b: f64| if a + 0.3 * b < 0.6 { 1.0 } else { 0.0 } * (1.0 + a * b);
        let (res, m) = (8, 32);
        let fast = sampled_power(g, res, m);
        let half = (res / 2) as i64;
        let mut worst: f64 = 0.0;
        for (idx, &p) in fast.iter().enumerate() {
            let (k1, k2) = ((idx % res) as i64 - half, (idx / res) as i64 - half);
            let mut sum = Complex64::new(0.0, 0.0);
            for i in 0..m {
                for j in 0..m {
                    let (a, b) = ((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
                    let phase = -2.0 * std::f64::consts::PI * (k1 as f64 * a + k2 as f64 * b);
                    sum += Complex64::from_polar(g(a, b), phase);
                }
            }
            let direct = (sum / (m * m) as f64).norm_sqr();
            worst = worst.max((p - direct).abs());
        }
        assert!(worst < 1e-14, "largest difference {worst:e}");
    }
}
