//! Optimizer speed against error (issue 5): the cost of one loss-and-gradient evaluation (criterion),
//! then a table of full single-set optimizations, time against final loss, for N = 256, 1024, 4096 in
//! 2D and 4D, as tables are made: the shipped double-wedge target (4D: on xu and yv, blue-noise strata
//! on xy and uv), a multi-jittered start, and the Latin constraint (a free run, then a polish with the
//! first coordinates stratified, each up to the iteration budget).
//!
//! Goal: under 10 s per set on 2 cores for 4D N = 1024 and 2D N = 4096.
//! Set `ANISOSPEC_BENCH_QUICK=1` to skip the N = 4096 optimizations. The variance the tables buy is
//! measured in `tests/compare.rs` and in `anisospec compare`.

use anisospec::optimize::{
    optimize_set, Limits, Setup, Strata, DEFAULT_ANNULAR_WEIGHT, DEFAULT_REPULSION,
};
use anisospec::rng;
use anisospec::samplers::build;
use anisospec::spectrum::Method;
use anisospec::targets::Target;
use criterion::Criterion;
use rand::Rng as _;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn setup(n: usize, dims: usize, max_iters: u64, latin: bool) -> Setup {
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
        init: Some(if dims == 4 { "xuyv-mj" } else { "mj" }.into()),
        latin,
        annular_weight: DEFAULT_ANNULAR_WEIGHT,
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
        let obj = setup(n, dims, 1, false).objective().expect("objective");
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
        for budget in [100, 300, 1000] {
            let s = setup(n, dims, budget, true);
            let obj = s.objective().expect("objective");
            let mut r = rng::stream(1, 0);
            let init = build(s.init.as_deref().expect("a start sampler"), dims).expect("sampler");
            let start = init.generate(n, &mut r);
            let t0 = Instant::now();
            let (_, rep) =
                optimize_set(&obj, &start, &s.limits, s.latin, 0, &mut r).expect("optimize");
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

fn main() {
    let mut c = Criterion::default().configure_from_args();
    evaluations(&mut c);
    c.final_summary();
    speed_against_error();
}
