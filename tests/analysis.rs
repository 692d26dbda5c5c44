//! Issue 3 "Must show": convergence rates, prediction against measurement, directional cones, bad input.
//!
//! Statistics used to size the runs. With R realizations, the relative standard error of an MSE is
//! about sqrt((κ − 1)/R) (κ the kurtosis of the error; 3 for Gaussian errors), i.e. σ(ln MSE) ≈ 0.07 at
//! R = 400. A weighted fit over N = 16, 64, 256, 1024, 4096 (ln N spaced by ln 4, Σ(ln N − mean)² = 19.2)
//! then has σ(slope) ≈ 0.07 / sqrt(19.2) ≈ 0.016: the ±0.15 tolerance is about 9σ, so noise cannot fail
//! a right rate, while the rates being told apart differ by at least 0.5 (30σ). The fit's own standard
//! error is asserted to stay below 0.05 so that the test keeps this power.

use anisospec::converge::{converge, measure, ConvergeConfig, ConvergePoint};
use anisospec::integrands::{parse, Integrand};
use anisospec::samplers::{self, Sampler};
use anisospec::spectrum::Method;
use anisospec::variance::{predict, VarianceConfig, VariancePoint};

fn sampler(name: &str, dims: usize) -> Box<dyn Sampler> {
    samplers::build(name, dims).unwrap()
}

/// The z-score of a prediction against a measurement over `r_meas` realizations, after checking
/// that the measurement's standard error has the size its errors give, so that `|z| ≤ 3` cannot
/// pass by an inflated one. The relative standard error of an MSE is `sqrt((κ − 1) / R)`, `κ` the
/// kurtosis of the errors, so `κ̂ = 1 + R (se / MSE)²` recovers `κ`. The errors here are near
/// Gaussian (`κ = 3`; most are sums of many independent pieces, points or strata): measured 2.74 to
/// 3.57 over every z-test of this file, with `κ̂`'s own noise about `2 sqrt(14 / R)` (0.12 at
/// R = 4000, for Gaussian errors). The window `2 ≤ κ̂ ≤ 5` is that assumption of near-Gaussian
/// errors, checked by these measurements, not a bound derived for every integrand: it holds the
/// standard error within 0.71 to 1.41 times its Gaussian-error size `MSE sqrt(2 / R)`; one scaled by
/// 3 (`κ̂ ≥ 16.7` from the smallest measured 2.74) or by 1/3 (`κ̂ ≤ 1.3`) fails.
fn z_score(p: &VariancePoint, m: &ConvergePoint, r_meas: usize) -> f64 {
    let kurtosis = 1.0 + r_meas as f64 * (m.mse_stderr / m.mse).powi(2);
    assert!(
        (2.0..=5.0).contains(&kurtosis),
        "N = {}: the measured MSE {:e} ± {:e} over R = {r_meas} implies an error kurtosis {kurtosis}",
        m.n,
        m.mse,
        m.mse_stderr
    );
    (p.variance - m.mse) / (p.stderr.powi(2) + m.mse_stderr.powi(2)).sqrt()
}

/// The standard error of the random sampler's prediction at `n` points over `r_pred` realizations,
/// in closed form, for a 2D integrand `f` on the `res × res` grid. With `w_k = |f̂(k)|²` and
/// `h(d) = Σ_k w_k e^{−2πi k·d}` (`k ≠ 0` on the grid), a realization's sum is
/// `V = (1/N) Σ_k w_k P(k) = Σ_k w_k / N + (1/N²) Σ_{j≠l} h(x_j − x_l)`, a degenerate U-statistic
/// of the `N` independent uniform points: `Var V = 4 C(N, 2) E[(Re h)²] / N⁴`, with
/// `E[(Re h)²] = (Σ_k w_k² + Σ_k w_k w_{−k}) / 2` (`w_{−k}` = 0 where `−k` is off the grid).
fn random_prediction_stderr(f: &dyn Integrand, n: usize, res: usize, r_pred: usize) -> f64 {
    let half = (res / 2) as i64;
    let w = |k1: i64, k2: i64| {
        if (k1, k2) == (0, 0) || k1.max(k2) >= half || k1.min(k2) < -half {
            0.0
        } else {
            f.fourier(&[k1, k2]).unwrap().norm_sqr()
        }
    };
    let mut re_h2 = 0.0;
    for k2 in -half..half {
        for k1 in -half..half {
            let wk = w(k1, k2);
            re_h2 += wk * (wk + w(-k1, -k2)) / 2.0;
        }
    }
    let nf = n as f64;
    (2.0 * nf * (nf - 1.0) * re_h2 / nf.powi(4) / r_pred as f64).sqrt()
}

/// Checks a random sampler's reported prediction standard error (`Var f` exact: no tail error)
/// against [`random_prediction_stderr`]. The reported one is `s / sqrt(R)`, `s²` the sample
/// variance of `R` realizations of `V`, whose relative standard deviation is about
/// `sqrt((κ_V − 1) / R)`, `κ_V` the kurtosis of `V`. Random points' `P(k)` is near exponential
/// with mean 1, independently over pairs `±k`, so `V` is near a weighted sum of centred
/// exponentials, of kurtosis at most 9 (one term): at R = 1000 and 4 of its standard deviations,
/// `s² / Var V ∈ 1 ± 4 sqrt(8 / 1000) = [0.64, 1.36]`, the standard error within 0.80 to 1.17
/// times its expected size. One scaled by 3 or by 1/3 fails.
fn assert_random_prediction_stderr(p: &VariancePoint, f: &dyn Integrand, r_pred: usize) {
    assert_eq!(p.tail_stderr, 0.0);
    let expected = random_prediction_stderr(f, p.n, p.res, r_pred);
    let ratio = p.stderr / expected;
    eprintln!(
        "random N={}: prediction stderr {:.3e}, closed form {expected:.3e}, ratio {ratio:.3}",
        p.n, p.stderr
    );
    assert!(
        (0.80..=1.17).contains(&ratio),
        "N = {}: prediction stderr {:e} is {ratio} times its closed form {expected:e}",
        p.n,
        p.stderr
    );
}

const NS: [usize; 5] = [16, 64, 256, 1024, 4096];

/// DESIGN §4 rates: (sampler, [aligned step, 30° step, disc, Gaussian]).
///
/// Discontinuous integrands: random −1; jittered −1.5; N-rooks −2 on the aligned edge (its x marginal
/// is stratified in 1D) and −1 otherwise; MJ and CMJ −2 aligned and −1.5 otherwise. Smooth Gaussian:
/// random −1, jittered and MJ −2, N-rooks −1 (white off the axes), CMJ about −3.
const RATES: [(&str, [f64; 4]); 5] = [
    ("random", [-1.0, -1.0, -1.0, -1.0]),
    ("jittered", [-1.5, -1.5, -1.5, -2.0]),
    ("nrooks", [-2.0, -1.0, -1.0, -1.0]),
    ("mj", [-2.0, -1.5, -1.5, -2.0]),
    ("cmj", [-2.0, -1.5, -1.5, -3.0]),
];

const RATE_INTEGRANDS: [&str; 4] = [
    "step:theta=0,c=0.5",
    "step:theta=30",
    "disc:r=0.3",
    "gaussian:sigma=0.15",
];

#[test]
fn rates_of_design_section_4() {
    let cfg = ConvergeConfig {
        realizations: 400,
        seed: 2017,
        random_placement: false,
    };
    let mut failures = Vec::new();
    for (name, want) in RATES {
        let s = sampler(name, 2);
        for (spec, &want) in RATE_INTEGRANDS.iter().zip(&want) {
            let f = parse(spec).unwrap();
            let c = converge(s.as_ref(), f.as_ref(), &NS, &cfg, |_| {}).unwrap();
            let fit = c.fit.unwrap();
            eprintln!(
                "{name:>9} {spec:<20} slope {:+.3} ± {:.3} (want {want:+.1}; chi2/dof {:.2})",
                fit.slope, fit.stderr, fit.chi2_per_dof
            );
            assert!(
                fit.stderr < 0.05,
                "{name} on {spec}: slope error {} too large for a fair test",
                fit.stderr
            );
            if (fit.slope - want).abs() > 0.15 {
                failures.push(format!(
                    "{name} on {spec}: slope {:.3} ± {:.3}, want {want}",
                    fit.slope, fit.stderr
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "rates off by more than 0.15:\n{}",
        failures.join("\n")
    );
}

#[test]
fn prediction_meets_measurement() {
    let mut worst: f64 = 0.0;
    for spec in ["gaussian:sigma=0.15", "step:theta=0,c=0.5"] {
        let f = parse(spec).unwrap();
        for name in ["random", "jittered", "nrooks"] {
            let s = sampler(name, 2);
            for n in [64usize, 256] {
                let vc = VarianceConfig {
                    res: 32,
                    res_per_n: Some(4),
                    realizations: 1000,
                    cones: 4,
                    seed: 31,
                    method: Method::Exact,
                };
                let p = &predict(s.as_ref(), f.as_ref(), &[n], &vc).unwrap().points[0];
                if name == "random" {
                    assert_random_prediction_stderr(p, f.as_ref(), vc.realizations);
                }
                let cfg = ConvergeConfig {
                    realizations: 20000,
                    seed: 32,
                    random_placement: false,
                };
                let m = measure(s.as_ref(), f.as_ref(), n, &cfg).unwrap();
                let z = z_score(p, &m, cfg.realizations);
                eprintln!(
                    "{name:>9} {spec:<20} N={n:<4} predicted {:.4e} ± {:.1e} (tail {:.1e})  measured {:.4e} ± {:.1e}  z = {z:+.2}",
                    p.variance,
                    p.stderr,
                    p.tail,
                    m.mse,
                    m.mse_stderr
                );
                // 12 comparisons at 3 standard errors: a right prediction fails one of them at a
                // new seed with probability 1 − 0.9973^12 ≈ 3 % (z normal); a frame or factor
                // error moves z by far more (see the tests below). The seeds are fixed.
                assert!(z.abs() <= 3.0, "{name} on {spec} at N={n}: z = {z}");
                worst = worst.max(z.abs());
            }
        }
    }
    eprintln!("largest |z| = {worst:.2}");
}

/// A sheared sampler shifts its pattern before shearing it, so the prediction holds in the pattern's
/// frame, for the integrand pulled back through the shear. On the `xu` edge of shear 0.5, padded MJ
/// sheared by the exact shear and by shears off by −20 % and +10 % (the oracle's error) is predicted
/// as measured, within 3 combined standard errors. The sheared sets' own spectrum, taken as if the
/// formula held in the world frame, predicted 82 times the measured MSE at the exact shear (N = 256,
/// K = 256, by hand), so the test fails if the frame is wrong.
#[test]
fn a_sheared_sampler_is_predicted_in_its_patterns_frame() {
    let f = parse("sheared:s=0.5,c=0.7@xu").unwrap();
    let n = 256;
    for shear in [0.5, 0.4, 0.55] {
        let s: Box<dyn Sampler> = Box::new(
            samplers::Sheared::new(
                sampler("padded-mj", 4),
                shear,
                shear,
                anisospec::points::shear::ShearMode::Transported,
            )
            .unwrap(),
        );
        let vc = VarianceConfig {
            res: 1024,
            res_per_n: None,
            realizations: 200,
            cones: 1,
            seed: 41,
            method: Method::nufft(1e-9).unwrap(),
        };
        let p = &predict(s.as_ref(), f.as_ref(), &[n], &vc).unwrap().points[0];
        let cfg = ConvergeConfig {
            realizations: 4000,
            seed: 42,
            random_placement: false,
        };
        let m = measure(s.as_ref(), f.as_ref(), n, &cfg).unwrap();
        let z = z_score(p, &m, cfg.realizations);
        eprintln!(
            "shear {shear}: predicted {:.4e} ± {:.1e} (tail {:.1e})  measured {:.4e} ± {:.1e}  z = {z:+.2}",
            p.variance,
            p.stderr,
            p.tail,
            m.mse,
            m.mse_stderr
        );
        assert!(z.abs() <= 3.0, "shear {shear}: z = {z}");
    }
}

/// The pattern's frame holds for the wrap-around shear too, and for an integrand with terms on both
/// sheared planes (each pulled back through its own shear, the other plane's coordinates held at ½):
/// padded MJ sheared by (0.4, 0.6) on `sheared@xu + sheared@yv`, seam-free and wrapped, is predicted
/// as measured within 3 combined standard errors. A sampler sheared twice is refused, not predicted in
/// the wrong frame.
#[test]
fn a_sheared_sampler_is_predicted_on_both_planes_and_in_both_modes() {
    use anisospec::points::shear::ShearMode;
    let f = parse("sheared:s=0.5,c=0.7@xu+sheared:s=0.5,c=0.6@yv").unwrap();
    let n = 256;
    let vc = VarianceConfig {
        res: 256,
        res_per_n: None,
        realizations: 400,
        cones: 1,
        seed: 43,
        method: Method::nufft(1e-9).unwrap(),
    };
    let cfg = ConvergeConfig {
        realizations: 4000,
        seed: 44,
        random_placement: false,
    };
    for mode in [ShearMode::Transported, ShearMode::Wrap] {
        let s = samplers::Sheared::new(sampler("padded-mj", 4), 0.4, 0.6, mode).unwrap();
        let p = &predict(&s, f.as_ref(), &[n], &vc).unwrap().points[0];
        let m = measure(&s, f.as_ref(), n, &cfg).unwrap();
        let z = z_score(p, &m, cfg.realizations);
        eprintln!(
            "{mode:?}: predicted {:.4e} ± {:.1e}  measured {:.4e} ± {:.1e}  z = {z:+.2}",
            p.variance, p.stderr, m.mse, m.mse_stderr
        );
        assert!(z.abs() <= 3.0, "{mode:?}: z = {z}");
    }
    let inner = samplers::Sheared::new(sampler("padded-mj", 4), 0.5, 0.5, ShearMode::Wrap).unwrap();
    let twice = samplers::Sheared::new(Box::new(inner), 0.5, 0.5, ShearMode::Transported).unwrap();
    let err = predict(&twice, f.as_ref(), &[n], &vc)
        .unwrap_err()
        .to_string();
    assert!(err.contains("sheared twice"), "{err}");
    // A shear of 0 moves no point: any integrand is predicted, with the unsheared sampler's bits.
    let disc = parse("disc:r=0.3@xy").unwrap();
    let zero =
        samplers::Sheared::new(sampler("padded-mj", 4), 0.0, 0.0, ShearMode::Transported).unwrap();
    let vc = VarianceConfig {
        realizations: 8,
        ..vc
    };
    let sheared = predict(&zero, disc.as_ref(), &[16], &vc).unwrap();
    let plain = predict(sampler("padded-mj", 4).as_ref(), disc.as_ref(), &[16], &vc).unwrap();
    assert_eq!(sheared.points[0].variance, plain.points[0].variance);
}

/// A shifted lattice has the same power spectrum for every shift, so its realizations' predictions
/// differ only by the spectrum method's error: the predicted slope has no interval, whatever the
/// method (a NUFFT's tolerance, or the exact DFT's rounding), while a random sampler's realizations
/// give it one. On an oblique step every frequency of the grid is active, so the full-grid sums of
/// the method are used.
#[test]
fn a_lattice_prediction_has_no_interval_at_any_tolerance() {
    let f = parse("step:theta=30").unwrap();
    let ns = [16, 64, 256];
    for method in [
        Method::nufft(1e-3).unwrap(),
        Method::nufft(1e-9).unwrap(),
        Method::Exact,
    ] {
        let vc = VarianceConfig {
            res: 32,
            res_per_n: None,
            realizations: 20,
            cones: 4,
            seed: 3,
            method,
        };
        let lattice = predict(sampler("lattice", 2).as_ref(), f.as_ref(), &ns, &vc).unwrap();
        let spread = lattice
            .points
            .iter()
            .map(|p| p.stderr / p.variance)
            .fold(0.0, f64::max);
        let fit = lattice.fit.unwrap();
        eprintln!("lattice {method:?}: largest stderr/variance {spread:e}");
        assert_eq!(fit.interval(), None, "{method:?}: {lattice:?}");
        assert!(lattice
            .cone_fits
            .iter()
            .flatten()
            .all(|c| !c.errors_defined));
        let random = predict(sampler("random", 2).as_ref(), f.as_ref(), &ns, &vc).unwrap();
        let (lo, hi) = random
            .fit
            .unwrap()
            .interval()
            .expect("a random set's interval");
        // White noise's expected prediction is `Σ |f̂|² / N`: slope −1 exactly, inside a 95 %
        // interval (at these fixed seeds).
        assert!(
            lo <= -1.0 && -1.0 <= hi,
            "{method:?}: random slope in [{lo}, {hi}]"
        );
    }
}

/// Where a lattice's spectrum is 0 at every frequency the integrand has energy, its prediction is
/// zero and its digits are rounding (a smooth Gaussian: grid sums about 1e-33): no slope, no cone
/// fits, every point flagged, while Sobol on the same Gaussian gets a slope with an interval. On an
/// axis-aligned step the grid sums are rounding beside an exact white-noise tail: the slope is the
/// tail's, with no interval (the realizations' spread, about 1e-33, is rounding), never an interval
/// fitted to rounding (before: "-1.000 .. -1.000").
#[test]
fn a_prediction_at_rounding_level_gets_no_slope_or_interval() {
    let vc = VarianceConfig {
        res: 32,
        res_per_n: None,
        realizations: 20,
        cones: 4,
        seed: 1,
        method: Method::Exact,
    };
    let gaussian = parse("gaussian:sigma=0.15").unwrap();
    let ns = [1024, 4096, 16384];
    let lattice = predict(sampler("lattice", 2).as_ref(), gaussian.as_ref(), &ns, &vc).unwrap();
    assert!(
        lattice.points.iter().all(|p| p.is_rounding()),
        "{lattice:?}"
    );
    assert!(lattice.fit.is_none(), "{lattice:?}");
    assert!(lattice.cone_fits.iter().all(Option::is_none), "{lattice:?}");
    let sobol = predict(sampler("sobol", 2).as_ref(), gaussian.as_ref(), &ns, &vc).unwrap();
    assert!(sobol.points.iter().all(|p| !p.is_rounding()), "{sobol:?}");
    assert!(sobol.fit.unwrap().interval().is_some(), "{sobol:?}");

    let step = parse("step:theta=0,c=0.5").unwrap();
    let vc = VarianceConfig { res: 128, ..vc };
    let lattice = predict(
        sampler("lattice", 2).as_ref(),
        step.as_ref(),
        &[16, 64],
        &vc,
    )
    .unwrap();
    assert!(
        lattice.points.iter().all(|p| !p.is_rounding()),
        "{lattice:?}"
    );
    assert_eq!(lattice.fit.unwrap().interval(), None, "{lattice:?}");
}

/// A narrow Gaussian (sigma = 0.02) puts energy on the whole grid, so the prediction sums the
/// full-grid NUFFT: a lattice's cones that miss its dual points are 0 (exact sums: about 1e-35),
/// and at a loose eps the NUFFT's error there (about 1e-22 at eps = 1e-3) must not pass for a
/// share with a slope (before, "cone 0 slope −3.103 ± 0.585"): every cone and N the exact sums
/// find at rounding level is within its error bound under the NUFFT, and a cone without a fit
/// there has none under the NUFFT, at eps = 1e-3 and 1e-6.
#[test]
fn a_cone_within_the_nufft_error_gets_no_slope() {
    let f = parse("gaussian:sigma=0.02").unwrap();
    let ns = [1024, 4096, 16384];
    let vc = |method| VarianceConfig {
        res: 64,
        res_per_n: None,
        realizations: 20,
        cones: 4,
        seed: 1,
        method,
    };
    let lattice = sampler("lattice", 2);
    let exact = predict(lattice.as_ref(), f.as_ref(), &ns, &vc(Method::Exact)).unwrap();
    let zero: Vec<usize> = (0..4).filter(|&c| exact.cone_fits[c].is_none()).collect();
    assert!(!zero.is_empty(), "the lattice misses some cones: {exact:?}");
    for eps in [1e-3, 1e-6] {
        let fast = predict(
            lattice.as_ref(),
            f.as_ref(),
            &ns,
            &vc(Method::nufft(eps).unwrap()),
        )
        .unwrap();
        for (e, p) in exact.points.iter().zip(&fast.points) {
            for c in (0..4).filter(|&c| e.cones[c] <= e.cone_rounding[c]) {
                assert!(
                    p.cones[c] <= p.cone_rounding[c],
                    "eps {eps:e}, N {}, cone {c}: {fast:?}",
                    p.n
                );
            }
        }
        for &c in &zero {
            assert!(
                fast.cone_fits[c].is_none(),
                "eps {eps:e}, cone {c}: {fast:?}"
            );
        }
    }
}

#[test]
fn prediction_meets_measurement_in_4d_on_two_planes() {
    // Two sheared Gaussians in xu and yv: the prediction sums the xu and yv spectra of the 4D sets.
    let f = parse("gaussian:sigma=0.12@xu+gaussian:sigma=0.12,cx=0.3@yv").unwrap();
    let s = sampler("padded-jittered", 4);
    let vc = VarianceConfig {
        res: 32,
        res_per_n: None,
        realizations: 1000,
        cones: 4,
        seed: 41,
        method: Method::Exact,
    };
    let p = &predict(s.as_ref(), f.as_ref(), &[64], &vc).unwrap().points[0];
    let cfg = ConvergeConfig {
        realizations: 20000,
        seed: 42,
        random_placement: false,
    };
    let m = measure(s.as_ref(), f.as_ref(), 64, &cfg).unwrap();
    let z = z_score(p, &m, cfg.realizations);
    eprintln!(
        "padded-jittered 4D N=64: predicted {:.4e} ± {:.1e}, measured {:.4e} ± {:.1e}, z = {z:+.2}",
        p.variance, p.stderr, m.mse, m.mse_stderr
    );
    assert!(z.abs() <= 3.0, "z = {z}");
}

/// A sum of overlapping steps has no closed-form `∫f²`; its tail comes from a randomized-QMC `∫f²`.
/// N-rooks at N = 256 with K = 4N: the prediction meets the measured MSE within 3 combined standard
/// errors, and the grid's sum alone (what the prediction was before the tail had an estimate) misses
/// it by more than 3. Measured: 1.013e-5 ± 3.1e-8 (tail 1.54e-6 ± 2.4e-8) against 1.031e-5 ± 2.2e-7
/// (R = 4000): z = −0.8, the grid alone z = 7.9.
#[test]
fn prediction_meets_measurement_on_an_overlapping_sum() {
    let f = parse("step:c=0.3+step:theta=90,c=0.6").unwrap();
    assert_eq!(f.mean_square(), None);
    let s = sampler("nrooks", 2);
    let vc = VarianceConfig {
        res: 128,
        res_per_n: Some(4),
        realizations: 200,
        cones: 4,
        seed: 7,
        method: Method::nufft(1e-9).unwrap(),
    };
    let p = &predict(s.as_ref(), f.as_ref(), &[256], &vc).unwrap().points[0];
    let cfg = ConvergeConfig {
        realizations: 4000,
        seed: 8,
        random_placement: false,
    };
    let m = measure(s.as_ref(), f.as_ref(), 256, &cfg).unwrap();
    let se = (p.stderr.powi(2) + m.mse_stderr.powi(2)).sqrt();
    let z = z_score(p, &m, cfg.realizations);
    let z_grid = (m.mse - p.grid) / se;
    eprintln!(
        "nrooks N=256: predicted {:.4e} ± {:.1e} (tail {:.3e} ± {:.1e}), measured {:.4e} ± {:.1e}, z = {z:+.2}, grid alone z = {z_grid:+.1}",
        p.variance, p.stderr, p.tail, p.tail_stderr, m.mse, m.mse_stderr
    );
    assert!(p.tail_stderr > 0.0);
    assert!(z.abs() <= 3.0, "z = {z}");
    assert!(z_grid > 3.0, "grid alone z = {z_grid}");
}

#[test]
fn nrooks_cones_aligned_versus_oblique_step() {
    let s = sampler("nrooks", 2);
    let ns = [16usize, 64, 256, 1024];
    // Aligned step: f̂ lives on the k1 axis (cone 0 of 4). The variance comes from |k1| up to a few N,
    // so the grid grows as 4N.
    let aligned = parse("step:theta=0,c=0.5").unwrap();
    let vc = VarianceConfig {
        res: 32,
        res_per_n: Some(4),
        realizations: 100,
        cones: 4,
        seed: 5,
        method: Method::Exact,
    };
    let pa = predict(s.as_ref(), aligned.as_ref(), &ns, &vc).unwrap();
    for p in &pa.points {
        let share = p.cones[0] / p.grid;
        eprintln!(
            "aligned N={:<5} variance {:.3e} (tail {:.1e}), axis cone share {share:.4}",
            p.n, p.variance, p.tail
        );
        // A step across x alone has f̂ = 0 off the k1 axis: the axis cone holds all of it, up to
        // rounding.
        assert!(
            (1.0 - share).abs() < 1e-12,
            "N={}: axis cone share {share}",
            p.n
        );
    }
    let fit = pa.cone_fits[0].unwrap();
    let total = pa.fit.unwrap();
    eprintln!(
        "aligned: axis cone slope {:.3} ± {:.3}, total {:.3} ± {:.3}",
        fit.slope, fit.stderr, total.slope, total.stderr
    );
    // As in the header: the fits' own standard errors (measured 0.004) stay below 0.05, so that the
    // ±0.15 tolerance is at least 3 of them and still tells −2 from −1.5.
    assert!(fit.stderr < 0.05 && total.stderr < 0.05);
    assert!((fit.slope + 2.0).abs() < 0.15 && (total.slope + 2.0).abs() < 0.15);

    // 30° step: the edge's spectrum lies along 30°, in cone 1; the square's sides add axis terms
    // that N-rooks suppresses. The diagonal cones (1 and 3) are white for N-rooks: slope −1.
    let oblique = parse("step:theta=30").unwrap();
    let vc = VarianceConfig {
        res: 64,
        res_per_n: None,
        method: Method::nufft(1e-9).unwrap(),
        ..vc
    };
    let po = predict(s.as_ref(), oblique.as_ref(), &ns, &vc).unwrap();
    let off: Vec<f64> = po.points.iter().map(|p| p.cones[1] + p.cones[3]).collect();
    for (p, o) in po.points.iter().zip(&off) {
        let share = o / p.grid;
        eprintln!(
            "30° N={:<5} variance {:.3e}, diagonal cones share {share:.3}",
            p.n, p.variance
        );
        if p.n >= 64 {
            assert!(share > 0.85, "N={}: diagonal share {share}", p.n);
        }
    }
    let se: Vec<f64> = po
        .points
        .iter()
        .map(|p| (p.cone_stderr[1].powi(2) + p.cone_stderr[3].powi(2)).sqrt())
        .collect();
    let nf: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    // N-rooks is random: its spread is far above any method's error, so a floor of 0 asks only for
    // nonzero standard errors.
    let fit = anisospec::converge::fit_power_law(&nf, &off, &se, &[0.0; 4]).unwrap();
    eprintln!(
        "30°: diagonal cones slope {:.3} ± {:.3}",
        fit.slope, fit.stderr
    );
    assert!(
        fit.stderr < 0.05,
        "30°: slope standard error {}",
        fit.stderr
    );
    assert!((fit.slope + 1.0).abs() < 0.15);
}

#[test]
fn same_bits_for_a_seed_whatever_the_threads() {
    let f = parse("disc:r=0.25,cx=0.4").unwrap();
    let s = sampler("mj", 2);
    let cfg = ConvergeConfig {
        realizations: 64,
        seed: 9,
        random_placement: true,
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| converge(s.as_ref(), f.as_ref(), &[16, 64], &cfg, |_| {}).unwrap())
    };
    let (a, b) = (run(1), run(3));
    for (p, q) in a.points.iter().zip(&b.points) {
        assert_eq!(p.mse.to_bits(), q.mse.to_bits());
        assert_eq!(p.mean_error.to_bits(), q.mean_error.to_bits());
    }
}

#[test]
fn random_placement_keeps_the_rate() {
    // A disc moved at random in every realization: jittered still converges at −1.5.
    let f = parse("disc:r=0.2").unwrap();
    let cfg = ConvergeConfig {
        realizations: 400,
        seed: 77,
        random_placement: true,
    };
    let c = converge(
        sampler("jittered", 2).as_ref(),
        f.as_ref(),
        &NS,
        &cfg,
        |_| {},
    )
    .unwrap();
    let fit = c.fit.unwrap();
    eprintln!(
        "jittered, disc placed at random: slope {:.3} ± {:.3}",
        fit.slope, fit.stderr
    );
    // As in the header: R = 400 over the same N gives σ(slope) ≈ 0.016, and the ±0.15 tolerance is a
    // fair test (at least 3 standard errors, and still telling −1.5 from −1 or −2) only while the fit's
    // own standard error stays below 0.05; a noisy fit must fail here rather than pass by luck.
    assert!(
        fit.stderr < 0.05,
        "slope standard error {} too large for a fair test",
        fit.stderr
    );
    assert!((fit.slope + 1.5).abs() < 0.15);
    for p in &c.points {
        // Unbiased: the mean error is within 4 standard errors of 0 (sd of e ≈ sqrt(MSE)).
        assert!(p.mean_error.abs() < 4.0 * (p.mse / 400.0).sqrt(), "{p:?}");
    }
}

/// Integrand specs that every entry point refuses, each with a phrase its message must hold: an
/// unknown name, a bad value, a disc outside the unit square (in x and in y), a fan with its shears
/// out of order, an unknown key.
const BAD_SPECS: [(&str, &str); 6] = [
    ("blob", "unknown integrand 'blob'"),
    ("gaussian:sigma=-0.1", "sigma=-0.1"),
    ("disc:r=0.3,cx=0.9", "outside the domain"),
    ("disc:r=0.4,cy=0.95", "outside the domain"),
    ("fan:s0=0.8,s1=0.2", "s0=0.8 > s1=0.2"),
    ("step:angle=3", "unknown key 'angle'"),
];

/// Runs `refuse` (named `entry` in messages) on every spec of [`BAD_SPECS`]; it returns the exit
/// code and the message: each must be a usage error (exit code 2) whose message names the fault.
fn assert_bad_specs_refused(entry: &str, refuse: impl Fn(&str) -> (Option<i32>, String)) {
    for (spec, says) in BAD_SPECS {
        let (code, message) = refuse(spec);
        assert_eq!(code, Some(2), "{entry} {spec}: {message}");
        assert!(message.contains(says), "{entry} {spec}: {message}");
    }
}

#[test]
fn bad_input_is_a_usage_error_with_exit_code_2() {
    assert_bad_specs_refused("parse", |spec| {
        let e = parse(spec).err().unwrap_or_else(|| panic!("{spec} parsed"));
        (Some(e.exit_code()), e.to_string())
    });
    let cfg = ConvergeConfig {
        realizations: 10,
        seed: 1,
        random_placement: false,
    };
    let f2 = parse("disc").unwrap();
    // A sampler whose N does not fit, a 4D sampler on a 2D integrand, too few realizations.
    for (s, n, r) in [("jittered", 15usize, 10usize), ("random", 16, 1)] {
        let e = converge(
            sampler(s, 2).as_ref(),
            f2.as_ref(),
            &[n],
            &ConvergeConfig {
                realizations: r,
                ..cfg
            },
            |_| {},
        )
        .unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
    }
    let e = converge(
        sampler("random", 4).as_ref(),
        f2.as_ref(),
        &[16],
        &cfg,
        |_| {},
    )
    .unwrap_err();
    assert_eq!(e.exit_code(), 2);
    // The Fourier prediction of a product over two projections is refused with a pointer to converge.
    let prod = parse("gaussian@xy*gaussian@uv").unwrap();
    let vc = VarianceConfig {
        res: 16,
        res_per_n: None,
        realizations: 4,
        cones: 4,
        seed: 1,
        method: Method::Exact,
    };
    let e = predict(sampler("random", 4).as_ref(), prod.as_ref(), &[16], &vc).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("converge"));
}

#[test]
fn fan_prediction_meets_measurement() {
    // The fan's Fourier coefficients come from quadrature (error < 1e-11); its double-wedge spectrum
    // spreads over the whole grid, so this also runs the full-grid (NUFFT) path.
    let f = parse("fan:s0=0.3,s1=0.7").unwrap();
    for name in ["random", "jittered"] {
        let s = sampler(name, 2);
        let vc = VarianceConfig {
            res: 64,
            res_per_n: None,
            realizations: 1000,
            cones: 4,
            seed: 51,
            method: Method::nufft(1e-9).unwrap(),
        };
        let p = &predict(s.as_ref(), f.as_ref(), &[64], &vc).unwrap().points[0];
        if name == "random" {
            assert_random_prediction_stderr(p, f.as_ref(), vc.realizations);
        }
        let cfg = ConvergeConfig {
            realizations: 20000,
            seed: 52,
            random_placement: false,
        };
        let m = measure(s.as_ref(), f.as_ref(), 64, &cfg).unwrap();
        let z = z_score(p, &m, cfg.realizations);
        eprintln!(
            "{name:>9} fan N=64: predicted {:.4e} ± {:.1e} (tail {:.1e}), measured {:.4e} ± {:.1e}, z = {z:+.2}",
            p.variance,
            p.stderr,
            p.tail,
            m.mse,
            m.mse_stderr
        );
        assert!(z.abs() <= 3.0, "{name}: z = {z}");
    }
}

#[test]
fn commands_write_csv_and_plot_and_refuse_bad_input() {
    use anisospec::cli::converge::{run as converge_run, ConvergeArgs};
    use anisospec::cli::variance::{run as variance_run, VarianceArgs};
    let dir = tempfile::tempdir().unwrap();
    let (csv, png) = (dir.path().join("conv.csv"), dir.path().join("conv.png"));
    let args = ConvergeArgs {
        sampler: vec!["random".into(), "jittered".into()],
        integrand: "disc:r=0.3".into(),
        n: vec![16, 64, 256],
        realizations: 50,
        seed: 1,
        random_placement: false,
        shear: anisospec::cli::ShearArgs {
            shear: None,
            shear_mode: anisospec::points::shear::ShearMode::Transported,
        },
        output: Some(csv.clone()),
        plot: Some(png.clone()),
        cache: None,
    };
    converge_run(&args).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows.len(), 1 + 2 * 3);
    assert!(rows[0].starts_with("sampler,integrand,n,mse,mse_stderr"));
    for r in &rows[1..] {
        let cells: Vec<&str> = r.split(',').collect();
        // The integrand name holds commas and is quoted: count from the end.
        let mse: f64 = cells[cells.len() - 8].parse().unwrap();
        let slope: f64 = cells[cells.len() - 3].parse().unwrap();
        assert!(mse > 0.0 && slope < 0.0, "{r}");
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);

    let vcsv = dir.path().join("var.csv");
    let vargs = VarianceArgs {
        sampler: "nrooks".into(),
        integrand: "step:theta=30".into(),
        n: vec![16, 64],
        res: 32,
        res_per_n: None,
        realizations: 10,
        cones: 4,
        exact: false,
        eps: 1e-9,
        seed: 1,
        shear: anisospec::cli::ShearArgs {
            shear: None,
            shear_mode: anisospec::points::shear::ShearMode::Transported,
        },
        output: Some(vcsv.clone()),
    };
    variance_run(&vargs).unwrap();
    let text = std::fs::read_to_string(&vcsv).unwrap();
    assert!(text.starts_with("n,variance,stderr,grid,tail,cone_0,cone_0_stderr"));
    assert_eq!(text.lines().count(), 3);

    // Bad input: exit code 2 and no output written.
    let bad = dir.path().join("bad.csv");
    assert_bad_specs_refused("converge", |spec| {
        let e = converge_run(&ConvergeArgs {
            integrand: spec.into(),
            output: Some(bad.clone()),
            plot: None,
            cache: None,
            ..args.clone()
        })
        .unwrap_err();
        (Some(e.exit_code()), e.to_string())
    });
    let e = converge_run(&ConvergeArgs {
        sampler: vec!["random".into(), "nosuch".into()],
        output: Some(bad.clone()),
        plot: None,
        cache: None,
        ..args.clone()
    })
    .unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(!bad.exists());
}

#[test]
fn binary_lists_integrands_and_exits_2_on_bad_input() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_anisospec");
    let out = Command::new(bin).arg("integrands").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "gaussian", "disc", "step", "sheared", "fan", "sigma", "theta", "s0",
    ] {
        assert!(
            text.contains(name),
            "{name} missing from `anisospec integrands`"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("conv.csv");
    for cmd in ["converge", "variance"] {
        assert_bad_specs_refused(cmd, |spec| {
            let out = Command::new(bin)
                .args([
                    cmd,
                    "--sampler",
                    "jittered",
                    "--integrand",
                    spec,
                    "--n",
                    "16,64",
                    "-o",
                ])
                .arg(&csv)
                .output()
                .unwrap();
            assert!(!csv.exists(), "{cmd} {spec} wrote {}", csv.display());
            (
                out.status.code(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            )
        });
    }
    // A good run writes the CSV.
    let out = Command::new(bin)
        .args([
            "converge",
            "--sampler",
            "random,mj",
            "--integrand",
            "step:theta=30",
            "--n",
            "16,64",
            "--realizations",
            "20",
            "-o",
        ])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 5);
}

/// The standard errors behind the z-tests are the right size (a z-test with an inflated standard
/// error passes anything). The prediction against the measurement, repeated over `M = 32`
/// independent seeds (jittered, N = 16, on a Gaussian; prediction R = 150, measurement R = 4000):
///
/// - `z_i = (measured_i − predicted_i) / sqrt(se_meas_i² + se_pred_i²)` is standard normal for a
///   right prediction with right standard errors, so `Σ z_i²` is chi²(M): its mean square lies in
///   `[χ²_{0.0005}(32), χ²_{0.9995}(32)] / 32 = [0.374, 2.031]` with probability 99.9 %;
/// - across seeds, the measured MSEs' sample variance `s²` over the mean reported `se_meas²` is
///   `χ²(M − 1) / (M − 1)`, in `[χ²_{0.0005}(31), χ²_{0.9995}(31)] / 31 = [0.367, 2.051]` at 99.9 %;
///   and the same for the predictions and their reported `se_pred²`.
///
/// The quantiles assume normal estimates with known variances. The departures are small beside
/// intervals from about 0.37 to 2 times the expected value: a mean of R values is near normal (an
/// MSE's skewness is about `sqrt(8 / R) = 0.045` for Gaussian errors; a prediction's is its
/// realizations' over `sqrt(150)`), each `se²` is estimated to about `sqrt((κ − 1) / R)` relative
/// (`κ` the kurtosis of what is averaged, 15 for squared Gaussian errors: 0.06 for the MSE at
/// R = 4000, about 0.3 for the prediction) but the checks average 32 of them (dividing by estimated
/// `se²` biases `z²` up by about their squared relative error, some 9 % of the prediction's share
/// at most, small beside the interval), and the whole tail beyond the grid
/// (K = 64 = 4N), white-noise estimate and error alike, is at most 2.2e-18, against
/// `se_pred` ≈ 2.6e-5.
/// Standard errors scaled by 3 give a mean square near 1/9, scaled by 1/3 near 9: both fail, as do
/// the scatter checks (each tried with the scale applied to the reported errors, then reverted).
#[test]
fn the_z_tests_standard_errors_are_calibrated() {
    let f = parse("gaussian:sigma=0.15").unwrap();
    let s = sampler("jittered", 2);
    let n = 16;
    let seeds = 32;
    let (mut z2, mut measured, mut predicted) = (Vec::new(), Vec::new(), Vec::new());
    let mut largest_tail: f64 = 0.0;
    for i in 0..seeds {
        let vc = VarianceConfig {
            res: 32,
            res_per_n: Some(4),
            realizations: 150,
            cones: 1,
            seed: 1000 + 2 * i,
            method: Method::Exact,
        };
        let p = &predict(s.as_ref(), f.as_ref(), &[n], &vc).unwrap().points[0];
        let cfg = ConvergeConfig {
            realizations: 4000,
            seed: 1001 + 2 * i,
            random_placement: false,
        };
        let m = measure(s.as_ref(), f.as_ref(), n, &cfg).unwrap();
        assert!(
            p.stderr > 0.0 && m.mse_stderr > 0.0,
            "seed {i}: {p:?} {m:?}"
        );
        let z = (m.mse - p.variance) / (p.stderr.powi(2) + m.mse_stderr.powi(2)).sqrt();
        z2.push(z * z);
        measured.push((m.mse, m.mse_stderr));
        predicted.push((p.variance, p.stderr));
        largest_tail = largest_tail.max(p.tail);
    }
    let m = seeds as f64;
    let mean_square = z2.iter().sum::<f64>() / m;
    // Sample variance of the estimates over the mean reported squared standard error.
    let scatter_ratio = |xs: &[(f64, f64)]| {
        let mean = xs.iter().map(|x| x.0).sum::<f64>() / m;
        let var = xs.iter().map(|x| (x.0 - mean).powi(2)).sum::<f64>() / (m - 1.0);
        let reported = xs.iter().map(|x| x.1 * x.1).sum::<f64>() / m;
        (var / reported, mean)
    };
    let (meas_ratio, meas_mean) = scatter_ratio(&measured);
    let (pred_ratio, pred_mean) = scatter_ratio(&predicted);
    eprintln!(
        "mean z² {mean_square:.3} over {seeds} seeds; scatter / reported se²: measured {meas_ratio:.3} (mean MSE {meas_mean:.4e}), predicted {pred_ratio:.3} (mean {pred_mean:.4e}); se_meas {:.2e}, se_pred {:.2e}; largest tail {largest_tail:.1e}",
        measured[0].1, predicted[0].1
    );
    assert!(
        (0.374..=2.031).contains(&mean_square),
        "mean z² = {mean_square} outside chi²(32)/32's 99.9 % interval"
    );
    for (what, ratio) in [("measured", meas_ratio), ("predicted", pred_ratio)] {
        assert!(
            (0.367..=2.051).contains(&ratio),
            "{what}: scatter / reported se² = {ratio} outside chi²(31)/31's 99.9 % interval"
        );
    }
}
