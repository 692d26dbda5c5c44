//! Convergence throughput (issue 3).
//!
//! (a) `integrand_eval`: evaluations per second of each integrand family on 65 536 fixed points (one
//!     thread; criterion reports the throughput in elements/s).
//! (b) `sweep`: one timed run of the full study of 8 samplers × 9 values of N × 1000 realizations on a
//!     Gaussian (all threads), through the library's `converge` — the job `anisospec converge` does.
//!     N = 16, 32, …, 4096, each moved to the nearest N the sampler allows. It runs once (its cost is
//!     seconds, not microseconds); the time, the evaluations and their rate are printed to stderr and
//!     written to `target/criterion/converge_sweep.csv`.
//! (c) `generate`: one set of pmj02 (2D), padded-pmj02 (4D) and the lattice (2D, 4D) at N = 1024 and
//!     65 536 on one thread, with Owen-scrambled Sobol beside them as the reference cost. Medians
//!     before and after pmj02's bit-mask strata search (2-core machine shared with other jobs, load ≈ 3.5; old and new code
//!     run back to back, Sobol 2D steady at 18.5 µs): pmj02 N = 1024 222 → 70 µs, N = 65 536
//!     22.4 → 13.2 ms; padded-pmj02 N = 1024 320 → 143 µs, N = 65 536 39.4 → 23.8 ms. The rank-1
//!     lattice (generator cached after its first search): 2D 10.8 µs and 0.76 ms, 4D 25 µs and
//!     1.78 ms, beside Sobol 4D at 20 µs and 1.71 ms.

use anisospec::converge::{converge, ConvergeConfig};
use anisospec::integrands::parse;
use anisospec::rng::stream;
use anisospec::samplers;
use criterion::{Criterion, Throughput};
use rand::Rng as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

const FAMILIES: [&str; 6] = [
    "gaussian:sigma=0.15",
    "disc:r=0.3",
    "step:theta=30",
    "sheared:s=0.5",
    "fan:s0=0.3,s1=0.7",
    "gaussian@xy*sheared:s=0.5@uv",
];

fn integrand_eval(c: &mut Criterion) {
    let count = 1 << 16;
    let mut rng = stream(3, 0);
    let pts: Vec<f64> = (0..4 * count).map(|_| rng.random::<f64>()).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let mut g = c.benchmark_group("integrand_eval");
    g.throughput(Throughput::Elements(count as u64))
        .measurement_time(Duration::from_secs(3));
    for spec in FAMILIES {
        let f = parse(spec).expect("valid spec");
        let d = f.dims();
        g.bench_function(spec, |b| {
            pool.install(|| {
                b.iter(|| {
                    black_box(
                        pts[..d * count]
                            .chunks_exact(d)
                            .map(|p| f.eval(p))
                            .sum::<f64>(),
                    )
                })
            })
        });
    }
    g.finish();
}

fn generate(c: &mut Criterion) {
    let mut g = c.benchmark_group("generate");
    g.measurement_time(Duration::from_secs(3));
    for (name, dims) in [
        ("pmj02", 2),
        ("sobol", 2),
        ("padded-pmj02", 4),
        ("sobol", 4),
        ("lattice", 2),
        ("lattice", 4),
    ] {
        let s = samplers::build(name, dims).expect("a known sampler");
        for n in [1024, 1 << 16] {
            g.bench_function(format!("{name}_{dims}d_n{n}"), |b| {
                b.iter(|| black_box(s.generate(n, &mut stream(1, 0))))
            });
        }
    }
    g.finish();
}

fn sweep() {
    let names = [
        "random", "jittered", "nrooks", "mj", "cmj", "pmj02", "halton", "sobol",
    ];
    let f = parse("gaussian:sigma=0.15").expect("valid spec");
    let cfg = ConvergeConfig {
        realizations: 1000,
        seed: 1,
        random_placement: false,
    };
    let start = Instant::now();
    let mut evaluations = 0u64;
    let mut lines = vec!["sampler,slope,slope_stderr,seconds,evaluations".to_string()];
    for name in names {
        let s = samplers::build(name, 2).expect("a known sampler");
        let ns: Vec<usize> = (4..=12)
            .map(|e| 1usize << e)
            .map(|n| s.check_n(n).map_or_else(|m| m, |_| n))
            .collect();
        let t = Instant::now();
        let c = converge(s.as_ref(), f.as_ref(), &ns, &cfg, |_| {}).expect("the sweep runs");
        let ev: u64 = c.points.iter().map(|p| p.evaluations).sum();
        evaluations += ev;
        let fit = c.fit.expect("a fit");
        lines.push(format!(
            "{name},{:.4},{:.4},{:.3},{ev}",
            fit.slope,
            fit.stderr,
            t.elapsed().as_secs_f64()
        ));
    }
    let secs = start.elapsed().as_secs_f64();
    lines.push(format!("total,,,{secs:.3},{evaluations}"));
    eprintln!(
        "converge sweep: 8 samplers x 9 N x 1000 realizations on a Gaussian: {secs:.2} s, {evaluations} evaluations ({:.1} M/s incl. sampling, {} threads)",
        evaluations as f64 / secs / 1e6,
        rayon::current_num_threads()
    );
    for l in &lines {
        eprintln!("  {l}");
    }
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("../criterion");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("converge_sweep.csv"), lines.join("\n") + "\n");
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    integrand_eval(&mut c);
    generate(&mut c);
    // `cargo bench -- NAME` filters criterion's benches; run the sweep unless a filter excludes it.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    if args.is_empty() || args.iter().any(|a| "sweep".contains(a.as_str())) {
        sweep();
    }
    c.final_summary();
}
