//! The NUFFT against the exact DFT (DESIGN §3): type 1 under the per-bin accuracy contract, type 2
//! against the exact adjoint, parameter checks and edge cases.

use anisospec::rng::stream;
use anisospec::spectrum::nufft::{contract_error, Nufft2d};
use anisospec::spectrum::{exact, fourier_sums, power, Method};
use anisospec::Error;
use rand::Rng as _;
use rustfft::num_complex::Complex64;

fn random_set(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = stream(seed, 0);
    (0..n)
        .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
        .collect()
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

fn exact_power(points: &[[f64; 2]], res: usize) -> Vec<f64> {
    power(points, res, Method::Exact)
}

#[test]
fn plans_are_send_and_sync() {
    fn shared<T: Send + Sync>() {}
    shared::<Nufft2d>();
}

#[test]
fn type1_meets_the_contract_on_a_larger_grid() {
    // More points than bins, and a fine grid that is not a power of two (n = 2·96 = 192).
    let pts = random_set(3000, 14);
    let res = 96;
    let reference = exact_power(&pts, res);
    for eps in [1e-4, 1e-7] {
        let plan = Nufft2d::new(res, eps).unwrap();
        let err = contract_error(&plan.power(&pts), &reference);
        eprintln!("random N=3000 K={res} eps={eps:e}: max rel err {err:.3e}");
        assert!(err <= 10.0 * eps, "K={res} eps={eps:e}: {err:e}");
    }
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
            // The three tolerances and the ends of the range the plan promises to meet.
            for eps in [1e-1, 1e-2, 1e-3, 1e-6, 1e-9, 1e-12] {
                let plan = Nufft2d::new(res, eps).unwrap();
                let err = contract_error(&plan.power(pts), &reference);
                eprintln!("{name} K={res} eps={eps:e}: max rel err {err:.3e}");
                assert!(err <= 10.0 * eps, "{name} K={res} eps={eps:e}: {err:e}");
            }
        }
    }
}

fn rel_l2(a: &[Complex64], b: &[Complex64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
    let den: f64 = b.iter().map(|y| y.norm_sqr()).sum();
    (num / den).sqrt()
}

#[test]
fn type2_matches_the_exact_adjoint() {
    let pts = random_set(400, 21);
    for res in [64, 40] {
        let mut rng = stream(22, res as u64);
        let coeffs: Vec<Complex64> = (0..res * res)
            .map(|_| Complex64::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5))
            .collect();
        let reference = exact::type2(&coeffs, &pts, res);
        for eps in [1e-1, 1e-2, 1e-3, 1e-6, 1e-9, 1e-12] {
            let plan = Nufft2d::new(res, eps).unwrap();
            let err = rel_l2(&plan.type2(&coeffs, &pts), &reference);
            eprintln!("type2 K={res} eps={eps:e}: rel l2 err {err:.3e}");
            assert!(err <= 10.0 * eps, "type2 K={res} eps={eps:e}: {err:e}");
        }
    }
}

#[test]
fn type2_is_the_adjoint_of_weighted_type1() {
    // <type1_weighted(a), c> = Σ_k conj(F(k)) c(k) = Σ_j a_j g_j with g = type2(c), for real a.
    let pts = jittered_set(16, 31);
    let res = 32;
    let mut rng = stream(32, 0);
    let a: Vec<f64> = pts.iter().map(|_| rng.random::<f64>() - 0.5).collect();
    let c: Vec<Complex64> = (0..res * res)
        .map(|_| Complex64::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5))
        .collect();
    let plan = Nufft2d::new(res, 1e-12).unwrap();
    let f = plan.type1_weighted(&pts, &a);
    let g = plan.type2(&c, &pts);
    let lhs: Complex64 = f.iter().zip(&c).map(|(f, c)| f.conj() * c).sum();
    let rhs: Complex64 = a.iter().zip(&g).map(|(a, g)| g * *a).sum();
    assert!((lhs - rhs).norm() <= 1e-10 * lhs.norm(), "{lhs} vs {rhs}");
    // And the weighted sums against the exact DFT of a weighted set.
    let exact_f: Vec<Complex64> = {
        let half = res as isize / 2;
        (0..res * res)
            .map(|idx| {
                let k1 = (idx % res) as isize - half;
                let k2 = (idx / res) as isize - half;
                pts.iter()
                    .zip(&a)
                    .map(|(p, w)| {
                        let t = (k1 as f64 * p[0] + k2 as f64 * p[1]).rem_euclid(1.0);
                        Complex64::from_polar(*w, -std::f64::consts::TAU * t)
                    })
                    .sum()
            })
            .collect()
    };
    assert!(rel_l2(&f, &exact_f) <= 1e-11);
}

#[test]
fn bad_parameters_are_rejected() {
    for eps in [0.0, 1e-13, 1e-15, 0.2, 1.0, -1e-3, f64::NAN, f64::INFINITY] {
        match Nufft2d::new(64, eps) {
            Err(Error::Usage(msg)) => {
                assert!(msg.contains("1e-12") && msg.contains("1e-1"), "{msg}")
            }
            Err(e) => panic!("eps {eps}: wrong error kind {e:?}"),
            Ok(_) => panic!("eps {eps} accepted"),
        }
        assert!(matches!(Method::nufft(eps), Err(Error::Usage(_))));
    }
    for res in [0, 1, 63] {
        assert!(matches!(Nufft2d::new(res, 1e-6), Err(Error::Usage(_))));
    }
    assert!(Nufft2d::new(2, 1e-12).is_ok() && Nufft2d::new(2, 1e-1).is_ok());
    assert_eq!(Method::nufft(1e-6).unwrap(), Method::Nufft { eps: 1e-6 });
}

/// Every entry finite, and the power within the contract of the exact one (all bins, since the sets
/// below have no dark bins other than exact zeros, which the absolute check covers).
fn check_edge(name: &str, pts: &[[f64; 2]], res: usize, eps: f64) {
    let plan = Nufft2d::new(res, eps).unwrap();
    let f = plan.type1(pts);
    let p = plan.power(pts);
    let reference = exact_power(pts, res);
    let n = pts.len() as f64;
    assert!(
        f.iter().all(|c| c.re.is_finite() && c.im.is_finite()),
        "{name}"
    );
    for (a, e) in p.iter().zip(&reference) {
        assert!(a.is_finite(), "{name}");
        assert!(
            (a - e).abs() <= 10.0 * eps * e.max(1e-3 * n),
            "{name}: {a} vs {e}"
        );
    }
    let exact_f = exact::fourier_sums(pts, res);
    assert!(rel_l2(&f, &exact_f) <= 10.0 * eps, "{name}");
}

#[test]
fn edge_cases_are_finite_and_exact() {
    for eps in [1e-3, 1e-9] {
        check_edge("one point", &[[0.3, 0.7]], 32, eps);
        check_edge("identical points", &[[0.123, 0.987]; 50], 32, eps);
        let lo = 1.0 - f64::EPSILON / 2.0;
        let corners = [[0.0, 0.0], [lo, 0.0], [0.0, lo], [lo, lo], [0.5, lo]];
        check_edge("points at 0 and just below 1", &corners, 32, eps);
        check_edge("on fine-grid nodes", &[[0.25, 0.5], [0.75, 0.0]], 32, eps);
    }
    // An empty set has no power (0, not 0/0).
    let plan = Nufft2d::new(16, 1e-6).unwrap();
    assert!(plan.power(&[]).iter().all(|&p| p == 0.0));
    assert!(power(&[], 16, Method::Exact).iter().all(|&p| p == 0.0));
}

#[test]
fn method_nufft_is_wired_and_plans_are_shared_across_threads() {
    use rayon::prelude::*;
    let sets: Vec<Vec<[f64; 2]>> = (0..6).map(|s| random_set(300, 40 + s)).collect();
    let method = Method::nufft(1e-6).unwrap();
    let fast: Vec<Vec<f64>> = sets.par_iter().map(|s| power(s, 32, method)).collect();
    for (s, p) in sets.iter().zip(&fast) {
        let reference = exact_power(s, 32);
        assert!(contract_error(p, &reference) <= 1e-5);
        // Same bits on any thread.
        assert!(p == &power(s, 32, method), "power differs between threads");
        let f = fourier_sums(s, 32, method);
        let n = s.len() as f64;
        assert!(p
            .iter()
            .zip(&f)
            .all(|(p, f)| (p - f.norm_sqr() / n).abs() <= 1e-14 * p.max(1.0)));
    }
}
