//! Orthogonal-array sampling of strength 2 (Jarosz, Enayet, Kensler, Kilpatrick & Christensen 2019).

use super::grid::{in_stratum, permutation};
use super::{nearest_valid, Sampler};
use crate::rng::Rng;

fn is_prime(p: usize) -> bool {
    p >= 2
        && (2..)
            .take_while(|d| d * d <= p)
            .all(|d| !p.is_multiple_of(d))
}

/// `Some(p)` if `n = p²` with `p` a prime `>= 3` (the Bose array needs `p + 1 >= 4` columns).
pub fn oa_prime(n: usize) -> Option<usize> {
    let p = super::grid::int_root(n, 2);
    (p >= 3 && p * p == n && is_prime(p)).then_some(p)
}

/// 4D orthogonal-array sampling from the Bose array OA(p², p+1, p, 2), `N = p²` with `p` an odd prime.
///
/// Row `r = (i, j)`, `i, j < p`, has symbols `A_0 = j`, `A_1 = i`, `A_c = i + (c - 1) j mod p`; any two
/// columns hold every symbol pair exactly once. Four columns are used, one per dimension, each with
/// its own random relabelling of the symbols, so every 2D projection has one point in each cell of a
/// `p × p` grid. Inside stratum `s` of a dimension, the `p` points that share it take the `p` sub-strata
/// of width `1/p²` in random order (multi-jittered offsets), so every 1D projection has one point in
/// each of the `N` strata.
#[derive(Clone, Debug)]
pub struct OrthogonalArray;

impl Sampler for OrthogonalArray {
    fn name(&self) -> String {
        "oa".into()
    }
    fn dims(&self) -> usize {
        4
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        match oa_prime(n) {
            Some(_) => Ok(()),
            None => Err(nearest_valid(n, |c| oa_prime(c).is_some())),
        }
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let p = oa_prime(n).expect("check_n passed");
        let mut out = vec![0.0; 4 * n];
        for dim in 0..4 {
            let relabel = permutation(p, rng);
            // Sub-stratum order within each stratum, and how many of its points are placed so far.
            let order: Vec<Vec<usize>> = (0..p).map(|_| permutation(p, rng)).collect();
            let mut used = vec![0usize; p];
            for r in 0..n {
                let (i, j) = (r / p, r % p);
                let symbol = match dim {
                    0 => j,
                    1 => i,
                    c => (i + (c - 1) * j) % p,
                };
                let s = relabel[symbol];
                let sub = order[s][used[s]];
                used[s] += 1;
                out[r * 4 + dim] = in_stratum(s * p + sub, n, rng);
            }
        }
        out
    }
}
