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
    // rows[i]: the first coordinate at (i + ½)/m, transformed along the second.
    let mut rows: Vec<Complex64> = vec![Complex64::new(0.0, 0.0); m * m];
    rows.par_chunks_exact_mut(m)
        .enumerate()
        .for_each(|(i, row)| {
            let a = (i as f64 + 0.5) / m as f64;
            for (j, z) in row.iter_mut().enumerate() {
                let b = (j as f64 + 0.5) / m as f64;
                *z = Complex64::new(eval(a, b) * scale, 0.0);
            }
            fft.process(row);
        });
    let half = (res / 2) as i64;
    let bin = |k: i64| k.rem_euclid(m as i64) as usize;
    // One column per kept k2, transformed along the first coordinate.
    let columns: Vec<Vec<Complex64>> = (-half..half)
        .into_par_iter()
        .map(|k2| {
            let mut col: Vec<Complex64> = (0..m).map(|i| rows[i * m + bin(k2)]).collect();
            fft.process(&mut col);
            col
        })
        .collect();
    let mut out = vec![0.0; res * res];
    for (i, col) in columns.iter().enumerate() {
        for (j, v) in out[i * res..(i + 1) * res].iter_mut().enumerate() {
            *v = col[bin(j as i64 - half)].norm_sqr();
        }
    }
    out
}
