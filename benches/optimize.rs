//! Optimizer speed against error (issue 5): the cost of one loss-and-gradient evaluation (criterion),
//! then a table of full single-set optimizations, time against final loss, for N = 256, 1024, 4096 in
//! 2D (double wedge) and 4D (double wedge on xu and yv, blue-noise strata on xy and uv).
//!
//! Goal: under 10 s per set on 2 cores for 4D N = 1024 and 2D N = 4096.
//! Set `ANISOSPEC_BENCH_QUICK=1` to skip the N = 4096 optimizations.

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
        limits: Limits { max_iters, max_seconds: 120.0, tol: 1e-6 },
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
        g.bench_function(format!("{dims}d_n{n}"), |b| b.iter(|| black_box(obj.evaluate(&set))));
    }
    g.finish();
}

fn speed_against_error() {
    let quick = std::env::var_os("ANISOSPEC_BENCH_QUICK").is_some();
    println!("\noptimize one set (double wedge), time against final loss");
    println!("{:>4} {:>6} {:>8} {:>8} {:>10} {:>12} {:>12}", "dims", "N", "budget", "iters", "seconds", "start loss", "final loss");
    for (dims, n) in [(2, 256), (2, 1024), (2, 4096), (4, 256), (4, 1024), (4, 4096)] {
        if quick && n == 4096 {
            continue;
        }
        for budget in [100, 400, 2000] {
            let s = setup(n, dims, budget);
            let obj = s.objective().expect("objective");
            let t0 = Instant::now();
            let (_, rep) = optimize_set(&obj, &start(n, dims), &s.limits, 0, &mut rng::stream(1, 1)).expect("optimize");
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
