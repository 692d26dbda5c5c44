//! Stratification, determinism and N-validation of every classical sampler.

use anisospec::points::shear::ShearMode;
use anisospec::points::PointSets;
use anisospec::rng::stream;
use anisospec::samplers::disk::{max_packing_radius, Poisson, DEFAULT_RELATIVE_RADIUS};
use anisospec::samplers::grid::mj_shape;
use anisospec::samplers::{
    build, catalog, generate_sets, validate_n, Sampler, Sheared, NAMES_2D, NAMES_4D,
};
use anisospec::Error;

/// A small valid N near `target` for `s`.
fn valid_near(s: &dyn Sampler, target: usize) -> usize {
    s.check_n(target).map_or_else(|n| n, |_| target)
}

/// Every registered name in `dims`, families expanded.
fn all_names(dims: usize) -> Vec<String> {
    if dims == 2 {
        NAMES_2D.iter().map(|s| s.to_string()).collect()
    } else {
        let mut v: Vec<String> = NAMES_4D.iter().map(|s| s.to_string()).collect();
        for p in ["padded", "xuyv"] {
            v.extend(NAMES_2D.iter().map(|s| format!("{p}-{s}")));
        }
        v
    }
}

/// Coordinate pairs of projection `(a, b)` of one set.
fn proj(set: &[f64], dims: usize, a: usize, b: usize) -> Vec<(f64, f64)> {
    set.chunks_exact(dims).map(|p| (p[a], p[b])).collect()
}

/// True if the `cols × rows` grid has exactly `per` points in every cell.
fn stratified(pts: &[(f64, f64)], cols: usize, rows: usize) -> bool {
    let mut counts = vec![0usize; cols * rows];
    for &(x, y) in pts {
        let i = ((x * cols as f64) as usize).min(cols - 1);
        let j = ((y * rows as f64) as usize).min(rows - 1);
        counts[j * cols + i] += 1;
    }
    let per = pts.len() / (cols * rows);
    per * cols * rows == pts.len() && counts.iter().all(|&c| c == per)
}

/// One point in each of the `n` strata of every 1D projection of `(x, y)`.
fn nrooks(pts: &[(f64, f64)]) -> bool {
    let n = pts.len();
    stratified(pts, n, 1) && stratified(pts, 1, n)
}

/// Every elementary interval `2^-a × 2^-(m-a)` of a `2^m`-point set holds one point.
fn elementary(pts: &[(f64, f64)]) -> bool {
    let n = pts.len();
    assert!(n.is_power_of_two());
    let m = n.trailing_zeros();
    (0..=m).all(|a| stratified(pts, 1 << a, 1 << (m - a)))
}

fn one_set(name: &str, dims: usize, n: usize, seed: u64) -> Vec<f64> {
    let s = build(name, dims).unwrap();
    generate_sets(s.as_ref(), n, 1, seed)
        .unwrap()
        .set(0)
        .to_vec()
}

const SEEDS: [u64; 4] = [1, 2, 77, 123_456_789];

#[test]
fn jittered_one_point_per_stratum() {
    for &seed in &SEEDS {
        for m in [1, 3, 8] {
            let set = one_set("jittered", 2, m * m, seed);
            assert!(stratified(&proj(&set, 2, 0, 1), m, m));
            let set = one_set("jittered", 4, m.pow(4), seed);
            // Every cell of the m^4 grid: count distinct 4D cells.
            let mut cells: Vec<usize> = set
                .chunks_exact(4)
                .map(|p| {
                    p.iter()
                        .fold(0, |acc, &c| acc * m + (c * m as f64) as usize)
                })
                .collect();
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(cells.len(), m.pow(4));
        }
    }
}

#[test]
fn nrooks_one_per_row_and_column() {
    for &seed in &SEEDS {
        for n in [1, 7, 100, 1000] {
            assert!(nrooks(&proj(&one_set("nrooks", 2, n, seed), 2, 0, 1)));
            let set = one_set("nrooks", 4, n, seed);
            for (a, b) in [(0, 1), (2, 3)] {
                assert!(nrooks(&proj(&set, 4, a, b)));
            }
        }
    }
}

#[test]
fn mj_and_cmj_are_nrooks_and_coarse_stratified() {
    for name in ["mj", "cmj"] {
        for &seed in &SEEDS {
            for n in [16, 20, 24, 256, 1056] {
                let (m, rows) = mj_shape(n).unwrap();
                let pts = proj(&one_set(name, 2, n, seed), 2, 0, 1);
                assert!(nrooks(&pts), "{name} N={n} not N-rooks");
                assert!(stratified(&pts, m, rows), "{name} N={n} not {m}x{rows}");
            }
        }
    }
}

#[test]
fn sobol_and_pmj02_fill_every_elementary_interval() {
    for name in ["sobol", "pmj02"] {
        for &seed in &SEEDS {
            // One sequence of 2^12 points: each of its power-of-two prefixes must be a (0,m,2)-net.
            let set = one_set(name, 2, 1 << 12, seed);
            let pts = proj(&set, 2, 0, 1);
            for m in 0..=12 {
                assert!(
                    elementary(&pts[..1 << m]),
                    "{name} seed {seed}: prefix 2^{m}"
                );
            }
            // And sets generated directly at a power of two.
            for m in [1, 5, 8] {
                let set = one_set(name, 2, 1 << m, seed);
                assert!(elementary(&proj(&set, 2, 0, 1)), "{name} N=2^{m}");
            }
        }
    }
    // The 4D Sobol set keeps the (0,m,2)-net in its first two dimensions.
    let set = one_set("sobol", 4, 1024, 5);
    assert!(elementary(&proj(&set, 4, 0, 1)));
}

#[test]
fn pmj02_prefixes_between_powers_stay_nrooks_coarse() {
    // A non-power-of-two prefix is still a valid set (no panic), with the 2^m prefix inside it.
    let set = one_set("pmj02", 2, 1000, 3);
    let pts = proj(&set, 2, 0, 1);
    assert!(elementary(&pts[..512]));
}

#[test]
fn oa_projections_are_stratified() {
    for &seed in &SEEDS {
        for p in [3usize, 5, 7, 11] {
            let n = p * p;
            let set = one_set("oa", 4, n, seed);
            for a in 0..4 {
                for b in a + 1..4 {
                    let pts = proj(&set, 4, a, b);
                    assert!(stratified(&pts, p, p), "oa N={n} dims {a}{b} not {p}x{p}");
                    assert!(nrooks(&pts), "oa N={n} dims {a}{b} not N-stratified in 1D");
                }
            }
        }
    }
}

/// What each 2D sampler promises about its own (first, second) projection at `n`.
fn promise_2d(name: &str, pts: &[(f64, f64)]) {
    let n = pts.len();
    match name {
        "jittered" => {
            let m = (n as f64).sqrt().round() as usize;
            assert!(stratified(pts, m, m), "{name}");
        }
        "nrooks" => assert!(nrooks(pts), "{name}"),
        "mj" | "cmj" => {
            let (m, rows) = mj_shape(n).unwrap();
            assert!(nrooks(pts) && stratified(pts, m, rows), "{name}");
        }
        "sobol" | "pmj02" if n.is_power_of_two() => assert!(elementary(pts), "{name}"),
        _ => {}
    }
}

#[test]
fn xuyv_and_padded_carry_the_inner_stratification() {
    for inner in ["jittered", "nrooks", "mj", "cmj", "sobol", "pmj02"] {
        for &seed in &SEEDS[..2] {
            let n = 256;
            let xuyv = one_set(&format!("xuyv-{inner}"), 4, n, seed);
            promise_2d(inner, &proj(&xuyv, 4, 0, 2));
            promise_2d(inner, &proj(&xuyv, 4, 1, 3));
            let padded = one_set(&format!("padded-{inner}"), 4, n, seed);
            promise_2d(inner, &proj(&padded, 4, 0, 1));
            promise_2d(inner, &proj(&padded, 4, 2, 3));
        }
    }
    // The xu projection of padded jittered is not jittered (DESIGN §2 note): a 16x16 jittered xu
    // projection would need every one of 256 cells filled; independent x and u leave many empty.
    let padded = one_set("padded-jittered", 4, 256, 9);
    assert!(!stratified(&proj(&padded, 4, 0, 2), 16, 16));
}

#[test]
fn every_sampler_is_in_range_deterministic_and_seed_dependent() {
    for dims in [2, 4] {
        for name in all_names(dims) {
            let s = build(&name, dims).unwrap();
            assert_eq!(s.dims(), dims);
            let n = valid_near(s.as_ref(), if name.ends_with("blue") { 64 } else { 100 });
            let run = |threads: usize, seed: u64| -> PointSets {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| generate_sets(s.as_ref(), n, 3, seed).unwrap())
            };
            let a = run(1, 42);
            let b = run(2, 42);
            assert_eq!((a.sets(), a.n(), a.dims()), (3, n, dims), "{name}");
            assert!(
                a.data()
                    .iter()
                    .all(|c| c.is_finite() && (0.0..1.0).contains(c)),
                "{name}: coordinate out of [0,1)"
            );
            let bits = |p: &PointSets| p.data().iter().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "{name}: thread count changed the bits");
            assert_ne!(a.set(0), a.set(1), "{name}: two sets of one run are equal");
            let c = run(1, 43);
            assert_ne!(
                a.data(),
                c.data(),
                "{name}: seeds 42 and 43 gave the same sets"
            );
        }
    }
}

#[test]
fn check_n_names_the_nearest_valid_n() {
    let cases: [(&str, usize, usize, usize); 9] = [
        ("jittered", 2, 50, 49),
        ("jittered", 2, 60, 64),
        ("jittered", 4, 100, 81),
        ("jittered", 4, 200, 256),
        ("oa", 4, 50, 49),
        ("oa", 4, 16, 9),
        ("mj", 2, 17, 16),
        ("padded-jittered", 4, 50, 49),
        ("sobol", 2, 70_000, 65_536),
    ];
    for (name, dims, n, nearest) in cases {
        let s = build(name, dims).unwrap();
        assert_eq!(s.check_n(n), Err(nearest), "{name} {dims}D N={n}");
        assert_eq!(s.check_n(nearest), Ok(()), "{name} {dims}D N={nearest}");
        let msg = validate_n(s.as_ref(), n).unwrap_err().to_string();
        assert!(msg.contains(&nearest.to_string()), "{msg}");
    }
    for name in ["random", "nrooks", "halton", "pmj02", "poisson", "blue"] {
        assert_eq!(build(name, 2).unwrap().check_n(123), Ok(()), "{name}");
    }
    assert!(matches!(
        validate_n(build("random", 2).unwrap().as_ref(), 0),
        Err(Error::Usage(_))
    ));
}

/// Near the coordinate limit (2^28 coordinates), the N a refusal names is one the sampler allows
/// and within the limit, for every sampler in 2D and 4D (jittered in 4D named 91^4, past the limit,
/// before).
#[test]
fn the_nearest_n_named_near_the_coordinate_limit_is_usable() {
    let names_4d = NAMES_4D
        .iter()
        .map(|n| n.to_string())
        .chain(NAMES_2D.iter().map(|n| format!("padded-{n}")));
    let all = NAMES_2D
        .iter()
        .map(|n| (n.to_string(), 2))
        .chain(names_4d.map(|n| (n, 4)));
    let mut checked = 0;
    for (name, dims) in all {
        let s = build(&name, dims).unwrap();
        let largest = anisospec::points::MAX_COORDINATES / dims;
        for n in [largest - 1, largest - 12345] {
            let Err(e) = validate_n(s.as_ref(), n) else {
                continue;
            };
            let msg = e.to_string();
            let Some(named) = msg
                .split("the nearest N it allows is ")
                .nth(1)
                .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
                .and_then(|t| t.parse::<usize>().ok())
            else {
                continue; // refused for another reason (a parameter at this N), not for N itself
            };
            assert!(named <= largest, "{name} {dims}D N={n}: {msg}");
            assert_eq!(s.check_n(named), Ok(()), "{name} {dims}D N={n}: {msg}");
            checked += 1;
        }
    }
    // Jittered, MJ, Sobol, OA and their padded forms refuse these N: the test has cases.
    assert!(checked >= 8, "{checked} refusals checked");
    // Several sets drawn together: the named N keeps all of them within the limit (3 sets of the
    // nearer 44742721 points would not fit).
    let jittered = build("jittered", 2).unwrap();
    let msg = generate_sets(jittered.as_ref(), 44_739_240, 3, 1)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("the nearest N it allows is 44729344"), "{msg}");
    // The N a command substitutes for one the sampler cannot make (gallery, compare) is within the
    // limit too: 90^4, not 91^4.
    let jittered_4d = build("jittered", 4).unwrap();
    assert_eq!(
        anisospec::samplers::usable_n(jittered_4d.as_ref(), 67_108_863),
        65_610_000
    );
}

#[test]
fn poisson_keeps_the_requested_radius() {
    let sampler = Poisson::default();
    for &seed in &SEEDS {
        for n in [64, 500] {
            let set = sampler.try_generate(n, &mut stream(seed, 0)).unwrap();
            let r = DEFAULT_RELATIVE_RADIUS * max_packing_radius(n);
            let pts = proj(&set, 2, 0, 1);
            let mut min_d2 = f64::INFINITY;
            for i in 0..n {
                for j in 0..i {
                    let d = |a: f64, b: f64| {
                        let t = (a - b).abs();
                        t.min(1.0 - t)
                    };
                    let dx = d(pts[i].0, pts[j].0);
                    let dy = d(pts[i].1, pts[j].1);
                    min_d2 = min_d2.min(dx * dx + dy * dy);
                }
            }
            assert!(
                min_d2.sqrt() >= r,
                "N={n}: min distance {} < {r}",
                min_d2.sqrt()
            );
            // The fallible path and the trait path agree when the first radius suffices.
            assert_eq!(set, sampler.generate(n, &mut stream(seed, 0)));
        }
    }
    // An unreachable radius is reported, not looped on.
    let tight = Poisson::new(0.99).unwrap();
    assert!(matches!(
        tight.try_generate(200, &mut stream(1, 0)),
        Err(Error::Numerical(_))
    ));
    // The infallible path backs off instead, and says how far; the set keeps the radius it reports.
    let (set, rel) = tight.generate_reporting(200, &mut stream(1, 0));
    assert!(rel < 0.99 && rel > 0.5, "backed-off relative radius {rel}");
    let nn = nn_distances(&set);
    assert_eq!(nn.len(), 200);
    assert!(nn.iter().all(|&d| d >= rel), "a pair is closer than {rel}");
    assert!(Poisson::new(0.0).is_err() && Poisson::new(1.5).is_err());
}

#[test]
fn registry_lists_and_rejects_helpfully() {
    let cat = catalog();
    for name in NAMES_2D {
        assert!(
            cat.iter().any(|i| i.name == name && i.dims.contains(&2)),
            "{name}"
        );
    }
    for name in NAMES_4D {
        assert!(
            cat.iter().any(|i| i.name == name && i.dims.contains(&4)),
            "{name}"
        );
    }
    let err = |name: &str, dims| match build(name, dims) {
        Err(Error::Usage(m)) => m,
        _ => panic!("{name} {dims}D should be a usage error"),
    };
    let m = err("cjm", 2);
    assert!(m.contains("'cmj'") && m.contains("pmj02"), "{m}");
    let m = err("mj", 4);
    assert!(m.contains("padded-mj"), "{m}");
    let m = err("oa", 2);
    assert!(m.contains("--dims 4"), "{m}");
    let m = err("padded-foo", 4);
    assert!(m.contains("padded-"), "{m}");
    assert!(build("random", 3).is_err());
    assert_eq!(build("xuyv-cmj", 4).unwrap().name(), "xuyv-cmj");
}

#[test]
fn sheared_wraps_a_4d_sampler() {
    let inner = build("xuyv-nrooks", 4).unwrap();
    let sheared = Sheared::new(inner, 0.5, -0.3, ShearMode::Transported).unwrap();
    assert_eq!(sheared.dims(), 4);
    let pts = generate_sets(&sheared, 256, 2, 7).unwrap();
    assert!(pts.data().iter().all(|c| (0.0..1.0).contains(c)));
    // Transported shear: t = x + s u inherits the N-rooks stratification of the first coordinate, so
    // the inverse CDF of t maps the points to one per stratum of N.
    let set = pts.set(0);
    let s = 0.5f64;
    let cdf = |t: f64| {
        // Trapezoid CDF of t = x + s u, x,u ~ U[0,1), s < 1.
        if t < s {
            t * t / (2.0 * s)
        } else if t <= 1.0 {
            t - s / 2.0
        } else {
            1.0 - (1.0 + s - t).powi(2) / (2.0 * s)
        }
    };
    let a: Vec<(f64, f64)> = set
        .chunks_exact(4)
        .map(|p| (cdf(p[0] + s * p[2]).clamp(0.0, 1.0 - 1e-15), 0.5))
        .collect();
    assert!(stratified(&a, 256, 1));
    assert!(Sheared::new(build("mj", 2).unwrap(), 0.5, 0.5, ShearMode::Wrap).is_err());
}

/// Nearest-neighbour toroidal distances of one 2D set, in units of the hexagonal packing radius.
fn nn_distances(set: &[f64]) -> Vec<f64> {
    let n = set.len() / 2;
    let r = max_packing_radius(n);
    let d = |a: f64, b: f64| {
        let t = (a - b).abs();
        t.min(1.0 - t)
    };
    (0..n)
        .map(|i| {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| d(set[2 * i], set[2 * j]).hypot(d(set[2 * i + 1], set[2 * j + 1])))
                .fold(f64::INFINITY, f64::min)
                / r
        })
        .collect()
}

#[test]
fn blue_noise_spreads_its_points() {
    // White noise has mean nearest-neighbour distance 1/(2 sqrt N) = 0.465 packing radii and a
    // minimum near 0.02; measured for blue (20 Lloyd steps): mean 0.84-0.87, minimum 0.56-0.75 over
    // 24 sets (seeds 0-7, N = 64, 256, 1024), the spread of the mean across seeds about 0.006.
    // The white-noise check: NN distance has sd 0.243 packing radii, so the mean of 256 has a
    // standard error near 0.015 and 0.05 is over 3 standard errors.
    for &seed in &SEEDS {
        let set = one_set("blue", 2, 256, seed);
        let nn = nn_distances(&set);
        let mean = nn.iter().sum::<f64>() / nn.len() as f64;
        let min = nn.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(mean > 0.8, "seed {seed}: mean NN distance {mean}");
        assert!(min > 0.4, "seed {seed}: min NN distance {min}");
        let white = one_set("random", 2, 256, seed);
        let wmean = nn_distances(&white).iter().sum::<f64>() / 256.0;
        assert!((wmean - 0.465).abs() < 0.05, "white noise mean NN {wmean}");
    }
}

#[test]
fn halton_prefixes_stratify_mixed_radix_grids() {
    // The first 2^a 3^b points of scrambled Halton (2,3) put one point in each 2^-a x 3^-b cell
    // (digit scrambling permutes the leading digits, CRT pairs them).
    for &seed in &SEEDS {
        let set = one_set("halton", 2, 72, seed);
        assert!(stratified(&proj(&set, 2, 0, 1), 8, 9));
        let set = one_set("halton", 4, 210, seed);
        assert!(stratified(&proj(&set, 4, 0, 1), 2, 3));
        assert!(stratified(&proj(&set, 4, 2, 3), 5, 7));
        assert!(stratified(&proj(&set, 4, 0, 3), 2, 7));
    }
}

/// Mean over `sets` realizations of `P(k) - expect(k)` averaged over the frequencies `keep` accepts on
/// a 16 × 16 grid, with its standard error (from the spread of the per-set means).
fn spectral_excess(
    pts: &PointSets,
    a: usize,
    b: usize,
    keep: impl Fn(i64, i64) -> bool,
    expect: impl Fn(i64, i64) -> f64,
) -> (f64, f64) {
    use anisospec::points::Projection;
    use anisospec::spectrum::{power, Method};
    let res = 16usize;
    let per_set: Vec<f64> = (0..pts.sets())
        .map(|s| {
            let p = power(&pts.project(s, Projection { a, b }), res, Method::Exact);
            let (mut sum, mut count) = (0.0, 0);
            for i in 0..res {
                for j in 0..res {
                    let (k1, k2) = (j as i64 - 8, i as i64 - 8);
                    if (k1, k2) != (0, 0) && keep(k1, k2) {
                        sum += p[i * res + j] - expect(k1, k2);
                        count += 1;
                    }
                }
            }
            sum / count as f64
        })
        .collect();
    let r = per_set.len() as f64;
    let mean = per_set.iter().sum::<f64>() / r;
    let var = per_set.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (r - 1.0);
    (mean, (var / r).sqrt())
}

#[test]
fn spectra_match_theory_where_it_is_known() {
    let sinc2 = |t: f64| if t == 0.0 { 1.0 } else { (t.sin() / t).powi(2) };
    let m = 16.0;
    // Jittered with m × m cells: E[P(k)] = 1 - sinc²(π k1/m) sinc²(π k2/m) for 0 < |k| < m.
    let jit = |k1: i64, k2: i64| {
        1.0 - sinc2(std::f64::consts::PI * k1 as f64 / m)
            * sinc2(std::f64::consts::PI * k2 as f64 / m)
    };
    let low = |k1: i64, k2: i64| k1 * k1 + k2 * k2 <= 16;
    let off_axis = |k1: i64, k2: i64| k1 != 0 && k2 != 0;
    let sets = |name: &str, dims, seed| {
        generate_sets(build(name, dims).unwrap().as_ref(), 256, 64, seed).unwrap()
    };
    let checks = [
        ("random", 2, 0, 1, true),
        ("jittered", 2, 0, 1, false),
        ("xuyv-jittered", 4, 0, 2, false),
        ("xuyv-jittered", 4, 1, 3, false),
        ("padded-jittered", 4, 0, 1, false),
        ("random", 4, 1, 2, true),
    ];
    for (seed, (name, dims, a, b, white)) in (11..).zip(checks) {
        // A different seed per check: sets of one seed share their first inner 2D set.
        let pts = sets(name, dims, seed);
        let (excess, se) = if white {
            spectral_excess(&pts, a, b, low, |_, _| 1.0)
        } else {
            spectral_excess(&pts, a, b, low, jit)
        };
        assert!(
            excess.abs() < 4.0 * se,
            "{name} ({a},{b}): excess {excess} ± {se}"
        );
        // The 4-standard-error test above must have power: for white noise the 48 bins hold 24
        // independent exponential P (P(k) = P(-k)), so se ≈ 1/sqrt(24 · 64) = 0.026 over 64 sets,
        // estimated within about 9 %; stratified sets have less spread. Twice that is a broken spread.
        assert!(se > 0.0 && se < 0.05, "{name}: standard error {se}");
    }
    // Padding leaves xu white away from the axes (DESIGN §2): far above the jittered spectrum there.
    let pts = sets("padded-jittered", 4, 99);
    let (excess, se) = spectral_excess(
        &pts,
        0,
        2,
        |k1, k2| low(k1, k2) && off_axis(k1, k2),
        |_, _| 1.0,
    );
    assert!(
        excess.abs() < 4.0 * se,
        "padded-jittered xu: excess {excess} ± {se}"
    );
    let (gap, _) = spectral_excess(&pts, 0, 2, |k1, k2| low(k1, k2) && off_axis(k1, k2), jit);
    assert!(
        gap > 10.0 * se,
        "padded-jittered xu is not whiter than jittered: {gap} vs {se}"
    );
}

#[test]
fn every_sampler_handles_its_smallest_sets() {
    for dims in [2, 4] {
        for name in all_names(dims) {
            let s = build(&name, dims).unwrap();
            for target in [1, 2, 3] {
                let n = valid_near(s.as_ref(), target);
                let pts = generate_sets(s.as_ref(), n, 2, 5).unwrap();
                assert_eq!(pts.n(), n, "{name}");
                assert!(
                    pts.data().iter().all(|c| (0.0..1.0).contains(c)),
                    "{name} N={n}"
                );
            }
        }
    }
}

/// How far the exact DFT's `P` of a shifted rank-1 lattice of `n` points may be from the ideal
/// spectrum on a `res × res` grid (`u = 2^−53`): `(on_dual, off_dual)`, the absolute error where
/// `P = N` and the largest `P` elsewhere. The crate bounds the computation of `F` by
/// `ρ_F N` at any bin ([`anisospec::spectrum::exact::sum_error`]); the stored points are off the ideal
/// lattice too: `stratum / N` rounds by at most `u / 2` and adding the shift by at most `u` (a sum
/// below 2), the wrap being exact, so each coordinate by `1.5 u`, and a term `exp(−2πi k·x)` moves by
/// at most `2π (|k1| + |k2|) 1.5 u ≤ 3π K u` (the part common to every point, the shift's own value,
/// turns `F` by one phase and leaves `P` alone). So `|F̂ − F| ≤ ρ N` with `ρ = ρ_F + 3π K u`:
/// `|F̂| ≤ (1 + ρ) N` on the dual lattice, where `|F| = N`, and `|F̂| ≤ ρ N` off it, where `F = 0`;
/// `|F̂|² / N` adds at most `3 u` relative (two squares, a sum, a division), allowed as `4 u`.
fn lattice_power_error(n: usize, res: usize) -> (f64, f64) {
    let u = f64::EPSILON / 2.0;
    let rho =
        anisospec::spectrum::exact::sum_error(n, res) + 3.0 * std::f64::consts::PI * res as f64 * u;
    let nf = n as f64;
    (
        ((1.0 + rho).powi(2) * (1.0 + 4.0 * u) - 1.0) * nf,
        rho * rho * nf * (1.0 + 4.0 * u),
    )
}

/// The rank-1 lattice is an N-rooks set, and a shifted lattice's power spectrum is exactly `N` on its
/// dual lattice `k1 + g k2 ≡ 0 (mod N)` and 0 elsewhere (exact DFT, within the rounding bound of
/// [`lattice_power_error`]), for a power of two and
/// for an N with odd factors; `xuyv-lattice` carries the lattice into `xu`; in 4D every 2D
/// projection `(i, j)` has the spectrum of the 2D lattice `(z_i, z_j)`.
#[test]
fn lattice_is_nrooks_with_its_spectrum_on_the_dual_lattice() {
    use anisospec::samplers::lattice::generating_vector;
    use anisospec::spectrum::{power, Method};
    let res = 64;
    for (n, seed) in [(256usize, 3u64), (250, 4), (1021, 5)] {
        let g = generating_vector(n, 2)[1] as i64;
        let set = one_set("lattice", 2, n, seed);
        let pts = proj(&set, 2, 0, 1);
        assert!(nrooks(&pts), "lattice N={n} not N-rooks");
        let xy: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
        let p = power(&xy, res, Method::Exact);
        let (on_bound, off_bound) = lattice_power_error(n, res);
        let (mut worst_on, mut worst_off) = (0.0f64, 0.0f64);
        let half = res as i64 / 2;
        for (idx, &v) in p.iter().enumerate() {
            let (k2, k1) = (
                idx as i64 / res as i64 - half,
                idx as i64 % res as i64 - half,
            );
            let on_dual = (k1 + g * k2).rem_euclid(n as i64) == 0;
            let (expected, bound) = if on_dual {
                (n as f64, on_bound)
            } else {
                (0.0, off_bound)
            };
            let error = (v - expected).abs();
            assert!(
                error <= bound,
                "N={n} g={g} k=({k1},{k2}): P = {v}, expected {expected} within {bound:.2e}"
            );
            if on_dual {
                worst_on = worst_on.max(error / bound);
            } else {
                worst_off = worst_off.max(error / bound);
            }
        }
        eprintln!(
            "lattice N={n}: bounds {on_bound:.2e} on the dual lattice, {off_bound:.2e} off it; worst error / bound {worst_on:.2e} on, {worst_off:.2e} off"
        );
    }
    let set = one_set("xuyv-lattice", 4, 256, 6);
    assert!(nrooks(&proj(&set, 4, 0, 2)) && nrooks(&proj(&set, 4, 1, 3)));
    // 4D (Korobov): every 2D projection (i, j) is the lattice of (z_i, z_j).
    for (n, seed) in [(256usize, 7u64), (243, 8)] {
        let z: Vec<i64> = generating_vector(n, 4).iter().map(|&c| c as i64).collect();
        let set = one_set("lattice", 4, n, seed);
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let pts = proj(&set, 4, a, b);
            assert!(nrooks(&pts), "4D lattice N={n} ({a},{b}) not N-rooks");
            let xy: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let p = power(&xy, 32, Method::Exact);
            let (on_bound, off_bound) = lattice_power_error(n, 32);
            let mut worst = 0.0f64;
            for (idx, &v) in p.iter().enumerate() {
                let (k2, k1) = (idx as i64 / 32 - 16, idx as i64 % 32 - 16);
                let on_dual = (k1 * z[a] + k2 * z[b]).rem_euclid(n as i64) == 0;
                let (expected, bound) = if on_dual {
                    (n as f64, on_bound)
                } else {
                    (0.0, off_bound)
                };
                let error = (v - expected).abs();
                assert!(
                    error <= bound,
                    "4D N={n} ({a},{b}) k=({k1},{k2}): P = {v}, expected {expected} within {bound:.2e}"
                );
                worst = worst.max(error / bound);
            }
            eprintln!("4D lattice N={n} ({a},{b}): worst error / bound {worst:.2e}");
        }
    }
}

/// `lattice:Z` takes the generating vector given: with the built-in lattice's own vector it draws the
/// same bits for a seed (2D Fibonacci 89 points, 4D Korobov 256 points); entries are taken mod N (an
/// entry N + 34 is 34); a wrong count or a non-number is a usage error naming the form.
#[test]
fn given_lattice_takes_its_generating_vector() {
    use anisospec::samplers::lattice::generating_vector;
    for (n, dims) in [(89usize, 2usize), (256, 4)] {
        let z: Vec<String> = generating_vector(n, dims)
            .iter()
            .map(|c| c.to_string())
            .collect();
        let name = format!("lattice:{}", z.join(":"));
        assert_eq!(build(&name, dims).unwrap().name(), name);
        assert_eq!(
            one_set(&name, dims, n, 9),
            one_set("lattice", dims, n, 9),
            "{name}"
        );
    }
    assert_eq!(
        one_set("lattice:1:123", 2, 89, 4),
        one_set("lattice:1:34", 2, 89, 4)
    );
    for (name, dims, says) in [
        ("lattice:1:2:3", 2, "has 3 entries but the sets are 2D"),
        ("lattice:1:34", 4, "has 2 entries but the sets are 4D"),
        ("lattice:1:x", 2, "'x' is not a whole number"),
        ("lattice:", 2, "is not a whole number"),
        ("lattice:1:-3", 2, "'-3' is not a whole number"),
    ] {
        match build(name, dims) {
            Err(e @ Error::Usage(_)) => {
                let m = e.to_string();
                assert!(
                    m.contains(says) && m.contains("lattice:1:34 (2D)"),
                    "{name}: {m}"
                );
                assert_eq!(e.exit_code(), 2);
            }
            Err(e) => panic!("{name}: {e} is not a usage error"),
            Ok(_) => panic!("{name} {dims}D was accepted"),
        }
    }
}
