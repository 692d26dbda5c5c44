//! The NUFFT against the exact DFT (DESIGN §3): type 1 under the per-bin accuracy contract, type 2
//! against the exact adjoint, parameter checks and edge cases.

use anisospec::rng::stream;
use anisospec::spectrum::nufft::Nufft2d;
use anisospec::spectrum::{exact, fourier_sums, power, Method};
use anisospec::Error;
use rand::Rng as _;
use rustfft::num_complex::Complex64;

fn random_set(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = stream(seed, 0);
    (0..n).map(|_| [rng.random::<f64>(), rng.random::<f64>()]).collect()
}

fn jittered_set(m: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = stream(seed, 1);
    let mut pts = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m {
            pts.push([
                (j as f64 + rng.random::<f64>()) / m as f64,
                (i as f64 + rng.random::<f64>()) / m as f64,
            ]);
        }
    }
    pts
}

fn sobol_set(n: usize, seed: u32) -> Vec<[f64; 2]> {
    (0..n as u32)
        .map(|i| {
            [
                sobol_burley::sample(i, 0, seed) as f64,
                sobol_burley::sample(i, 1, seed) as f64,
            ]
        })
        .collect()
}

/// Maximum relative error of `P` over the bins whose exact power is at least 1e-3 of the mean.
fn max_rel_err(p: &[f64], exact: &[f64]) -> f64 {
    let mean = exact.iter().sum::<f64>() / exact.len() as f64;
    p.iter()
        .zip(exact)
        .filter(|(_, e)| **e >= 1e-3 * mean)
        .map(|(a, e)| (a - e).abs() / e)
        .fold(0.0, f64::max)
}

fn exact_power(points: &[[f64; 2]], res: usize) -> Vec<f64> {
    power(points, res, Method::Exact)
}

#[test]
fn type1_meets_the_per_bin_contract() {
    let sets: Vec<(&str, Vec<[f64; 2]>)> = vec![
        ("random", random_set(600, 11)),
        ("jittered", jittered_set(24, 12)),
        ("sobol", sobol_set(512, 13)),
    ];
    for res in [64, 50] {
        for (name, pts) in &sets {
            let reference = exact_power(pts, res);
            for eps in [1e-3, 1e-6, 1e-9] {
                let plan = Nufft2d::new(res, eps).unwrap();
                let err = max_rel_err(&plan.power(pts), &reference);
                eprintln!("{name} K={res} eps={eps:e}: max rel err {err:.3e}");
                assert!(err <= 10.0 * eps, "{name} K={res} eps={eps:e}: {err:e}");
            }
        }
    }
}
