//! Lattice designs for variance targets (`design = "lattice"`): instead of moving points, search the
//! rank-1 lattices of `N` points for the generating vector whose predicted variance for the target's
//! family is lowest.
//!
//! A randomly shifted rank-1 lattice with generator `z` has `P(k) = N` on its dual lattice
//! `{k : k·z ≡ 0 (mod N)}` and 0 elsewhere ([`crate::samplers::lattice`]), so the variance of DESIGN §4
//! is exactly `Σ_{k ≠ 0 on the dual} |ĝ(k)|²`: a sum over about one frequency in `N`, cheap enough to
//! evaluate for every candidate. The sum runs over the `|ĝ|²` grid of side [`SEARCH_RES`], far wider
//! than the optimizer's fit radius: a lattice's energy sits in peaks of height `N`, and a search on the
//! fit grid alone would only push them out of sight. Frequencies beyond the grid are left out; among
//! them the multiples of `(N, 0)`, where every candidate has a peak (its first coordinate has
//! multiplier 1, so it is N-stratified), weigh the same for all.
//!
//! - 2D: `z = (1, a)`, with `a` the coprime multiplier of lowest predicted variance.
//! - 4D, `(x, y, u, v)`: `z = (1, g, a, a g)`, with `g` the best 2D lattice's multiplier
//!   ([`crate::samplers::lattice::generating_vector`]). Then `xu` is the lattice `(1, a)` and `yv`,
//!   `(g, a g)`, is the same lattice, both of lowest predicted variance; `xy` is `(1, g)` and `uv`,
//!   `(a, a g)`, the same lattice again: the largest dark disc around `k = 0` any rank-1 lattice has,
//!   the stratification the point optimizer asks of `xy` and `uv` with a blue-noise disc.
//!
//! Points sit at `((i z_d mod N) + ½) / N`: every coordinate at its strata's centres, as `--latin`
//! holds them. Each use of the table shifts it at random.

use crate::error::{Error, Result};
use crate::samplers::lattice::{gcd, generating_vector, LATTICE_MAX_N};
use crate::targets::Variance;
use rayon::prelude::*;
use serde::Serialize;

/// Side of the `|ĝ|²` grid the search sums over (frequencies `−512 … 511` in each coordinate); the
/// integrand is sampled on the largest grid the variance target allows, 4096 × 4096.
pub const SEARCH_RES: usize = 1024;

/// A searched lattice and what it predicts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LatticeDesign {
    /// Points per set.
    pub n: usize,
    /// The generating vector `z` (2 or 4 entries, `z_0 = 1`, each coprime to `n`).
    pub generator: Vec<usize>,
    /// Predicted variance of one estimate of the target's integrand (units of the integrand
    /// squared), `Σ |ĝ(k)|²` over the dual lattice points of the search grid, `k ≠ 0`.
    pub predicted_variance: f64,
    /// The same relative to random sampling's over the search grid, `(1/N) Σ_{k≠0} |ĝ(k)|²`.
    pub variance_ratio: f64,
    /// Side of the grid the sums ran over ([`SEARCH_RES`]).
    pub search_res: usize,
}

/// `Σ w(k)` over the nonzero `k` of the `res × res` grid (DESIGN §3 layout, `k1 = j − res/2`,
/// `k2 = i − res/2`) on the dual lattice `{k : k1 + a k2 ≡ 0 (mod n)}` of the 2D lattice `(1, a)`.
pub fn dual_sum(w: &[f64], res: usize, n: usize, a: usize) -> f64 {
    let (h, n, a) = ((res / 2) as i64, n as i64, a as i64);
    let mut sum = 0.0;
    for k2 in -h..h {
        // k1 ≡ −a k2 (mod n): the smallest such k1 ≥ −h, then every n-th.
        let r = (-(a % n) * (k2 % n)).rem_euclid(n);
        let mut k1 = r - n * (r + h).div_euclid(n);
        while k1 < h {
            if (k1, k2) != (0, 0) {
                sum += w[((k2 + h) * 2 * h + k1 + h) as usize];
            }
            k1 += n;
        }
    }
    sum
}

/// Checks that a lattice design (or mixture) can have `n` points: `2 ..= LATTICE_MAX_N`, else
/// `Error::Usage` naming N and the range.
pub fn check_n(n: usize) -> Result<()> {
    if !(2..=LATTICE_MAX_N).contains(&n) {
        return Err(Error::Usage(format!(
            "N = {n}: a lattice design needs 2 to {LATTICE_MAX_N} points"
        )));
    }
    Ok(())
}

/// The lattice of lowest predicted variance for `target` with `n` points in `dims` (2 or 4)
/// dimensions (see the module doc). Fails with `Error::Usage` for other dims or `n` outside
/// `2 ..= LATTICE_MAX_N`, and with the target's own errors when its spectrum cannot be sampled.
pub fn design(target: &Variance, n: usize, dims: usize) -> Result<LatticeDesign> {
    if dims != 2 && dims != 4 {
        return Err(Error::Usage(format!(
            "--dims {dims}: a lattice design is 2D or 4D; use --dims 2 or --dims 4"
        )));
    }
    check_n(n)?;
    let w = target.spectrum(SEARCH_RES)?;
    let h = SEARCH_RES / 2;
    let random: f64 = w.iter().sum::<f64>() - w[h * SEARCH_RES + h];
    if random <= 0.0 {
        return Err(Error::Input(format!(
            "target integrand '{}' has no energy at nonzero frequencies on the search grid: every set integrates it exactly, so there is nothing to design",
            target.integrand
        )));
    }
    let (best, a) = (1..n)
        .filter(|&a| gcd(a, n) == 1)
        .map(|a| (dual_sum(&w, SEARCH_RES, n, a), a))
        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
        .expect("1 is coprime to every n");
    let generator = if dims == 2 {
        vec![1, a]
    } else {
        let g = generating_vector(n, 2)[1];
        vec![1, g, a, (a as u128 * g as u128 % n as u128) as usize]
    };
    Ok(LatticeDesign {
        n,
        generator,
        predicted_variance: best,
        variance_ratio: best * n as f64 / random,
        search_res: SEARCH_RES,
    })
}

impl LatticeDesign {
    /// The lattice's points, `[n, dims]` row-major, at `((i z_d mod N) + ½) / N`.
    pub fn points(&self) -> Vec<f64> {
        lattice_points(self.n, &self.generator)
    }
}

/// The points of the rank-1 lattice of `n` points with generator `z`, `[n, dims]` row-major, at
/// `((i z_d mod N) + ½) / N`.
pub fn lattice_points(n: usize, generator: &[usize]) -> Vec<f64> {
    let n = n as u128;
    (0..n)
        .flat_map(|i| {
            generator
                .iter()
                .map(move |&z| ((i * z as u128 % n) as f64 + 0.5) / n as f64)
        })
        .collect()
}

/// Shear errors a lattice mixture is designed over: this many, evenly spaced across
/// `[−shear_error, shear_error]` (0.625 % apart at ±25 %). A lattice's variance spikes where the
/// erred edge meets one of its dual points, a narrow range of errors: designed over 41 errors
/// (1.25 % apart), the `xu` edge's 16-set mixture predicted 8.0e-7 at every one of them and 1.25e-6
/// at +1.875 %, between two; designed over 81, a replica's worst at 161 errors was 1.3 % above its
/// worst at the 81, and compare measured 1.18e-6 ± 1.2e-7 halfway between design errors against
/// 1.04e-6 ± 1.2e-7 on them (16 sets, N = 1024, R = 256).
pub const MIXTURE_ERRORS: usize = 81;

/// A mixture of rank-1 lattices (`design = "lattice-mixture"`): one generating vector per set,
/// chosen so that the worst predicted variance over the shear's errors is lowest.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LatticeMixture {
    /// Points per set.
    pub n: usize,
    /// The generating vector of each set, `(1, g, a, a g)` with the 2D multiplier `g` of the best
    /// 2D lattice in `xy` and `uv`, and the set's own `a` in `xu` and `yv`.
    pub generators: Vec<Vec<usize>>,
    /// The relative errors of the shear the mixture was designed over.
    pub errors: Vec<f64>,
    /// Predicted variance of one estimate at each error (units of the integrand squared): the mean
    /// over the sets of each lattice's `Σ |ĝ(k)|²` over its dual points on the search grid.
    pub predicted_variance: Vec<f64>,
    /// The lowest worst-case any mixture of these lattices in any proportions could have (the
    /// linear program's optimum); the sets' worst is above it by the rounding to whole sets.
    pub bound: f64,
    /// Seconds the design took, with the whole first computation of its spectra (one process
    /// computes them once and shares them, but each design is charged them).
    pub seconds: f64,
}

impl LatticeMixture {
    /// The worst predicted variance over the errors.
    pub fn worst(&self) -> f64 {
        self.predicted_variance.iter().copied().fold(0.0, f64::max)
    }

    /// Every set's points, `[sets, n, 4]` row-major.
    pub fn points(&self) -> Vec<f64> {
        self.generators
            .iter()
            .flat_map(|z| lattice_points(self.n, z))
            .collect()
    }
}

/// The mixture of `sets` rank-1 lattices of `n` points in 4D whose worst predicted variance for
/// `target`'s family over [`MIXTURE_ERRORS`] errors of its shear is lowest (the target must have
/// `design = "lattice-mixture"`, a nonzero shear and shear error).
///
/// For each error `e` the family's `|ĝ_e|²` (moved by `shear (1 + e)`, averaged over its placements)
/// is summed over the dual lattice of every coprime multiplier `a` ([`dual_sum`]): the variance
/// `V(e, a)` of DESIGN §4 for the lattice `(1, a)` in `xu` (and `yv`). A set drawn at random from a
/// mixture with weights `w_a` has variance `Σ_a w_a V(e, a)`, linear in `w`, so the weights that
/// minimize the worst error solve a linear program (microlp): minimize `t` subject to
/// `Σ_a w_a V(e, a) ≤ t` for every `e`, `Σ w_a = 1`, `w ≥ 0`. The weights are then rounded to whole
/// sets (largest remainders, ties to the smaller multiplier), and one set at a time is moved to
/// another lattice while that lowers the worst (first improvement, multipliers in increasing
/// order, at most `sets × 64` moves), so the result is deterministic.
pub fn mixture(target: &Variance, n: usize, sets: usize) -> Result<LatticeMixture> {
    mixture_over(target, n, sets, MIXTURE_ERRORS)
}

/// [`mixture`] over `count` (at least 2) errors.
fn mixture_over(target: &Variance, n: usize, sets: usize, count: usize) -> Result<LatticeMixture> {
    check_n(n)?;
    if sets == 0 {
        return Err(Error::Usage(
            "a lattice mixture needs at least one set (asked: 0 sets)".into(),
        ));
    }
    let spread = target.shear_error();
    let errors: Vec<f64> = (0..count)
        .map(|j| spread * (2.0 * j as f64 / (count - 1) as f64 - 1.0))
        .collect();
    let multipliers: Vec<usize> = (1..n).filter(|&a| gcd(a, n) == 1).collect();
    let started = std::time::Instant::now();
    // The spectra's full first computation, and the time this call waited for them.
    let (mut spectra_seconds, mut waited) = (0.0, 0.0);
    // v[j][i]: the variance at error j of the lattice with multiplier i.
    let mut v = Vec::with_capacity(errors.len());
    for e in &errors {
        let member = Variance {
            shear: target.shear * (1.0 + e),
            shear_error: Some(0.0),
            design: None,
            ..target.clone()
        };
        let asked = std::time::Instant::now();
        let (w, seconds) = member.spectrum_timed(SEARCH_RES)?;
        spectra_seconds += seconds;
        waited += asked.elapsed().as_secs_f64();
        v.push(
            multipliers
                .par_iter()
                .map(|&a| dual_sum(&w, SEARCH_RES, n, a))
                .collect::<Vec<f64>>(),
        );
    }
    let scale = v.iter().flatten().copied().fold(0.0, f64::max);
    if scale <= 0.0 {
        return Err(Error::Input(format!(
            "target integrand '{}' has no energy on any lattice's dual points of the search grid: every lattice integrates it exactly, so there is nothing to design",
            target.integrand
        )));
    }
    let (weights, bound) = minimax_weights(&v, scale)?;
    // From the rounded program's weights, or every set on the best single lattice if that is
    // better: the mixture is never worse than one lattice.
    let mut counts = whole_sets(&weights, sets);
    // Each lattice's own worst, the largest of its column; ties to the smaller multiplier.
    let (single, single_worst) = (0..multipliers.len())
        .map(|i| (i, v.iter().map(|row| row[i]).fold(0.0, f64::max)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("1 is coprime to every n");
    if single_worst < worst_of(&v, &counts) {
        counts = vec![0; multipliers.len()];
        counts[single] = sets;
    }
    improve(&v, &mut counts);
    let g = generating_vector(n, 2)[1];
    let generators = counts
        .iter()
        .zip(&multipliers)
        .flat_map(|(&c, &a)| {
            std::iter::repeat_n(
                vec![1, g, a, (a as u128 * g as u128 % n as u128) as usize],
                c,
            )
        })
        .collect();
    Ok(LatticeMixture {
        n,
        generators,
        errors,
        predicted_variance: mixed(&v, &counts),
        bound: bound.min(worst_of(&v, &counts)),
        // The spectra's time counts in full even where this call found them computed.
        seconds: started.elapsed().as_secs_f64() - waited + spectra_seconds,
    })
}

/// The variance at each error of the mixture with `counts[i]` sets of lattice `i`.
fn mixed(v: &[Vec<f64>], counts: &[usize]) -> Vec<f64> {
    let sets: usize = counts.iter().sum();
    v.iter()
        .map(|row| {
            row.iter()
                .zip(counts)
                .map(|(x, &c)| x * c as f64)
                .sum::<f64>()
                / sets as f64
        })
        .collect()
}

fn worst_of(v: &[Vec<f64>], counts: &[usize]) -> f64 {
    mixed(v, counts).into_iter().fold(0.0, f64::max)
}

/// The weights over the lattices (columns of `v`) that minimize the worst row, and that worst, by
/// the linear program of [`mixture`] on `v / scale` (values in `[0, 1]`).
fn minimax_weights(v: &[Vec<f64>], scale: f64) -> Result<(Vec<f64>, f64)> {
    use microlp::{ComparisonOp, OptimizationDirection, Problem};
    let mut lp = Problem::new(OptimizationDirection::Minimize);
    let columns = v[0].len();
    let w: Vec<_> = (0..columns)
        .map(|_| lp.add_var(0.0, (0.0, f64::INFINITY)))
        .collect();
    let t = lp.add_var(1.0, (0.0, f64::INFINITY));
    for row in v {
        let mut terms: Vec<_> = w.iter().zip(row).map(|(&x, &c)| (x, c / scale)).collect();
        terms.push((t, -1.0));
        lp.add_constraint(&terms, ComparisonOp::Le, 0.0);
    }
    let ones: Vec<_> = w.iter().map(|&x| (x, 1.0)).collect();
    lp.add_constraint(&ones, ComparisonOp::Eq, 1.0);
    let solution = lp.solve().map_err(|e| {
        Error::Numerical(format!(
            "the lattice mixture's linear program failed ({e}); use design = \"lattice\" instead"
        ))
    })?;
    let weights = w.iter().map(|&x| solution[x].max(0.0)).collect();
    Ok((weights, solution[t] * scale))
}

/// `weights` (summing to 1) as whole numbers of `sets`: the floors of `w·sets`, then one more set for
/// the largest remainders (ties to the smaller index).
fn whole_sets(weights: &[f64], sets: usize) -> Vec<usize> {
    let want: Vec<f64> = weights.iter().map(|w| w * sets as f64).collect();
    let mut counts: Vec<usize> = want.iter().map(|x| x.floor() as usize).collect();
    let placed: usize = counts.iter().sum();
    let mut order: Vec<usize> = (0..weights.len()).collect();
    order.sort_by(|&i, &j| (want[j] - want[j].floor()).total_cmp(&(want[i] - want[i].floor())));
    for &i in order.iter().take(sets.saturating_sub(placed)) {
        counts[i] += 1;
    }
    counts
}

/// Moves one set at a time from its lattice to another while that lowers the worst row (the first
/// such move in order of lattices; at most `sets × 64` moves).
fn improve(v: &[Vec<f64>], counts: &mut [usize]) {
    let total: usize = counts.iter().sum();
    let sets = total as f64;
    let mut current = mixed(v, counts);
    let mut best = current.iter().copied().fold(0.0, f64::max);
    for _ in 0..total * 64 {
        let moved = (0..counts.len())
            .filter(|&from| counts[from] > 0)
            .flat_map(|from| (0..counts.len()).map(move |to| (from, to)))
            .filter(|&(from, to)| from != to)
            .find_map(|(from, to)| {
                let worst = v
                    .iter()
                    .zip(&current)
                    .map(|(row, c)| c + (row[to] - row[from]) / sets)
                    .fold(0.0, f64::max);
                // Only a clear improvement: no cycling on rounding.
                (worst < best * (1.0 - 1e-12)).then_some((from, to))
            });
        let Some((from, to)) = moved else {
            return;
        };
        counts[from] -= 1;
        counts[to] += 1;
        current = mixed(v, counts);
        best = current.iter().copied().fold(0.0, f64::max);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::{power, Method};

    /// The dual sum is the variance DESIGN §4 predicts from the lattice's exact spectrum,
    /// `(1/N) Σ_{k≠0} w(k) P(k)`, for any weights: P is N on the dual lattice and 0 elsewhere.
    #[test]
    fn dual_sum_is_the_predicted_variance_of_the_exact_spectrum() {
        let (n, res) = (37, 48);
        let w: Vec<f64> = (0..res * res)
            .map(|i| 1.0 + ((i * 7919) % 101) as f64)
            .collect();
        for a in [1, 5, 11, 30] {
            let d = LatticeDesign {
                n,
                generator: vec![1, a],
                predicted_variance: 0.0,
                variance_ratio: 0.0,
                search_res: res,
            };
            let pts: Vec<[f64; 2]> = d.points().chunks_exact(2).map(|p| [p[0], p[1]]).collect();
            let p = power(&pts, res, Method::Exact);
            let h = res / 2;
            let predicted: f64 = (0..res * res)
                .filter(|&i| i != h * res + h)
                .map(|i| w[i] * p[i] / n as f64)
                .sum();
            let sum = dual_sum(&w, res, n, a);
            assert!(
                (sum - predicted).abs() <= 1e-9 * predicted,
                "a = {a}: {sum} against {predicted}"
            );
        }
    }

    /// The design is the coprime multiplier of lowest dual sum, and its 4D projections are the
    /// lattices of the module doc: xu and yv the searched one, xy and uv the best 2D lattice, every
    /// coordinate N-stratified at its strata's centres.
    #[test]
    fn the_design_is_the_best_lattice_and_stratifies() {
        let target = Variance {
            integrand: "fan:s0=0.3,s1=0.7,c=0.7".into(),
            shear: 0.5,
            placements: Some(0),
            shear_error: None,
            extent: 1.0,
            weight: None,
            design: None,
        };
        let n = 64;
        let d2 = design(&target, n, 2).unwrap();
        let w = target.spectrum(SEARCH_RES).unwrap();
        for a in (1..n).filter(|&a| gcd(a, n) == 1) {
            assert!(d2.predicted_variance <= dual_sum(&w, SEARCH_RES, n, a));
        }
        let korobov = dual_sum(&w, SEARCH_RES, n, generating_vector(n, 4)[2]);
        assert!(d2.predicted_variance < korobov, "{d2:?} {korobov}");
        let d4 = design(&target, n, 4).unwrap();
        let (a, g) = (d2.generator[1], generating_vector(n, 2)[1]);
        assert_eq!(d4.generator, vec![1, g, a, a * g % n]);
        assert_eq!(d4.predicted_variance, d2.predicted_variance);
        let pts = d4.points();
        for dim in 0..4 {
            let mut strata: Vec<usize> = pts
                .chunks_exact(4)
                .map(|p| {
                    let s = p[dim] * n as f64 - 0.5;
                    assert!((s - s.round()).abs() < 1e-12);
                    s.round() as usize
                })
                .collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..n).collect::<Vec<_>>());
        }
    }

    /// The linear program finds the minimax mixture: with two errors and lattices costing
    /// `[1, 0, 0.6]` and `[0, 1, 0.6]`, half of each of the first two (worst 0.5) beats the third
    /// alone (0.6). Rounded to 3 sets (2 + 1, worst 2/3), one move gives one set of each (worst
    /// 1.6/3), from which no single move lowers the worst.
    #[test]
    fn the_mixture_is_the_minimax_of_the_linear_program() {
        let v = vec![vec![1.0, 0.0, 0.6], vec![0.0, 1.0, 0.6]];
        let (w, worst) = minimax_weights(&v, 1.0).unwrap();
        assert!((worst - 0.5).abs() < 1e-9, "{worst}");
        assert!(
            (w[0] - 0.5).abs() < 1e-9 && (w[1] - 0.5).abs() < 1e-9 && w[2] < 1e-9,
            "{w:?}"
        );
        assert_eq!(whole_sets(&w, 4), vec![2, 2, 0]);
        let mut counts = whole_sets(&w, 3);
        assert_eq!(counts, vec![2, 1, 0]);
        improve(&v, &mut counts);
        assert_eq!(counts, vec![1, 1, 1]);
        assert!((worst_of(&v, &counts) - 1.6 / 3.0).abs() < 1e-12);
    }

    /// A mixture for the xu edge of shear 0.5 at three errors (-25 %, 0, +25 %; the design uses
    /// 81): each set is a lattice (1, g, a, a g), the predicted variance at each error is the mean
    /// of the sets' dual sums over that error's spectrum, recomputed here, and the worst lies between
    /// the program's bound and the best single lattice's worst.
    #[test]
    fn a_mixture_predicts_the_mean_of_its_lattices() {
        let target = Variance {
            integrand: "sheared:s=0.5,c=0.7".into(),
            shear: 0.5,
            placements: Some(0),
            shear_error: Some(0.25),
            extent: 3.0,
            weight: None,
            design: Some(crate::targets::variance::Design::LatticeMixture),
        };
        target.validate().unwrap();
        let (n, sets) = (64, 8);
        let mix = mixture_over(&target, n, sets, 3).unwrap();
        assert_eq!(mix.errors, vec![-0.25, 0.0, 0.25]);
        assert_eq!(mix.generators.len(), sets);
        let g = generating_vector(n, 2)[1];
        let spectra: Vec<_> = mix
            .errors
            .iter()
            .map(|e| {
                let member = Variance {
                    shear: 0.5 * (1.0 + e),
                    shear_error: Some(0.0),
                    design: None,
                    ..target.clone()
                };
                member.spectrum(SEARCH_RES).unwrap()
            })
            .collect();
        for z in &mix.generators {
            assert_eq!(z, &vec![1, g, z[2], z[2] * g % n]);
            assert_eq!(gcd(z[2], n), 1);
        }
        for (w, predicted) in spectra.iter().zip(&mix.predicted_variance) {
            let mean = mix
                .generators
                .iter()
                .map(|z| dual_sum(w, SEARCH_RES, n, z[2]))
                .sum::<f64>()
                / sets as f64;
            assert!(
                (mean - predicted).abs() <= 1e-12 * predicted,
                "{mean} {predicted}"
            );
        }
        let single = (1..n)
            .filter(|&a| gcd(a, n) == 1)
            .map(|a| {
                spectra
                    .iter()
                    .map(|w| dual_sum(w, SEARCH_RES, n, a))
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            mix.bound <= mix.worst() && mix.worst() <= single,
            "{mix:?} {single}"
        );
        assert_eq!(mix.points().len(), sets * n * 4);
    }

    #[test]
    fn bad_sizes_are_usage_errors() {
        let target = Variance {
            integrand: "fan:s0=0.3,s1=0.7".into(),
            shear: 0.5,
            placements: Some(0),
            shear_error: None,
            extent: 1.0,
            weight: None,
            design: None,
        };
        for (n, dims) in [(1, 2), (64, 3)] {
            assert_eq!(design(&target, n, dims).unwrap_err().exit_code(), 2);
        }
    }
}
