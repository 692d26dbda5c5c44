//! Issue 5: targets and the optimizer. Gradient checks, target file errors, spectral fit of every
//! shipped target at N = 256, stability on degenerate starts and extreme targets, determinism.

use anisospec::optimize::loss::{Objective, Repulsion, Term};
use anisospec::optimize::solver::TIME_LIMIT_STOP;
use anisospec::optimize::{
    metrics, optimize_set, optimize_sets, Limits, SetReport, Setup, Strata, DEFAULT_ANNULAR_WEIGHT,
    DEFAULT_REPULSION,
};
use anisospec::output::write_npy;
use anisospec::points::Projection;
use anisospec::rng;
use anisospec::spectrum::Method;
use anisospec::targets::Target;
use rand::Rng as _;
use std::path::{Path, PathBuf};

/// Panics unless every run of `reports` stopped by its own rule (the iteration limit, convergence or
/// a round without progress) and not by the wall clock: a run cut short by a slow machine is not the
/// run a test describes, and its result depends on the machine's speed.
fn assert_not_time_limited(what: &str, reports: &[SetReport]) {
    for r in reports {
        eprintln!(
            "{what}, set {}: {} iterations, {}",
            r.set, r.iterations, r.stop
        );
        assert!(
            !r.stop.starts_with(TIME_LIMIT_STOP),
            "{what}, set {}: stopped by the clock after {} iterations ({})",
            r.set,
            r.iterations,
            r.stop
        );
    }
}

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("targets")
        .join(name)
}

/// An image target on disk: a dark ellipse, written to a temporary folder.
fn image_target(dir: &Path) -> Target {
    let m = 32;
    let mut px = vec![1.0; m * m];
    for i in 0..m {
        for j in 0..m {
            let (a, b) = (
                (j as f64 + 0.5) / m as f64 * 2.0 - 1.0,
                (i as f64 + 0.5) / m as f64 * 2.0 - 1.0,
            );
            if (a / 0.5).powi(2) + (b / 0.3).powi(2) < 1.0 {
                px[i * m + j] = 0.0;
            }
        }
    }
    write_npy(&dir.join("img.npy"), &[m, m], &px).unwrap();
    std::fs::write(
        dir.join("img.toml"),
        "kind = \"image\"\nfile = \"img.npy\"\nextent = 1.0\n",
    )
    .unwrap();
    Target::load(&dir.join("img.toml")).unwrap()
}

fn all_target_kinds(dir: &Path) -> Vec<Target> {
    vec![
        Target::parse("kind = \"hairline\"\nshear = 0.5\nhalf_width = 0.1\nlength = 1.2\ninner_radius = 0.3\n").unwrap(),
        Target::parse("kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 1.2\ninner_radius = 0.2\n").unwrap(),
        Target::parse("kind = \"hairline\"\nshear = 0.0\nhalf_width = 0.06\nopening = 0.03\nlength = 1.5\nfalloff = 2\ndark_weight = 2000\n").unwrap(),
        Target::parse("kind = \"double-wedge\"\ns0 = -0.2\ns1 = 0.2\nmargin = 0.05\nradius = 1.0\nfalloff = 2\n").unwrap(),
        Target::parse("kind = \"blue-noise\"\nradius = 0.45\n").unwrap(),
        image_target(dir),
        Target::parse("kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 4\nextent = 1.2\n").unwrap(),
    ]
}

/// Central finite differences of the loss against the analytic gradient (type-1 + type-2 path),
/// relative error in the Euclidean norm over all coordinates.
fn gradient_error(obj: &Objective, set: &[f64]) -> f64 {
    let g = obj.evaluate(set).gradient;
    let h = 1e-6;
    let mut num = 0.0;
    let mut den = 0.0;
    let mut x = set.to_vec();
    for i in 0..set.len() {
        x[i] = set[i] + h;
        let lp = obj.evaluate(&x).loss;
        x[i] = set[i] - h;
        let lm = obj.evaluate(&x).loss;
        x[i] = set[i];
        let fd = (lp - lm) / (2.0 * h);
        num += (fd - g[i]).powi(2);
        den += g[i] * g[i];
    }
    (num / den).sqrt()
}

#[test]
fn gradient_matches_finite_differences_for_every_target_kind() {
    let dir = tempfile::tempdir().unwrap();
    // The widest repulsion allowed (1.07 mean spacings) makes many pairs of random points interact,
    // so that term is checked too.
    let repulsion = Repulsion {
        radius: anisospec::optimize::MAX_REPULSION_RADIUS,
        weight: 1.0,
    };
    for (t, target) in all_target_kinds(dir.path()).into_iter().enumerate() {
        for dims in [2, 4] {
            let n = 48;
            let setup = Setup {
                target: target.clone(),
                n,
                dims,
                strata: Strata::default(),
                repulsion,
                method: Method::Exact,
                limits: Limits::default(),
                init: None,
                latin: false,
                // Large, so that the annular-mean term's share of the gradient is checked too.
                annular_weight: 100.0,
            };
            let obj = setup.objective().unwrap();
            let mut r = rng::stream(77, (t * 10 + dims) as u64);
            let set: Vec<f64> = (0..n * dims).map(|_| r.random::<f64>()).collect();
            assert!(
                obj.evaluate(&set).repulsion > 0.0,
                "repulsion term inactive"
            );
            let without_annuli = Setup {
                annular_weight: 0.0,
                ..setup.clone()
            };
            // A variance target has no annuli (in 4D the strata's are checked).
            if target.kind() != "variance" || dims == 4 {
                assert!(
                    obj.evaluate(&set).spectral
                        > without_annuli.objective().unwrap().evaluate(&set).spectral,
                    "annular term inactive"
                );
            }
            let err = gradient_error(&obj, &set);
            eprintln!(
                "{} {dims}D: relative gradient error {err:.2e}",
                target.kind()
            );
            // Central differences at h = 1e-6 err by rounding, about ε|L|/h ≈ 2e-10 relative
            // (measured 3e-10 to 1.3e-9 over the kinds), and by truncation h²|L'''|/6, far smaller
            // here. A gradient that drops or mis-signs one term of the loss errs by 1e-3 or more, so
            // 1e-7 (75× the largest measured) tells the two apart by four orders of magnitude.
            assert!(
                err <= 1e-7,
                "{} in {dims}D: relative gradient error {err:.2e}",
                target.kind()
            );
        }
    }
}

/// The NUFFT objective against the exact one, at two tolerances. The bound comes from the NUFFT's
/// contracts (tests/nufft.rs, `spectrum::nufft`): P errs by at most 10·eps relative (so F by 5·eps), and
/// a type-2 transform by 10·eps in relative l2. The gradient is a type-2 transform of coefficients
/// `∂L/∂P(k) · F(k) · 2πik`, whose factors' relative errors add to first order: 10·eps (∂L/∂P, through
/// P) + 5·eps (F) + 10·eps (the type-2), so 25·eps; the loss, 20·eps. Both assume what these random
/// sets give: that `P` is not close to its target where the loss weighs it (a squared difference
/// `(P − T)²` errs by `10·eps · 2P / |P − T|` relative, unbounded as `P → T`), and that the bins under
/// the contract's floor (1e-3 of the mean) carry a negligible share. (Measured: gradient 5e-11 to
/// 2.6e-9 at eps = 1e-6 and 4e-12 to 1.1e-11 at 1e-9, far inside; a gradient that drops a term errs
/// by 1e-3 or more, and one that ignores eps by 2.5e-7 at eps = 1e-3.)
#[test]
fn nufft_gradient_matches_exact_gradient() {
    let dir = tempfile::tempdir().unwrap();
    for (t, target) in all_target_kinds(dir.path()).into_iter().enumerate() {
        let n = 200;
        let mut setup = Setup {
            target,
            n,
            dims: 4,
            strata: Strata::default(),
            repulsion: DEFAULT_REPULSION,
            method: Method::Exact,
            limits: Limits::default(),
            init: None,
            latin: false,
            annular_weight: 100.0,
        };
        let exact = setup.objective().unwrap();
        let mut r = rng::stream(78, t as u64);
        let set: Vec<f64> = (0..n * 4).map(|_| r.random::<f64>()).collect();
        let a = exact.evaluate(&set);
        for eps in [1e-6, 1e-9] {
            setup.method = Method::Nufft { eps };
            let b = setup.objective().unwrap().evaluate(&set);
            let num: f64 = a
                .gradient
                .iter()
                .zip(&b.gradient)
                .map(|(x, y)| (x - y).powi(2))
                .sum();
            let den: f64 = a.gradient.iter().map(|x| x * x).sum();
            let err = (num / den).sqrt();
            let kind = setup.target.kind();
            assert!(
                err <= 25.0 * eps,
                "{kind} at eps {eps:e}: NUFFT gradient error {err:.2e}"
            );
            let loss_err = (a.loss - b.loss).abs() / a.loss;
            assert!(
                loss_err <= 20.0 * eps,
                "{kind} at eps {eps:e}: NUFFT loss error {loss_err:.2e}"
            );
        }
    }
}

/// Every target file in `targets/`.
const SHIPPED_TARGETS: [&str; 5] = [
    "hairline.toml",
    "double-wedge.toml",
    "blue-noise.toml",
    "image-ellipse.toml",
    "widened-hairline.toml",
];

#[test]
fn target_files_are_strict() {
    for name in SHIPPED_TARGETS
        .iter()
        .chain(&["fan-variance.toml", "fan-lattice.toml"])
    {
        let t = Target::load(&shipped(name)).unwrap();
        for n in [64, 256, 1024, 4096] {
            t.grid(n).unwrap_or_else(|e| panic!("{name} at N={n}: {e}"));
        }
    }
    let cases = [
        (
            "kind = \"blue-noise\"\nradius = 0.4\nradus = 1\n",
            "unknown field",
        ),
        ("kind = \"blue-noise\"\nradius = nan\n", "finite"),
        (
            "kind = \"hairline\"\nshear = 0.5\nhalf_width = -0.1\nlength = 1\n",
            "half_width",
        ),
        (
            "kind = \"double-wedge\"\ns0 = 0.7\ns1 = 0.3\nradius = 1\n",
            "s0 = 0.7 > s1 = 0.3",
        ),
        ("kind = \"spiral\"\nradius = 1\n", "kind"),
        (
            "kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 1\nmargin = -0.1\n",
            "margin",
        ),
        (
            "kind = \"hairline\"\nshear = 0\nhalf_width = 0.1\nlength = 1\nopening = -1\n",
            "opening",
        ),
        (
            "kind = \"blue-noise\"\nradius = 0.4\nfalloff = 9\n",
            "falloff",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan\"\nextent = 1\nradius = 1\n",
            "unknown field",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan@xu\"\nextent = 1\n",
            "2D integrand",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan:s0=0.7,s1=0.3\"\nextent = 1\n",
            "swap them",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan\"\nextent = 1\nshear = nan\n",
            "'shear'",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan\"\nextent = -1\n",
            "'extent'",
        ),
        (
            "kind = \"variance\"\nintegrand = \"fan\"\nextent = 1\ndesign = \"grid\"\n",
            "unknown variant",
        ),
        (
            "kind = \"hairline\"\nshear = 0.5\nhalf_width = 0.1\nlength = 1\ndesign = \"lattice\"\n",
            "unknown field",
        ),
        // Shears are capped as in the variance target; a wedge of one slope is a hairline.
        (
            "kind = \"hairline\"\nshear = 1e300\nhalf_width = 0.1\nlength = 1\n",
            "'shear' is 1e300; give a finite shear of magnitude at most 1e6",
        ),
        (
            "kind = \"double-wedge\"\ns0 = -2e6\ns1 = 0.3\nradius = 1\n",
            "'s0'",
        ),
        (
            "kind = \"double-wedge\"\ns0 = 0.5\ns1 = 0.5\nradius = 1\n",
            "s0 = s1 = 0.5, a single line, not a wedge; use kind = \"hairline\" with shear = 0.5",
        ),
    ];
    for (text, needle) in cases {
        let e = Target::parse(text).unwrap_err();
        assert!(e.to_string().contains(needle), "{text:?}: {e}");
        assert_eq!(e.exit_code(), 2);
    }
    // A dark region that holds no frequency cell is refused, naming the key, rather than optimized
    // towards a dark mean over 0 cells.
    for (text, key) in [
        ("kind = \"blue-noise\"\nradius = 0\n", "raise radius"),
        ("kind = \"blue-noise\"\nradius = 0.05\n", "raise radius"),
        (
            "kind = \"hairline\"\nshear = 0.5\nhalf_width = 0.1\nlength = 0\n",
            "raise length",
        ),
        (
            "kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 0\n",
            "raise radius or inner_radius",
        ),
    ] {
        let t = Target::parse(text).unwrap();
        let e = t.grid(256).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let e = e.to_string();
        assert!(
            e.contains("darkens no frequency cell at N = 256") && e.contains(key),
            "{text:?}: {e}"
        );
    }
    // Below N = 4 no blue-noise disc fits: one that darkens a cell darkens the 4 at |k| = 1, more than
    // N points can. Every radius is refused by the same message (radius 0.5 said "raise radius",
    // 0.75 "lower radius").
    for radius in ["0.5", "0.75", "2"] {
        let t = Target::parse(&format!("kind = \"blue-noise\"\nradius = {radius}\n")).unwrap();
        for n in [2, 3] {
            let e = t.grid(n).unwrap_err().to_string();
            assert!(e.contains(&format!("N = {n} is too small")), "{e}");
        }
        t.grid(4).map(drop).unwrap_or_else(|e| {
            assert!(!e.to_string().contains("too small"), "{e}");
        });
    }
    // Beyond reach: a blue-noise disc of radius 1 darkens about pi N cells. At N = 256 its dark
    // cells are the lattice points 0 < |k| < r = radius sqrt(N) = 16, so the reachable fraction is
    // N / (G(r) - 1), G(r) the number of lattice points in the open disc of radius r.
    let n = 256;
    let far = Target::parse("kind = \"blue-noise\"\nradius = 1.0\n").unwrap();
    let e = far.grid(n).unwrap_err().to_string();
    // The message prints 4 significant digits (rounded, so up to 5e-5 above the exact fraction); the
    // first 5 characters keep 3 decimals (truncated, so less than 1e-3 below it).
    let frac: f64 = e.split("reachable fraction ").nth(1).unwrap()[..5]
        .parse()
        .unwrap();
    // The exact fraction: N over the count of dark cells, the lattice points with 0 < |k| < r.
    let r = (n as f64).sqrt();
    let m = r as i64;
    let dark = (-m..=m)
        .flat_map(|a| (-m..=m).map(move |b| a * a + b * b))
        .filter(|&q| q > 0 && q < m * m)
        .count();
    // The count checked against the Gauss circle bound: the unit squares centred on the lattice
    // points of the open disc of radius r lie inside the disc of radius r + 1/sqrt(2) and cover the
    // disc of radius r - 1/sqrt(2), so pi (r - 1/sqrt(2))^2 <= G(r) <= pi (r + 1/sqrt(2))^2, and
    // dark = G(r) - 1 (k = 0 left out). At r = 16: 734 to 876 cells (the count is 792).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let pi = std::f64::consts::PI;
    let (fewest, most) = (pi * (r - h).powi(2) - 1.0, pi * (r + h).powi(2) - 1.0);
    assert!(
        fewest <= dark as f64 && dark as f64 <= most,
        "{dark} dark cells, not in [{fewest}, {most}]"
    );
    let exact = n as f64 / dark as f64;
    assert!(
        exact - 1e-3 < frac && frac <= exact + 5e-5,
        "{e}: exact fraction {exact}"
    );
}

/// The fit criteria of issue 5 at N = 256 over 8 sets, for every shipped target: mean expected P
/// over the dark cells ≤ 0.1, and annular-mean error ≤ 0.1 over the fitted range. Measured with these
/// settings (seed 2024): dark means 0.001–0.080, annular errors 0.001–0.006 (at N = 1024, before the
/// double wedge's and the widened hairline's dark weights were raised: 0.004–0.067 and 0.001–0.008;
/// the widened hairline now gives 0.0017 and 0.005 there). Without the loss's annular term the
/// annular errors were 0.074–0.115.
#[test]
fn shipped_targets_fit_at_256() {
    let n = 256;
    let sets = 8;
    let mut failures = Vec::new();
    for name in SHIPPED_TARGETS {
        let target = Target::load(&shipped(name)).unwrap();
        let setup = Setup {
            target,
            n,
            dims: 2,
            strata: Strata::default(),
            repulsion: DEFAULT_REPULSION,
            method: Method::Nufft { eps: 1e-8 },
            limits: Limits {
                max_iters: 3000,
                max_seconds: 120.0,
                tol: 1e-6,
            },
            init: None,
            latin: false,
            annular_weight: DEFAULT_ANNULAR_WEIGHT,
        };
        let obj = setup.objective().unwrap();
        let (pts, reports) = optimize_sets(&setup, sets, 2024, &|_| {}).unwrap();
        assert_not_time_limited(name, &reports);
        assert!(reports
            .iter()
            .all(|r| r.loss.is_finite() && r.loss < r.initial_loss));
        let fit = metrics::fit(&pts, Projection::XY, &obj.terms[0].grid, Method::Exact);
        eprintln!("{name} N={n}: {fit:?}");
        if fit.dark_mean > 0.1 || fit.annular_max_error > 0.1 {
            failures.push(format!(
                "{name}: dark mean {:.4}, annular error {:.4}",
                fit.dark_mean, fit.annular_max_error
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// A 2D objective on the shipped blue-noise target, small N.
fn small_objective(n: usize) -> Objective {
    let target = Target::load(&shipped("blue-noise.toml")).unwrap();
    Objective {
        n,
        dims: 2,
        terms: vec![Term {
            proj: Projection::XY,
            grid: target.grid(n).unwrap(),
            weight: 1.0,
        }],
        repulsion: DEFAULT_REPULSION,
        annular_weight: DEFAULT_ANNULAR_WEIGHT,
        method: Method::Exact,
    }
}

#[test]
fn degenerate_starts_end_in_a_finite_report() {
    let n = 64;
    let obj = small_objective(n);
    let limits = Limits {
        max_iters: 400,
        max_seconds: 60.0,
        tol: 1e-6,
    };
    let mut r = rng::stream(5, 0);
    // All points in one cell of side 1/sqrt(N).
    let cell: Vec<f64> = (0..2 * n).map(|_| 0.3 + r.random::<f64>() / 8.0).collect();
    // Every point twice (pairs of duplicates), and one point repeated N times.
    let half: Vec<f64> = (0..n).map(|_| r.random::<f64>()).collect();
    let dup: Vec<f64> = half.iter().chain(half.iter()).copied().collect();
    let same: Vec<f64> = (0..n).flat_map(|_| [0.25, 0.75]).collect();
    for (name, start) in [("one cell", cell), ("duplicates", dup), ("all equal", same)] {
        let (set, rep) =
            optimize_set(&obj, &start, &limits, false, 0, &mut rng::stream(6, 0)).unwrap();
        assert_not_time_limited(name, std::slice::from_ref(&rep));
        assert!(
            set.iter().all(|c| c.is_finite() && (0.0..1.0).contains(c)),
            "{name}"
        );
        assert!(
            rep.loss.is_finite() && rep.loss < rep.initial_loss,
            "{name}: {rep:?}"
        );
        eprintln!(
            "{name}: loss {:.3e} -> {:.3e}, separated {}, {}",
            rep.initial_loss, rep.loss, rep.separated, rep.stop
        );
        if name != "one cell" {
            assert!(rep.separated > 0, "{name}: duplicates not separated");
        }
        // The log starts at the starting set and ends at the iterations done, its best loss never
        // rising.
        let (first, last) = (&rep.log[0], rep.log.last().unwrap());
        assert_eq!(
            (first.iter, first.loss, first.solver),
            (0, rep.initial_loss, "start")
        );
        assert_eq!(last.iter, rep.iterations, "{name}");
        assert_eq!(last.loss, rep.loss, "{name}");
        assert!(rep
            .log
            .windows(2)
            .all(|w| w[1].loss <= w[0].loss && w[1].iter > w[0].iter));
    }
}

#[test]
fn extreme_targets_end_in_a_clear_report() {
    // Zero width: the hairline is a line of measure zero; only its inner disc and the cells exactly on
    // the line are dark. It optimizes to a finite loss.
    let zero = Target::parse("kind = \"hairline\"\nshear = 0.0\nhalf_width = 0.0\nlength = 1.0\n")
        .unwrap();
    let g = zero.grid(64).unwrap();
    assert_eq!(g.dark_cells, 16, "the k1 axis up to radius 8, both sides");
    let setup = Setup {
        target: zero,
        n: 64,
        dims: 2,
        strata: Strata::default(),
        repulsion: DEFAULT_REPULSION,
        method: Method::Exact,
        limits: Limits {
            max_iters: 300,
            max_seconds: 60.0,
            tol: 1e-6,
        },
        init: None,
        latin: false,
        annular_weight: DEFAULT_ANNULAR_WEIGHT,
    };
    let (_, reports) = optimize_sets(&setup, 2, 1, &|_| {}).unwrap();
    assert_not_time_limited("zero-width hairline", &reports);
    assert!(
        reports
            .iter()
            .all(|r| r.loss.is_finite() && r.loss < r.initial_loss),
        "{reports:?}"
    );
    // A disc of the largest radius allowed is out of reach, and says by how much.
    let all = Target::parse("kind = \"blue-noise\"\nradius = 1024\n").unwrap();
    let e = all.grid(64).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("reachable fraction"), "{e}");
}

#[test]
fn same_seed_same_bits_whatever_the_thread_count() {
    let target = Target::load(&shipped("double-wedge.toml")).unwrap();
    let setup = Setup {
        target,
        n: 32,
        dims: 4,
        strata: Strata::default(),
        repulsion: DEFAULT_REPULSION,
        method: Method::Exact,
        limits: Limits {
            max_iters: 60,
            max_seconds: 600.0,
            tol: 0.0,
        },
        init: None,
        latin: true,
        annular_weight: DEFAULT_ANNULAR_WEIGHT,
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| optimize_sets(&setup, 3, 9, &|_| {}).unwrap())
    };
    let (one, reports) = run(1);
    assert_not_time_limited("one thread", &reports);
    let (two, reports) = run(2);
    assert_not_time_limited("two threads", &reports);
    assert_eq!(one, two);
    // The Latin constraint held: x and y are N-stratified in every set.
    for set in 0..3 {
        for d in 0..2 {
            let mut strata: Vec<usize> = (0..32)
                .map(|j| (one.set(set)[j * 4 + d] * 32.0) as usize)
                .collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..32).collect::<Vec<_>>());
        }
    }
}

/// An EXR image target (top row at the highest frequency, as `anisospec spectrum` writes spectra)
/// gives the same grid as the npy it was written from (row 0 lowest): the shipped tilted ellipse,
/// which a wrong row order would mirror into the other tilt. A file that is not an EXR image is an
/// input error naming it.
#[test]
fn exr_image_targets_match_npy() {
    let npy = Target::load(&shipped("image-ellipse.toml")).unwrap();
    let Target::Image(img) = &npy else {
        panic!("image-ellipse.toml is an image target")
    };
    assert_eq!(img.shape[0], img.shape[1]);
    let dir = tempfile::tempdir().unwrap();
    anisospec::output::image::write_spectrum_exr(
        &dir.path().join("e.exr"),
        &img.pixels,
        img.shape[0],
    )
    .unwrap();
    std::fs::write(
        dir.path().join("e.toml"),
        format!(
            "kind = \"image\"\nfile = \"e.exr\"\nextent = {}\n",
            img.extent
        ),
    )
    .unwrap();
    let exr = Target::load(&dir.path().join("e.toml")).unwrap();
    let (a, b) = (npy.grid(256).unwrap(), exr.grid(256).unwrap());
    assert_eq!(a.dark, b.dark);
    assert!(a
        .target
        .iter()
        .zip(&b.target)
        .all(|(x, y)| (x - y).abs() < 1e-6));
    let mirrored: Vec<bool> = a
        .dark
        .chunks_exact(a.res)
        .rev()
        .flatten()
        .copied()
        .collect();
    assert_ne!(
        mirrored, a.dark,
        "the test image must not be symmetric under a row flip"
    );

    std::fs::write(dir.path().join("bad.exr"), b"not an image").unwrap();
    std::fs::write(
        dir.path().join("bad.toml"),
        "kind = \"image\"\nfile = \"bad.exr\"\nextent = 1\n",
    )
    .unwrap();
    let e = Target::load(&dir.path().join("bad.toml")).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("bad.exr"), "{e}");
}

/// A start whose gradient vanishes by symmetry (the rank-1 lattice (1, 1), all points on the
/// diagonal, and the built-in 2D lattice) is nudged off it. Before, the solver stopped at once,
/// "converged", and handed the start back: loss 3300 and 200 on the blue-noise target at N = 64
/// with the exact DFT, dark mean 7.1 (white noise: 1). Nudged, both fit like a Sobol start (loss
/// 0.09 and 0.08 after 200 iterations, against Sobol's 0.07), within issue 5's fit criteria (dark
/// mean P and annular error at most 0.1). A Sobol start is not nudged.
#[test]
fn a_stationary_start_is_left() {
    let n = 64;
    for (init, nudged) in [("lattice:1:1", true), ("lattice", true), ("sobol", false)] {
        let setup = Setup {
            target: Target::load(&shipped("blue-noise.toml")).unwrap(),
            n,
            dims: 2,
            strata: Strata::default(),
            repulsion: DEFAULT_REPULSION,
            method: Method::Exact,
            limits: Limits {
                max_iters: 200,
                ..Limits::default()
            },
            init: Some(init.into()),
            latin: false,
            annular_weight: DEFAULT_ANNULAR_WEIGHT,
        };
        let obj = setup.objective().unwrap();
        let (pts, reports) = optimize_sets(&setup, 1, 1, &|_| {}).unwrap();
        assert_not_time_limited(init, &reports);
        let fit = metrics::fit(&pts, Projection::XY, &obj.terms[0].grid, Method::Exact);
        assert_eq!(reports[0].nudged, nudged, "{init}");
        // The fit criteria of issue 5 (as in shipped_targets_fit_at_256).
        assert!(
            fit.dark_mean <= 0.1 && fit.annular_max_error <= 0.1,
            "{init}: loss {} from {}, {fit:?}",
            reports[0].loss,
            reports[0].initial_loss
        );
    }
}
