//! Optimizer speed against error (issue 5): the cost of one loss-and-gradient evaluation (criterion),
//! then a table of full single-set optimizations, time against final loss, for N = 256, 1024, 4096 in
//! 2D (double wedge) and 4D (double wedge on xu and yv, blue-noise strata on xy and uv).
//!
//! Goal: under 10 s per set on 2 cores for 4D N = 1024 and 2D N = 4096.
//! Set `ANISOSPEC_BENCH_QUICK=1` to skip the N = 4096 optimizations.
//!
//! Then the variance gains (issue 5), measured as the MSE over `R` realizations on the `xu` slice
//! (`x, u` = the set's two coordinates), with the edge integrands of DESIGN §5 evaluated directly:
//! - a sheared edge `H(x + s u − c)`, `c ~ U(0, 1 + s)`, `s = 0.5 (1 + δ)` with the oracle's error
//!   `δ ∈ {0, ±5 %, ±20 %}`: jittered, transported-sheared N-rooks and MJ (shear 0.5), and the
//!   widened-hairline table (targets/hairline.toml, moved by the transported shear 0.5);
//! - a fan of five edges, shears 0.3 … 0.7, each with its own `c`: jittered, Owen-scrambled Sobol,
//!   PMJ02, transported MJ (shear 0.5), and the double-wedge table (targets/double-wedge.toml, moved
//!   by the transported shear 0.5).
//!
//! Each realization draws its own set (tables: a random set of the table, a random toroidal shift,
//! then the oracle's transported shear, as `table:PATH` does). Set `ANISOSPEC_BENCH=speed` or `=variance` to run one part only.

use anisospec::optimize::{optimize_set, Limits, Setup, Strata, DEFAULT_REPULSION};
use anisospec::rng;
use anisospec::spectrum::Method;
use anisospec::targets::Target;
use criterion::Criterion;
use rand::Rng as _;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn setup(n: usize, dims: usize, max_iters: u64) -> Setup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/double-wedge.toml");
    Setup {
        target: Target::load(&path).expect("shipped target"),
        n,
        dims,
        strata: Strata::default(),
        repulsion: DEFAULT_REPULSION,
        method: Method::Nufft { eps: 1e-8 },
        limits: Limits {
            max_iters,
            max_seconds: 120.0,
            tol: 1e-6,
        },
        init: None,
        latin: false,
    }
}

fn start(n: usize, dims: usize) -> Vec<f64> {
    let mut r = rng::stream(1, 0);
    (0..n * dims).map(|_| r.random::<f64>()).collect()
}

fn evaluations(c: &mut Criterion) {
    let mut g = c.benchmark_group("loss_and_gradient");
    g.sample_size(10);
    for (n, dims) in [(256, 2), (1024, 2), (4096, 2), (256, 4), (1024, 4)] {
        let obj = setup(n, dims, 1).objective().expect("objective");
        let set = start(n, dims);
        g.bench_function(format!("{dims}d_n{n}"), |b| {
            b.iter(|| black_box(obj.evaluate(&set)))
        });
    }
    g.finish();
}

fn speed_against_error() {
    let quick = std::env::var_os("ANISOSPEC_BENCH_QUICK").is_some();
    println!("\noptimize one set (double wedge), time against final loss");
    println!(
        "{:>4} {:>6} {:>8} {:>8} {:>10} {:>12} {:>12}",
        "dims", "N", "budget", "iters", "seconds", "start loss", "final loss"
    );
    for (dims, n) in [
        (2, 256),
        (2, 1024),
        (2, 4096),
        (4, 256),
        (4, 1024),
        (4, 4096),
    ] {
        if quick && n == 4096 {
            continue;
        }
        for budget in [100, 400, 2000] {
            let s = setup(n, dims, budget);
            let obj = s.objective().expect("objective");
            let t0 = Instant::now();
            let (_, rep) = optimize_set(
                &obj,
                &start(n, dims),
                &s.limits,
                false,
                0,
                &mut rng::stream(1, 1),
            )
            .expect("optimize");
            println!(
                "{dims:>4} {n:>6} {budget:>8} {:>8} {:>10.2} {:>12.4e} {:>12.4e}",
                rep.iterations,
                t0.elapsed().as_secs_f64(),
                rep.initial_loss,
                rep.loss
            );
        }
    }
}

/// `∫∫ H(x + s u − c) dx du` over the unit square: `∫ clamp(1 − c + s u, 0, 1) du`, piecewise linear in
/// `u`, so the trapezoid rule between its kinks is exact.
fn edge_integral(s: f64, c: f64) -> f64 {
    let g = |u: f64| (1.0 - c + s * u).clamp(0.0, 1.0);
    let mut knots = vec![0.0, 1.0];
    if s != 0.0 {
        knots.extend(
            [(c - 1.0) / s, c / s]
                .into_iter()
                .filter(|u| *u > 0.0 && *u < 1.0),
        );
    }
    knots.sort_by(f64::total_cmp);
    knots
        .windows(2)
        .map(|w| (w[1] - w[0]) * (g(w[0]) + g(w[1])) / 2.0)
        .sum()
}

/// One edge: shear and offset.
type Edge = (f64, f64);

/// The mean of the edges `H(x + s u − c)` at `(x, u)`.
fn fan_value(edges: &[Edge], x: f64, u: f64) -> f64 {
    edges
        .iter()
        .map(|&(s, c)| if x + s * u >= c { 1.0 } else { 0.0 })
        .sum::<f64>()
        / edges.len() as f64
}

/// Where a realization's points come from.
enum Source {
    /// A classical sampler, optionally moved by the transported shear `s`.
    Classical(Box<dyn anisospec::samplers::Sampler>, Option<f64>),
    /// An optimized table: a random set, randomly shifted on the torus, then moved by the oracle's
    /// transported shear.
    Table(anisospec::points::PointSets, f64),
}

impl Source {
    fn draw(&self, n: usize, r: &mut anisospec::rng::Rng) -> Vec<[f64; 2]> {
        use anisospec::points::shear::{shear_pair, ShearMode};
        match self {
            Source::Classical(s, shear) => {
                let set = s.generate(n, r);
                set.chunks_exact(2)
                    .map(|p| match shear {
                        Some(sh) => {
                            let (x, u) = shear_pair(p[0], p[1], *sh, ShearMode::Transported);
                            [x, u]
                        }
                        None => [p[0], p[1]],
                    })
                    .collect()
            }
            Source::Table(t, shear) => {
                let k = r.random_range(0..t.sets());
                let (dx, du) = (r.random::<f64>(), r.random::<f64>());
                t.project(k, anisospec::points::Projection::XY)
                    .into_iter()
                    .map(|p| {
                        let (a, b) = (
                            anisospec::points::wrap(p[0] + dx),
                            anisospec::points::wrap(p[1] + du),
                        );
                        let (x, u) = shear_pair(a, b, *shear, ShearMode::Transported);
                        [x, u]
                    })
                    .collect()
            }
        }
    }
}

/// MSE and its standard error over `reps` realizations; realization `i` uses stream `i` of `seed`
/// for the points and the integrand alike, so every source sees the same integrands.
fn mse(
    source: &Source,
    n: usize,
    reps: usize,
    seed: u64,
    integrand: &(dyn Fn(&mut anisospec::rng::Rng) -> Vec<Edge> + Sync),
) -> (f64, f64) {
    use rayon::prelude::*;
    let errs: Vec<f64> = (0..reps)
        .into_par_iter()
        .map(|i| {
            let mut ri = rng::substream(seed, i as u64, 0);
            let edges = integrand(&mut ri);
            let exact =
                edges.iter().map(|&(s, c)| edge_integral(s, c)).sum::<f64>() / edges.len() as f64;
            let mut rp = rng::substream(seed, i as u64, 1);
            let pts = source.draw(n, &mut rp);
            let est = pts
                .iter()
                .map(|p| fan_value(&edges, p[0], p[1]))
                .sum::<f64>()
                / n as f64;
            (est - exact).powi(2)
        })
        .collect();
    let m = errs.iter().sum::<f64>() / reps as f64;
    let v = errs.iter().map(|e| (e - m).powi(2)).sum::<f64>() / (reps - 1) as f64;
    (m, (v / reps as f64).sqrt())
}

fn table(target: &str, n: usize, sets: usize) -> anisospec::points::PointSets {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("targets")
        .join(target);
    let s = Setup {
        target: Target::load(&path).expect("shipped target"),
        n,
        dims: 2,
        strata: Strata::default(),
        repulsion: DEFAULT_REPULSION,
        method: Method::Nufft { eps: 1e-8 },
        limits: Limits {
            max_iters: 1500,
            max_seconds: 120.0,
            tol: 1e-6,
        },
        init: Some("mj".into()),
        latin: false,
    };
    anisospec::optimize::optimize_sets(&s, sets, 7, &|_| {})
        .expect("optimize")
        .0
}

fn variance_gains() {
    use anisospec::samplers::build;
    let reps: usize = std::env::var("ANISOSPEC_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4000);
    let sets = 16;
    println!(
        "\nvariance gains: MSE over {reps} realizations (± standard error); tables of {sets} sets"
    );
    for n in [64, 256, 1024] {
        let t0 = Instant::now();
        let hair = table("hairline.toml", n, sets);
        let wedge = table("double-wedge.toml", n, sets);
        println!(
            "N = {n} (tables optimized in {:.1} s)",
            t0.elapsed().as_secs_f64()
        );
        let classical = |name: &str, shear: Option<f64>| {
            Source::Classical(build(name, 2).expect("sampler"), shear)
        };
        for delta in [0.0, 0.05, -0.05, 0.2, -0.2] {
            let s_true = 0.5 * (1.0 + delta);
            let edge = move |r: &mut anisospec::rng::Rng| {
                vec![(s_true, r.random::<f64>() * (1.0 + s_true))]
            };
            let rows = [
                ("jittered", classical("jittered", None)),
                ("transported nrooks", classical("nrooks", Some(0.5))),
                ("transported mj", classical("mj", Some(0.5))),
                ("hairline table", Source::Table(hair.clone(), 0.5)),
            ];
            let results: Vec<(&str, (f64, f64))> = rows
                .iter()
                .map(|(name, src)| (*name, mse(src, n, reps, 11, &edge)))
                .collect();
            let jit = results[0].1 .0;
            for (name, (m, se)) in &results {
                println!("  edge s={s_true:.3} (shear error {:+.0} %) {name:<20} MSE {m:.3e} ± {se:.1e}  jittered/this {:.2}", delta * 100.0, jit / m);
            }
        }
        let fan = |r: &mut anisospec::rng::Rng| {
            (0..5)
                .map(|m| {
                    let s = 0.3 + 0.1 * m as f64;
                    (s, r.random::<f64>() * (1.0 + s))
                })
                .collect::<Vec<Edge>>()
        };
        let rows = [
            ("jittered", classical("jittered", None)),
            ("sobol", classical("sobol", None)),
            ("pmj02", classical("pmj02", None)),
            ("transported mj", classical("mj", Some(0.5))),
            ("double-wedge table", Source::Table(wedge.clone(), 0.5)),
        ];
        let results: Vec<(&str, (f64, f64))> = rows
            .iter()
            .map(|(name, src)| (*name, mse(src, n, reps, 12, &fan)))
            .collect();
        let best = results[..4]
            .iter()
            .map(|r| r.1 .0)
            .fold(f64::INFINITY, f64::min);
        for (name, (m, se)) in &results {
            println!(
                "  fan 0.3..0.7 {name:<20} MSE {m:.3e} ± {se:.1e}  best classical/this {:.2}",
                best / m
            );
        }
    }
}

fn main() {
    let part = std::env::var("ANISOSPEC_BENCH").unwrap_or_default();
    if part.is_empty() || part == "speed" {
        let mut c = Criterion::default().configure_from_args();
        evaluations(&mut c);
        c.final_summary();
        speed_against_error();
    }
    if part.is_empty() || part == "variance" {
        variance_gains();
    }
}
