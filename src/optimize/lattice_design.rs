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

/// The lattice of lowest predicted variance for `target` with `n` points in `dims` (2 or 4)
/// dimensions (see the module doc). Fails with `Error::Usage` for other dims or `n` outside
/// `2 ..= LATTICE_MAX_N`, and with the target's own errors when its spectrum cannot be sampled.
pub fn design(target: &Variance, n: usize, dims: usize) -> Result<LatticeDesign> {
    if dims != 2 && dims != 4 {
        return Err(Error::Usage(format!(
            "--dims {dims}: a lattice design is 2D or 4D; use --dims 2 or --dims 4"
        )));
    }
    if !(2..=LATTICE_MAX_N).contains(&n) {
        return Err(Error::Usage(format!(
            "-n {n}: a lattice design needs 2 to {LATTICE_MAX_N} points"
        )));
    }
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
        let n = self.n as u128;
        (0..n)
            .flat_map(|i| {
                self.generator
                    .iter()
                    .map(move |&z| ((i * z as u128 % n) as f64 + 0.5) / n as f64)
            })
            .collect()
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
