//! Spectra against theory: white noise, N-rooks' jittered axes and the padded-MJ cross (DESIGN §3).

use anisospec::points::Projection;
use anisospec::samplers::build;
use anisospec::spectrum::expected::{of_sampler, ExpectedSpectrum};
use anisospec::spectrum::Method;
use anisospec::targets::DARK_LEVEL;

fn at(spec: &ExpectedSpectrum, k1: i64, k2: i64) -> (f64, f64) {
    let h = (spec.res / 2) as i64;
    let idx = ((k2 + h) * spec.res as i64 + (k1 + h)) as usize;
    (spec.mean[idx], spec.stderr[idx])
}

/// The radial profile's standard error is the spread of the annulus mean over independent runs: 200
/// runs of R = 8 white-noise sets (N = 64, K = 32). Per annulus the ratio of the runs' standard
/// deviation to the mean reported standard error has a relative error of about 1/sqrt(2·199) = 5 %;
/// over the 15 annuli the mean ratio is 1 within 4 of its standard errors, 4 · 0.05 / sqrt(15). It was
/// 0.71 when the bins were combined as independent, though each has its mirror `−k` in the annulus.
#[test]
fn radial_standard_error_is_the_spread_over_runs() {
    use anisospec::spectrum::profiles::radial_profile;
    let random = build("random", 2).unwrap();
    let method = Method::Nufft { eps: 1e-6 };
    let (n, res, r, runs) = (64, 32, 8, 200);
    let profiles: Vec<_> = (0..runs)
        .map(|run| {
            let spec = of_sampler(
                random.as_ref(),
                n,
                Projection::XY,
                res,
                r,
                1000 + run,
                method,
            )
            .unwrap();
            radial_profile(&spec, 0, method)
        })
        .collect();
    let annuli = profiles[0].len();
    let ratios: Vec<f64> = (0..annuli)
        .map(|a| {
            let means: Vec<f64> = profiles.iter().map(|p| p[a].mean).collect();
            let m = means.iter().sum::<f64>() / runs as f64;
            let sd =
                (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
            let reported = profiles.iter().map(|p| p[a].stderr.unwrap()).sum::<f64>() / runs as f64;
            sd / reported
        })
        .collect();
    let mean_ratio = ratios.iter().sum::<f64>() / annuli as f64;
    let tolerance = 4.0 * 0.05 / (annuli as f64).sqrt();
    assert!(
        (mean_ratio - 1.0).abs() < tolerance,
        "spread / reported standard error: {mean_ratio:.3} (per annulus {ratios:.2?}), tolerance {tolerance:.3}"
    );
}

/// The library's expected spectrum (chunked sums of P and P², on the half plane for the NUFFT) is the
/// mean of `power` over the sets: over R = 37 sets (ten chunks of four, batches of several chunks) on
/// K = 2, 6 and 32, each bin within the reassociation error of summing 37 values, 37 · 2^-52 of the
/// sum, and, by NUFFT, P(k) = P(−k) bit for bit off the k1 axis (a row k2 < 0 is the mirror copy of
/// row −k2; on k2 = 0 both signs of k1 are computed).
#[test]
fn expected_spectrum_is_the_mean_of_power() {
    use anisospec::spectrum::expected::expected_spectrum;
    use anisospec::spectrum::power;
    let random = build("random", 2).unwrap();
    let sets: Vec<Vec<[f64; 2]>> = (0..37u64)
        .map(|r| {
            let set = random.generate(50, &mut anisospec::rng::stream(11, r));
            set.chunks_exact(2).map(|p| [p[0], p[1]]).collect()
        })
        .collect();
    for method in [Method::Exact, Method::Nufft { eps: 1e-6 }] {
        for res in [2, 6, 32] {
            let spec =
                expected_spectrum(sets.len(), res, method, "test", |r| sets[r].clone()).unwrap();
            let mut sum = vec![0.0; res * res];
            for s in &sets {
                for (a, p) in sum.iter_mut().zip(power(s, res, method)) {
                    *a += p;
                }
            }
            let r = sets.len() as f64;
            for (i, (m, s)) in spec.mean.iter().zip(&sum).enumerate() {
                let tol = r * f64::EPSILON * s / r;
                assert!(
                    (m - s / r).abs() <= tol,
                    "{method:?} K={res} bin {i}: {m} against {}",
                    s / r
                );
            }
            if matches!(method, Method::Nufft { .. }) {
                let h = (res / 2) as i64;
                for i in (1..res as i64).filter(|&i| i != h) {
                    for j in 1..res as i64 {
                        let mirror = ((2 * h - i) * res as i64 + (2 * h - j)) as usize;
                        let here = (i * res as i64 + j) as usize;
                        assert_eq!(spec.mean[here].to_bits(), spec.mean[mirror].to_bits());
                    }
                }
            }
        }
    }
}

fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    }
}

/// White noise: E[P(k)] = 1 at every k ≠ 0 within 4 standard errors, and P(0) = N exactly.
/// With ~K²/2 independent bins (P is symmetric) a 4-sigma excursion somewhere has a probability of a few
/// per cent per seed; the seed is fixed. A global check adds power: the mean squared z-score over all bins
/// must be 1 within 4 of its standard errors, sqrt(2 / (bins / 2)): z² has variance 2 for a normal z,
/// and only half the bins are independent (P(−k) = P(k)).
#[test]
fn white_noise_is_flat() {
    let random = build("random", 2).unwrap();
    for method in [Method::Exact, Method::Nufft { eps: 1e-9 }] {
        let (n, res, r) = (256, 32, 400);
        let spec = of_sampler(random.as_ref(), n, Projection::XY, res, r, 7, method).unwrap();
        // P(0) = |Σ 1|² / N: exactly N by the exact DFT (every phase at k = 0 is exactly 1), and
        // within the NUFFT's 10·eps of it.
        let (p0, se0) = at(&spec, 0, 0);
        match method {
            Method::Exact => assert_eq!((p0, se0), (n as f64, 0.0)),
            Method::Nufft { eps } => {
                assert!(
                    (p0 - n as f64).abs() <= 10.0 * eps * n as f64,
                    "P(0) = {p0}"
                );
                assert!(se0 <= 10.0 * eps * n as f64, "se(0) = {se0}");
            }
        }
        let mut z2 = 0.0;
        let mut bins = 0.0;
        let dc = (res / 2) * res + res / 2;
        for (i, (m, se)) in spec.mean.iter().zip(&spec.stderr).enumerate() {
            if i == dc {
                continue;
            }
            let z = (m - 1.0) / se;
            assert!(z.abs() < 4.0, "{method:?}: E[P] = {m} ± {se}");
            z2 += z * z;
            bins += 1.0;
        }
        let chi = z2 / bins;
        assert!(
            (chi - 1.0).abs() < 4.0 * (2.0 / (bins / 2.0)).sqrt(),
            "mean z² = {chi} over {bins} bins"
        );
    }
}

/// N-rooks pairs independently permuted, jittered 1D strata: for k1, k2 not multiples of N,
/// E[P(k)] = 1 + Σ_{j≠l} E[e^{−2πi k·(x_j − x_l)}] / N, and each dimension's factor is
/// sinc²(k_d/N) · (Σ_{a≠b} e^{−2πi k_d (a − b)/N}) / (N (N − 1)) = −sinc²(k_d/N) / (N − 1) (1 if k_d = 0).
/// So E[P] = 1 − sinc²(k1/N) on the k1 axis (1D jittered) and 1 + sinc²(k1/N) sinc²(k2/N) / (N − 1) off
/// it: white only up to that term (0.016 at N = 64, half a standard error here).
fn nrooks_law(k1: i64, k2: i64, n: usize) -> f64 {
    let s = |k: i64| sinc(k as f64 / n as f64).powi(2);
    match (k1, k2) {
        (0, 0) => n as f64,
        (k, 0) | (0, k) => 1.0 - s(k),
        _ => 1.0 + s(k1) * s(k2) / (n as f64 - 1.0),
    }
}

/// N-rooks: along the k1 axis the spectrum is 1D jittered, 1 − sinc²(k1/N); on the diagonal it is
/// white up to sinc⁴(k/N) / (N − 1) ([`nrooks_law`]). 62 bins at 4σ: a false alarm below 0.4 % per seed.
#[test]
fn nrooks_axis_follows_jittered_law() {
    let nrooks = build("nrooks", 2).unwrap();
    let (n, res, r) = (64, 64, 800);
    let spec = of_sampler(
        nrooks.as_ref(),
        n,
        Projection::XY,
        res,
        r,
        11,
        Method::Exact,
    )
    .unwrap();
    for k1 in 1..(res as i64 / 2) {
        let expect = nrooks_law(k1, 0, n);
        let (m, se) = at(&spec, k1, 0);
        assert!(
            (m - expect).abs() < 4.0 * se.max(1e-12),
            "k1={k1}: {m} ± {se} vs {expect}"
        );
        let diag = nrooks_law(k1, k1, n);
        let (d, sd) = at(&spec, k1, k1);
        assert!(
            (d - diag).abs() < 4.0 * sd,
            "diagonal k={k1}: {d} ± {sd} vs {diag}"
        );
    }
}

/// Padded multi-jittered sets are only N-rooks in xu (each MJ coordinate is 1D-stratified, the two sets
/// joined by a random permutation): a dark cross on the axes, white elsewhere ([`nrooks_law`]).
#[test]
fn padded_mj_shows_the_nrooks_cross_in_xu() {
    let padded = build("padded-mj", 4).unwrap();
    let (n, res, r) = (256, 64, 128);
    let spec = of_sampler(
        padded.as_ref(),
        n,
        Projection::XU,
        res,
        r,
        3,
        Method::Nufft { eps: 1e-6 },
    )
    .unwrap();
    for k in 1..16i64 {
        let expect = nrooks_law(k, 0, n);
        for (k1, k2) in [(k, 0), (-k, 0), (0, k), (0, -k)] {
            let (m, se) = at(&spec, k1, k2);
            // Not redundant with the 4σ check below, which has no bound on `se`: this is the claim
            // "dark" itself, at the level the targets call dark (DARK_LEVEL = 0.05), and it cannot
            // be passed by a noisy estimate whose standard error widens the 4σ band. At these sizes
            // (R = 128, expect ≤ 1 − sinc²(15/256) = 0.0112, measured se ≤ 0.0012) the 4σ check
            // puts m below 0.017: the two checks part only once se exceeds (0.05 − 0.0112) / 4 ≈
            // 0.0097, eight times the measured value, and then this one still asks for a dark axis.
            assert!(m < DARK_LEVEL, "axis ({k1},{k2}) = {m}");
            assert!(
                (m - expect).abs() < 4.0 * se.max(1e-9),
                "axis ({k1},{k2}) = {m} ± {se} vs {expect}"
            );
        }
    }
    // Off the axes, the mean over the square 1 ≤ k1, k2 < 16 of (P − the N-rooks law) is 0 within 4
    // standard errors (the law is white up to 1/(N − 1) = 0.004, 0.7 of this mean's standard error).
    let (mut sum, mut var, mut count) = (0.0, 0.0, 0.0);
    for k1 in 1..16i64 {
        for k2 in 1..16i64 {
            let (m, se) = at(&spec, k1, k2);
            sum += m - nrooks_law(k1, k2, n);
            var += se * se;
            count += 1.0;
        }
    }
    let mean = sum / count;
    assert!(
        mean.abs() < 4.0 * var.sqrt() / count,
        "off-axis mean excess {mean} ± {}",
        var.sqrt() / count
    );
}

/// The same seed gives the same bits on 1 and 2 threads.
#[test]
fn expected_spectrum_is_thread_count_independent() {
    let mj = build("mj", 2).unwrap();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                of_sampler(
                    mj.as_ref(),
                    64,
                    Projection::XY,
                    32,
                    37,
                    5,
                    Method::Nufft { eps: 1e-6 },
                )
                .unwrap()
            })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.mean, b.mean);
    assert_eq!(a.stderr, b.stderr);
}

/// The absolute error bound that `variance` allows a full-grid NUFFT sum (its `F` within
/// `10 eps N` of the exact sum), held against the exact DFT at every bin, where a lattice's `P` is
/// 0 and where it is `N`, and on random sets: `|ΔP| ≤ 2 ρ sqrt(P N) + ρ² N` with `ρ = 10 eps`.
#[test]
fn nufft_power_is_within_its_absolute_bound_at_every_bin() {
    use anisospec::spectrum::power;
    let res = 64;
    for name in ["lattice", "random", "sobol"] {
        let s = build(name, 2).unwrap();
        for n in [256, 1024, 4096] {
            let flat = s.generate(n, &mut anisospec::rng::stream(5, n as u64));
            let set = anisospec::points::project(&flat, 2, Projection::XY);
            let exact = power(&set, res, Method::Exact);
            for eps in [1e-3, 1e-6, 1e-9] {
                let fast = power(&set, res, Method::nufft(eps).unwrap());
                let rho = 10.0 * eps;
                let (nf, mut worst) = (n as f64, 0.0f64);
                for (&e, &f) in exact.iter().zip(&fast) {
                    let bound = 2.0 * rho * (f.max(0.0) * nf).sqrt() + rho * rho * nf;
                    worst = worst.max((f - e).abs() / bound);
                }
                eprintln!("{name} N={n} eps={eps:e}: worst |ΔP| / bound = {worst:.3e}");
                assert!(worst <= 1.0, "{name} N={n} eps={eps:e}: {worst}");
            }
        }
    }
}
