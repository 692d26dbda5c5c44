//! Spectrum benchmarks (DESIGN §3).
//!
//! (a) `expected_spectrum`: the expected power spectrum of R = 100 random sets, N = 4096, K = 256,
//!     eps = 1e-6, on ONE thread: 100 × `power()`, summed, and the library's
//!     `expected::expected_spectrum` (sums of P and P², standard errors) of the same sets.
//! (b) `exact_one_realization`: one exact DFT power spectrum of the same size (N = 4096, K = 256) on
//!     one thread: the reference of the "1000× faster than exact" target of issue 2.
//! (c) `exact_vs_nufft`: exact DFT against NUFFT (eps = 1e-6) for N = 1024, K = 64, one thread.
//! (d) `speed_vs_error`: one NUFFT power spectrum (N = 4096, K = 256) per eps = 1e-2 … 1e-12, with the
//!     max relative error of P against the exact DFT (bins above 1e-3 of the mean), measured once
//!     outside the timing loop. The table is printed to stderr and written to
//!     `target/criterion/nufft_speed_vs_error.csv` (time per transform there is a plain wall-clock
//!     mean over 20 runs; criterion's own figures are in its report).
//!
//! Figures (2-core AMD EPYC shared with other jobs, load ≈ 3.4; the old and new code run alternately
//! in the same minutes; times ±10 %):
//!
//! | eps   | before: w, n, ms, max err P | after: w, n, ms, max err P |
//! |-------|-----------------------------|----------------------------|
//! | 1e-3  | 6, 512, 0.88, 9.6e-4        | 10, 320, 0.41, 4.9e-4      |
//! | 1e-6  | 9, 512, 0.86, 2.7e-6        | 14, 320, 0.47, 1.2e-6      |
//! | 1e-9  | 12, 512, 0.92, 3.5e-9       | 12, 512, 0.75, 3.5e-9      |
//! | 1e-12 | 15, 512, 1.04, 5.9e-12      | 16, 512, 0.81, 1.3e-12     |
//!
//! `expected_spectrum`: 97–99 ms before, 51–54 ms after (0.51 ms per realization); one exact
//! realization: 288–291 ms, so the NUFFT is ≈ 570× faster than the exact DFT (≈ 300× before), short of
//! the 1000× target. The floor at n = 320 (σ = 1.25): real-to-complex row FFTs 0.12 ms, transpose
//! 0.03 ms, column FFTs 0.07 ms, deconvolution 0.03 ms, zeroing 0.01 ms, i.e. ≈ 0.26 ms of the
//! 0.29 ms budget before any spreading (0.20 ms at w = 14); smaller σ would need w > 16.
//!
//! On a newer machine of the same kind (AMD EPYC family 26, with 512-bit AVX-512; 2026-11-23, load
//! 2.7–3.6): `expected_spectrum` 38–41 ms (0.39 ms per realization), one exact realization 251–259 ms,
//! so ≈ 650×. Spreading merely compiled for AVX-512F (a third `target_feature` path of the same
//! code) ran 41–45 ms against 40–41 ms for the AVX2 path, so it was not kept.
//!
//! AVX-512 spreading written with intrinsics (same machine, 2026-11-23, load 1–3; old and new
//! binaries alternated): one or two 8-lane vectors per kernel row, masked grid updates; spreading
//! 0.16–0.21 ms → 0.13–0.17 ms per realization. What limits it now: with the kernel values held
//! constant spreading still takes 0.11–0.12 ms, without the grid updates 0.056 ms, so the `w` masked
//! read-modify-writes of 2 vectors per point (the grid is 892 KB, about the size of L2) dominate.
//! Tried and not kept, each measured with its own cost included: two points per Horner loop (more
//! independent multiply-adds), sorting the points by tiles of 16 × 16 grid cells or by strips of
//! rows (counting sort), software prefetch of the next point's rows, 64-byte aligned windows (no
//! split cache lines), 2 MB pages for the grid: none beat the noise (±10 %). A kernel fit 100×
//! looser lowers the Horner degree only from 10 to 9 at w = 14.
//!
//! FFT stages rewritten (same machine, 2026-11-23, load 1.0–3.4 from another build; old and new
//! binaries alternated): `expected_spectrum` best 36.8 ms before, 33.8 ms after (medians of six
//! alternating 4 s runs: ≈ 44 and ≈ 36 ms); per realization of `power` (best of 10 × 100 calls,
//! ten alternations) 0.352 ms before, 0.315 ms after, i.e. ≈ 800× the exact DFT's ≈ 255 ms. Stage
//! means per realization before → after: row stage (FFT along y and transpose) 0.116 → 0.096 ms
//! (two real rows packed per complex line, 16 lines per rustfft call: 0.063 ms of FFTs, the rest
//! packing and the separation fused with the transpose); column FFTs, deconvolution and power
//! 0.051 + 0.023 ms plus the mirroring pass → 0.075 ms; zeroing 0.008 and spreading 0.155 ms unchanged.
//!
//! Power rows and accumulated sums (same machine, 2026-11-23, load 1.1–2.8; old and new bench
//! binaries alternated): the library's `expected_spectrum` (sums of P and P²) 48.6–49.9 ms before,
//! 36.2–38.3 ms after (≈ 0.49 → 0.37 ms per realization): `Nufft2d::accumulate_power` adds each
//! row of P into the sums while in cache instead of writing the K² spectrum out and reading it back
//! (≈ 6 %), and the partial sums are reused across batches, 4 chunks per thread, instead of fresh
//! 16 MB per batch that page-faulted (≈ 30 % of the run in the kernel before). `power()` summed by
//! hand: 31.7–32.6 ms before, 31.2–33.4 ms after, i.e. unchanged at ≈ 0.32 ms per realization (the
//! vectorized reversed copy for k2 < 0 saves about what the row copy out of the work run costs).
//!
//! All of it together (same machine, 2026-11-23, load 0.6–1.6, one `cargo bench` run):
//! `expected_spectrum` 31.1–32.1 ms by hand (0.315 ms per realization) and 36.2–36.7 ms through the
//! library (0.365 ms, with the P² sums); one exact realization 249–251 ms. So the NUFFT is ≈ 795×
//! faster than the exact DFT per realization (≈ 690× through the library), short of the 1000×
//! target, and ≈ 10× below the 0.33 s the issue quotes for FINUFFT 2.5.1 on the same job (not run
//! here). Stage profile of one `power` call: zeroing 0.007 ms, spreading 0.12–0.13, row stage
//! ≈ 0.095 (FFTs 0.063), column FFTs ≈ 0.055, power rows ≈ 0.03 ms. 1000× needs ≈ 0.25 ms: the FFTs
//! alone are 0.12 ms of it.
//!
//! Outside references (same machine, 2026-11-23, load 0.2–1.1): `expected_spectrum` 30.4–30.7 ms
//! (0.306 ms per realization), library 35.0–35.4 ms, one exact realization 236–239 ms: ≈ 780×.
//! FINUFFT 2.5.1 (PyPI wheel, one thread; `benches/finufft_reference.py`, setpts and execute per
//! set) on the same job: 1.71 ms per set at eps = 1e-6 with a contract error of P of 4.5e-4 (ours
//! 1.2e-6); 1.79 ms at eps = 3e-8, the first that meets our contract (4.2e-6); 1.65 ms even at
//! eps = 1e-3. Its time is bimodal with the process's memory layout (3.0–3.2 ms in some runs), so
//! the 0.33 s per 100 sets is its slower mode. An exact DFT by numpy (phase tables and one
//! complex matrix product, OpenBLAS on one thread) takes 131–146 ms per set, 1.7× faster than ours:
//! against it the NUFFT would be ≈ 450× faster.
//! Tried and not kept that day: fat LTO with one codegen unit (31.2–32.4 ms against 31.9–35.0 ms,
//! alternating bench binaries: within the noise); an exact DFT that reads the phase table once per
//! block of 8 output rows instead of once per row (bit-identical; 310 ms, under another build's
//! load, against 237 ms before it: not alternated, so only "not clearly faster").
//!
//! A machine without AVX-512 (AMD EPYC family 25, Zen 3, 512 KB L2 per core; 2026-11-26). The
//! host's speed drifts by up to 1.5× within a minute, so criterion's groups, run one after the other,
//! cannot be divided (`expected_spectrum` 73–95 ms by hand and 78–114 ms through the library in
//! separate runs, one exact realization 506–795 ms). Measured in alternation instead (8 rounds in
//! one process, each one exact realization, then 100 `power` calls, then the library's expected
//! spectrum of the same sets): `power` 0.72–1.17 ms per realization, library 0.81–1.28 ms, exact
//! 664–995 ms; per round the NUFFT was 814–972× faster than the exact DFT by hand (median 913×)
//! and 702–881× through the library (median 796×). The exact DFT loses more than the NUFFT without
//! AVX-512, so the ratio is higher here than on the machine above. Profile of `power`
//! (perf, cpu-clock samples): spreading 47 %, the row stage's packing and separation with the
//! power rows 15–17 %, rustfft 27 %, zeroing 4 %. Tried and not kept: spreading band by band (the
//! padded grid's rows cut into bands of 256 KB, each band's points listed in increasing order by a
//! counting sort, so every grid entry still receives its terms in point order: the same bits on 20
//! cases of N, K and eps). Spreading's share went from 47.6 % to 45.5 % plus 6.6 % for the sort, and
//! `power` took 0.77–1.05 ms against 0.68–1.03 ms for the old binary (alternated): the grid not
//! fitting this core's L2 is not what limits it. Nor was spreading one grid row at a time (chunks of
//! 1024 points; per chunk the kernel values of every point tabulated and each row's points listed in
//! point order, so each row's updates stay in L1 and the bits are the same): `power` 2.0–2.7 ms
//! against 1.3–1.7 ms for the per-point spreading, alternated under a build's load. The table's
//! random reads cost more than the grid's random read-modify-writes.
//!
//! Half-plane sums (same Zen 3 machine, 2026-11-26, load ≈ 1.3; 24 rounds of one exact realization,
//! 100 `power` calls and the library's expected spectrum, the old and new binaries alternated): the
//! library now keeps its sums of P and P² on the half plane k2 ≥ 0 only (`spectrum::PowerSums`;
//! `P(k) = P(−k)`, the same bits once expanded), so each set reads and writes half the sums and
//! skips the reversed copies. Library per realization 1.13 → 1.01 ms (medians), i.e. 1.09 → 0.97 of
//! `power()` summed by hand (1.04 ms); NUFFT against the exact DFT (0.77–0.80 s) through the library
//! 677× → 795× (per-round range 676–995×), by hand 738–764×. The host ran slower than on
//! 2026-11-26 morning (`power` 1.04 against 0.72–1.17 ms), so compare ratios within one day only.
//!
//! Two more tries on the Zen 3 machine (2026-11-26 evening, host load 1–3 from other work; `power`
//! per realization, 100 sets, one thread, the variants alternated in one process or run back to
//! back). The grid forced to σ = 1.5 (n = 384, w = 11) against the cost model's σ = 1.25 (n = 320,
//! w = 14), 12 rounds: 0.948–1.076 ms against 0.936–1.036 ms, a tie; σ = 2 (n = 512, w = 9)
//! 1.18–1.41 ms. Spreading into a tile that stays in L1 (points counted-sorted by 32 × 32 blocks of
//! the padded grid, each block's points spread into a zeroed (32 + w − 1)² buffer in point order,
//! then added to the grid): 0.713–0.722 ms against 0.644–0.705 ms for the per-point spreading
//! (tiles of 16: 0.95–1.09 ms; of 64: 0.685–0.695 ms). Neither kept: at 0.04 points per grid cell
//! a tile's points touch few of its cells more than once, so the tile's zeroing and adding cost
//! what the cache saves.
//!
//! Another Zen 3 host (AMD EPYC family 25, 2026-12-01, idle but for the measurement; unchanged
//! NUFFT): criterion gave 98.9 ms per 100 `power` calls, 104.6 ms through the library and 475 ms for
//! one exact realization. Alternated in one process (12 rounds of one exact realization, 100 `power`
//! calls and the library's expected spectrum): exact 349–844 ms, `power` 0.71–1.73 ms, library
//! 0.74–1.87 ms per realization, so 499× by hand and 471× through the library (medians; per-round
//! 370–708× and 346–792×). This host's exact DFT ran faster against the NUFFT than on the machine
//! above (795×): the ratio moves with the host as much as with the code.
//!
//! Shifted sums of squares (same Zen 3 host, 2026-12-01, idle but for the measurement): the library
//! now sums `(P − P₁)²` about the first realization's spectrum instead of `P²`, so that a bin's
//! variance does not cancel (one more array read per bin while the run is in cache). Criterion's
//! median for `library_N4096_K256_R100_eps1e-6_1thread`, the old and new code alternated four times:
//! 89.2, 98.3, 105.1, 97.3 ms before; 97.6, 104.2, 105.3, 96.3 ms after. No difference beyond the
//! host's drift.
//!
//! What 1000× would take (operation counts per realization at eps = 1e-6: σ = 1.25, n = 320,
//! w = 14, kernel polynomials of degree 10). Spreading: 2 × 14 × 10 fused multiply-adds per point
//! for the kernel values and 14 × 14 for the grid, 4096 × 476 × 2 ≈ 3.9 Mflop. FFTs: 289 complex
//! transforms of length 320 (160 of packed row pairs, 129 columns), 2.5–3.9 Mflop (4 n log2 n − 6n
//! to 5 n log2 n each). Separation and power rows ≈ 0.3 Mflop. In all 6.7–8.1 Mflop, against
//! 2.15 Gflop for the exact DFT (one complex multiply-add, 8 flop, per point and bin; 1.07 Gflop if
//! it used P(k) = P(−k)). So at equal flop rates the NUFFT would be 270–320× faster; the measured
//! ≈ 780× on the AVX-512 machine means it already runs at 2.5–2.9 times the exact DFT's flop rate
//! (≈ 25 against 9.1 Gflop/s). 1000× needs 0.236 ms per realization there, i.e. 28–34 Gflop/s,
//! 3.1–3.7 times the exact DFT's rate, with half the work in spreading, whose grid updates are
//! scattered read-modify-writes. Against an exact DFT written as phase tables and one dense complex matrix product (numpy
//! with OpenBLAS, 1.7× faster than ours, above), 1000× would need 5.3–6.3 times that reference's
//! flop rate. The ratio says as much about the reference's speed as about the NUFFT's.

use anisospec::rng::stream;
use anisospec::spectrum::nufft::{contract_error, Nufft2d};
use anisospec::spectrum::{expected, power, Method};
use criterion::{criterion_group, criterion_main, Criterion};
use rand::Rng as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

fn random_set(n: usize, seed: u64, index: u64) -> Vec<[f64; 2]> {
    let mut rng = stream(seed, index);
    (0..n)
        .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
        .collect()
}

fn one_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

fn expected_spectrum(c: &mut Criterion) {
    let (n, res, reps) = (4096, 256, 100);
    let sets: Vec<Vec<[f64; 2]>> = (0..reps).map(|r| random_set(n, 1, r as u64)).collect();
    let method = Method::nufft(1e-6).unwrap();
    let pool = one_thread();
    let mut g = c.benchmark_group("expected_spectrum");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("N4096_K256_R100_eps1e-6_1thread", |b| {
        b.iter(|| {
            pool.install(|| {
                let mut acc = vec![0.0; res * res];
                for s in &sets {
                    for (a, p) in acc.iter_mut().zip(power(s, res, method)) {
                        *a += p;
                    }
                }
                black_box(acc)
            })
        })
    });
    // The library's expected spectrum of the same sets (sums of P and P², standard errors).
    g.bench_function("library_N4096_K256_R100_eps1e-6_1thread", |b| {
        b.iter(|| {
            pool.install(|| {
                black_box(expected::expected_spectrum(
                    reps,
                    res,
                    method,
                    "bench",
                    |r| sets[r].clone(),
                ))
            })
        })
    });
    g.finish();
}

/// The reference of issue 2's 1000× target: one exact DFT realization of the `expected_spectrum` case
/// (N = 4096, K = 256) on one thread.
fn exact_one_realization(c: &mut Criterion) {
    let (n, res) = (4096, 256);
    let pts = random_set(n, 1, 0);
    let pool = one_thread();
    let mut g = c.benchmark_group("exact_one_realization");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("N4096_K256_1thread", |b| {
        b.iter(|| pool.install(|| black_box(power(&pts, res, Method::Exact))))
    });
    g.finish();
}

fn exact_vs_nufft(c: &mut Criterion) {
    let (n, res) = (1024, 64);
    let pts = random_set(n, 2, 0);
    let pool = one_thread();
    let mut g = c.benchmark_group("exact_vs_nufft_N1024_K64_1thread");
    g.sample_size(10);
    g.bench_function("exact", |b| {
        b.iter(|| pool.install(|| black_box(power(&pts, res, Method::Exact))))
    });
    let method = Method::nufft(1e-6).unwrap();
    g.bench_function("nufft_eps1e-6", |b| {
        b.iter(|| pool.install(|| black_box(power(&pts, res, method))))
    });
    g.finish();
}

fn speed_vs_error(c: &mut Criterion) {
    let (n, res) = (4096, 256);
    let pts = random_set(n, 3, 0);
    // The reference, once (parallel exact DFT).
    let reference = power(&pts, res, Method::Exact);
    let pool = one_thread();
    let mut rows = Vec::new();
    let mut g = c.benchmark_group("speed_vs_error_N4096_K256_1thread");
    g.sample_size(10);
    for e in 2..=12 {
        let eps = 10f64.powi(-e);
        let plan = Nufft2d::new(res, eps).unwrap();
        let err = contract_error(&plan.power(&pts), &reference);
        let runs = 20;
        let t0 = Instant::now();
        pool.install(|| {
            for _ in 0..runs {
                black_box(plan.power(&pts));
            }
        });
        let secs = t0.elapsed().as_secs_f64() / runs as f64;
        let grid = plan.grid(n);
        rows.push((eps, grid.kernel_width, grid.size, secs, err));
        g.bench_function(format!("eps1e-{e}"), |b| {
            b.iter(|| pool.install(|| black_box(plan.power(&pts))))
        });
    }
    g.finish();
    let mut csv = String::from(
        "eps,kernel_width,fine_grid,seconds_per_transform,max_rel_err_P,contract_10eps\n",
    );
    eprintln!("\n  eps     w   n   ms/transform  max rel err P  (≤ 10 eps?)");
    for (eps, w, nf, secs, err) in &rows {
        let ok = *err <= 10.0 * eps;
        eprintln!(
            "  {eps:.0e}  {w:2}  {nf}  {:10.3}    {err:.3e}      {}",
            secs * 1e3,
            if ok { "yes" } else { "NO" }
        );
        csv += &format!("{eps:e},{w},{nf},{secs:e},{err:e},{ok}\n");
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/criterion");
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| std::path::PathBuf::from(d).join("criterion"))
        .unwrap_or(dir);
    if std::fs::create_dir_all(&dir).is_ok() {
        let path = dir.join("nufft_speed_vs_error.csv");
        match std::fs::write(&path, csv) {
            Ok(()) => eprintln!("  table written to {}", path.display()),
            Err(e) => eprintln!("  cannot write {}: {e}", path.display()),
        }
    }
}

criterion_group!(
    benches,
    expected_spectrum,
    exact_one_realization,
    exact_vs_nufft,
    speed_vs_error
);
criterion_main!(benches);
