//! Latin constraint: chosen coordinates of an optimized set end N-stratified (one point per interval
//! `[s/N, (s+1)/N)`), with independent uniform offsets inside the intervals.
//!
//! Why: a table is used through the transported shear (DESIGN §5), which maps the pattern's first
//! coordinate onto the whole sheared axis. The edge's periodic extension in that frame jumps where the
//! coordinate wraps: an edge aligned with the pattern's axis, whose spectrum is the whole `k1` axis up
//! to `N` and beyond, where the loss's grid does not reach. N-stratification with independent offsets
//! gives that axis the N-rooks hairline, `E[P(k1, 0)] = 1 − sinc²(k1/N)` for `0 < k1 < N`.
//!
//! How: [`stratify`] moves each constrained coordinate to the stratum of its rank, at a uniform
//! random offset; the solver then keeps those coordinates [`frozen`] while the others are polished.
//! (Letting the optimizer move the offsets inside their strata was measured to raise `P(k1, 0)` above
//! the grid to 0.1–0.3, which costs more on a sheared edge than the polish gains.)

use crate::rng::Rng;
use rand::Rng as _;

/// Moves coordinates `coords` of `set` (`[n, dims]`, in `[0, 1)`) onto the N strata: the point of
/// rank `r` in a coordinate (ties by index) goes to `(r + U) / N`, `U` uniform from `rng`. A set that
/// is already N-stratified keeps its strata and gets new offsets.
pub fn stratify(set: &mut [f64], n: usize, dims: usize, coords: &[usize], rng: &mut Rng) {
    let nf = n as f64;
    for &d in coords {
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| {
            set[a * dims + d]
                .total_cmp(&set[b * dims + d])
                .then(a.cmp(&b))
        });
        for (rank, &j) in order.iter().enumerate() {
            let x = (rank as f64 + rng.random::<f64>()) / nf;
            set[j * dims + d] = x.min(1.0 - f64::EPSILON);
        }
    }
}

/// The mask, `[n, dims]`, of the coordinates `coords` of every point: `true` where the solver must
/// not move the set.
pub fn frozen(n: usize, dims: usize, coords: &[usize]) -> Vec<bool> {
    (0..n * dims)
        .map(|i| coords.contains(&(i % dims)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratify_gives_one_point_per_stratum_and_keeps_the_order() {
        let n = 257;
        let mut rng = crate::rng::stream(3, 0);
        let mut set: Vec<f64> = (0..2 * n).map(|_| rng.random::<f64>()).collect();
        let before = set.clone();
        stratify(&mut set, n, 2, &[0], &mut rng);
        let mut strata: Vec<usize> = set
            .chunks_exact(2)
            .map(|p| (p[0] * n as f64) as usize)
            .collect();
        strata.sort_unstable();
        assert_eq!(strata, (0..n).collect::<Vec<_>>());
        for (a, b) in before.chunks_exact(2).zip(set.chunks_exact(2)) {
            assert_eq!(a[1], b[1], "the free coordinate must not move");
        }
        for i in 0..n {
            for j in 0..n {
                if before[2 * i] < before[2 * j] {
                    assert!(set[2 * i] < set[2 * j], "rank order changed");
                }
            }
        }
        assert_eq!(frozen(3, 4, &[0, 1]), [true, true, false, false].repeat(3));
    }
}
