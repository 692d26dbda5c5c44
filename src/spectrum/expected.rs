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
    let bins = res * res;
    let bar = progress::bar(realizations as u64, label);
    let mut total = PowerSums::new(res, method);
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
        .map(|_| (PowerSums::new(res, method), 0))
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
                    let pts = draw(r);
                    *count = pts.len();
                    sums.add(&pts);
                    bar.inc(1);
                }
            });
        for (sums, count) in chunks.iter() {
            n = *count;
            total.add_sums(sums);
        }
    }
    bar.finish_and_clear();
    let (sum, sum_sq) = total.into_grids();
    let r = realizations as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / r).collect();
    let stderr = if realizations < 2 {
        vec![0.0; bins]
    } else {
        mean.iter()
            .zip(&sum_sq)
            .map(|(m, s2)| ((s2 / r - m * m).max(0.0) * r / (r - 1.0) / r).sqrt())
            .collect()
    };
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
