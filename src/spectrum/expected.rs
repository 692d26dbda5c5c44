//! Expected power spectra: the mean of `P(k)` over independent realizations, with its standard error
//! (DESIGN §3).

use super::{check_res, Method, PowerSums};
use crate::error::{Error, Result};
use crate::points::{project, PointSets, Projection};
use crate::progress;
use crate::rng;
use crate::samplers::{validate_n, Sampler};
use rayon::prelude::*;

/// The mean spectrum over `realizations` sets of `n` points on a `res × res` grid, and its standard
/// error (grid layout: see [`crate::spectrum`]).
#[derive(Clone, Debug)]
pub struct ExpectedSpectrum {
    /// Grid side `K`.
    pub res: usize,
    /// Points per set.
    pub n: usize,
    /// Number of realizations averaged.
    pub realizations: usize,
    /// `E[P(k)]`, `K²` values.
    pub mean: Vec<f64>,
    /// Standard error of `mean` per bin (`sqrt(sample variance / R)`); all zero when `R = 1`, where it is
    /// unknown — check `realizations`.
    pub stderr: Vec<f64>,
}

/// Realizations summed sequentially inside one parallel task: the summation order, hence the bits, do
/// not depend on the thread count.
const CHUNK: usize = 4;
/// Chunks held in memory at once, at most (see `expected_spectrum`).
const CHUNKS_PER_BATCH: usize = 16;
/// Chunks per batch and thread: enough to balance the threads, few enough that the partial sums of
/// a batch stay small on few threads.
const CHUNKS_PER_THREAD: usize = 4;
/// Bytes the partial sums of one batch may hold: at K = 8192 one chunk's sums are 537 MB, so a batch
/// holds three chunks there (16 would be 8.6 GB); at K = 4096, 15 with the NUFFT (half-plane sums)
/// and 8 with the exact DFT (whole-grid sums).
const BATCH_BYTES: usize = 1 << 31;

/// Averages the spectra of `realizations` projected point sets, `draw(r)` giving realization `r`.
pub fn expected_spectrum<F>(
    realizations: usize,
    res: usize,
    method: Method,
    label: &str,
    draw: F,
) -> Result<ExpectedSpectrum>
where
    F: Fn(usize) -> Vec<[f64; 2]> + Sync,
{
    check_res(res)?;
    if realizations == 0 {
        return Err(Error::Usage(
            "--realizations 0 averages nothing; give at least 1 (2 or more for standard errors)"
                .into(),
        ));
    }
    let bar = progress::bar(realizations as u64, label);
    // Shifted by the first realization's spectrum, so that the variance does not cancel (see
    // [`PowerSums`]); that spectrum then takes its place in the sums as it is, not computed again.
    let (mut total, first_len) = if realizations < 2 {
        (PowerSums::new(res, method), None)
    } else {
        let first = draw(0);
        (
            PowerSums::shifted_by(res, method, &first),
            Some(first.len()),
        )
    };
    let mut n = 0;
    // Batches bound the memory; their boundaries do not change the summation order (chunk by
    // chunk, in order), so their size may follow the thread count without changing the bits.
    let per_batch = CHUNKS_PER_BATCH
        .min(CHUNKS_PER_THREAD * rayon::current_num_threads())
        .min((BATCH_BYTES / total.bytes()).max(1));
    let batch = CHUNK * per_batch;
    // The partial sums of each chunk of a batch (and its points per set), allocated once and
    // zeroed per batch: fresh vectors per chunk page-faulted on every batch (the allocator hands
    // the freed batch back to the system), ≈ 30 % of the time at K = 256.
    let mut partial: Vec<(PowerSums, usize)> = (0..realizations.div_ceil(CHUNK).min(per_batch))
        .map(|_| (total.zeroed_like(), 0))
        .collect();
    for start in (0..realizations).step_by(batch) {
        let end = (start + batch).min(realizations);
        let chunks = &mut partial[..(end - start).div_ceil(CHUNK)];
        chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, (sums, count))| {
                sums.clear();
                let c0 = start + c * CHUNK;
                for r in c0..(c0 + CHUNK).min(end) {
                    match first_len {
                        Some(len) if r == 0 => {
                            *count = len;
                            sums.add_shift();
                        }
                        _ => {
                            let pts = draw(r);
                            *count = pts.len();
                            sums.add(&pts);
                        }
                    }
                    bar.inc(1);
                }
            });
        for (sums, count) in chunks.iter() {
            n = *count;
            total.add_sums(sums);
        }
    }
    bar.finish_and_clear();
    let (mean, stderr) = total.mean_and_stderr(realizations);
    Ok(ExpectedSpectrum {
        res,
        n,
        realizations,
        mean,
        stderr,
    })
}

/// The expected spectrum of `sampler` in projection `proj`: realization `r` is set `r` of `seed`
/// (the same sets as `anisospec sample` with that seed). At most [`crate::stats::MAX_REALIZATIONS`]
/// realizations.
pub fn of_sampler(
    sampler: &dyn Sampler,
    n: usize,
    proj: Projection,
    res: usize,
    realizations: usize,
    seed: u64,
    method: Method,
) -> Result<ExpectedSpectrum> {
    crate::stats::check_realizations("--realizations", realizations)?;
    validate_n(sampler, n)?;
    let dims = sampler.dims();
    expected_spectrum(realizations, res, method, &sampler.name(), |r| {
        project(
            &sampler.generate(n, &mut rng::stream(seed, r as u64)),
            dims,
            proj,
        )
    })
}

/// The expected spectrum over every set of a stored point set.
pub fn of_sets(
    sets: &PointSets,
    proj: Projection,
    res: usize,
    method: Method,
) -> Result<ExpectedSpectrum> {
    expected_spectrum(sets.sets(), res, method, "point sets", |r| {
        sets.project(r, proj)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng as _;

    /// A rank-1 lattice, shifted at random on the torus per realization, has the same `P` in every
    /// realization up to rounding (`P = N` on its dual lattice): the standard error stays at the
    /// rounding of the values themselves, as the two-pass formula over the sets gives it, where
    /// `Σ P² − (Σ P)² / R` would leave about `sqrt(ε) N` (1.5e-8 relative) or exactly 0.
    #[test]
    fn a_spectrum_that_hardly_varies_has_a_rounding_level_standard_error() {
        let (n, res, reps) = (1024, 64, 20);
        let draw = |r: usize| {
            let mut rng = rng::stream(91, r as u64);
            let (sx, sy) = (rng.random::<f64>(), rng.random::<f64>());
            (0..n)
                .map(|i| {
                    let x = i as f64 / n as f64;
                    let y = ((i * 619) % n) as f64 / n as f64;
                    [(x + sx).fract(), (y + sy).fract()]
                })
                .collect::<Vec<_>>()
        };
        for method in [Method::Exact, Method::nufft(1e-9).unwrap()] {
            let got = expected_spectrum(reps, res, method, "lattice", draw).unwrap();
            let spectra: Vec<Vec<f64>> = (0..reps)
                .map(|r| super::super::power(&draw(r), res, method))
                .collect();
            let mut peaks = 0;
            for bin in 0..res * res {
                let values: Vec<f64> = spectra.iter().map(|p| p[bin]).collect();
                let mean = values.iter().sum::<f64>() / reps as f64;
                let var =
                    values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (reps - 1) as f64;
                let two_pass = (var / reps as f64).sqrt();
                let tol = 1e-6 * two_pass + 2.0 * f64::EPSILON * mean.abs();
                assert!(
                    (got.stderr[bin] - two_pass).abs() <= tol,
                    "{method:?} bin {bin}: P {mean:e}, standard error {:e}, two-pass {two_pass:e}",
                    got.stderr[bin]
                );
                peaks += usize::from(mean > 0.5 * n as f64);
            }
            assert!(
                peaks > 1,
                "{method:?}: the lattice's dual points in the grid"
            );
        }
    }
}
