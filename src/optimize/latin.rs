//! Latin constraint: chosen coordinates of an optimized set are N-stratified (one point per interval
//! `[s/N, (s+1)/N)`) and held where the start put them; the optimizer moves only the others.
//!
//! Why: a table is used through the transported shear (DESIGN §5), which maps the pattern's first
//! coordinate onto the whole sheared axis. The edge's periodic extension in that frame jumps where the
//! coordinate wraps: an edge aligned with the pattern's axis, whose spectrum is the whole `k1` axis up
//! to `N` and beyond, where the loss's grid does not reach. An N-stratified coordinate gives that axis
//! the N-rooks hairline: `E[P(k1, 0)] = 1 − sinc²(k1/N)` for random offsets in the strata, and exactly
//! 0 for `0 < |k1| < N` when every point sits at the centre of its stratum, as here (the random
//! toroidal shift of every use keeps the estimates unbiased). Against the edge's `|k1|^−2` that is the
//! difference between a floor of about `1 / (6 N²)` and `1 / (12 N²)` in the variance; on the fan of
//! edges at N = 1024 (offset 0.7) centring cut the double-wedge table's MSE from 3.6e-7 to 2.9e-7.
//! In 4D, holding `x` and `y` also keeps the start's `xy` projection, which a depth-of-field pixel seen through the
//! oracle's shear depends on most: a PMJ02 start keeps its (0,2)-net there.
//!
//! Measured (N = 1024, xu edge, oracle shear 5 % off; 4D tables of the widened hairline): moving the
//! held coordinates as well, even inside their strata, raised `P(k1, 0)` above the loss's grid to
//! 0.1–0.3; letting `x, y` move freely and stratifying them afterwards gave 1.3e-6 on that edge but
//! 4.8e-6 on the renderer's hairline pixel, where holding a PMJ02 `xy` gives 3.0e-7 (2.0e-6 on the
//! edge).

/// Makes coordinates `coords` of `set` (`[n, dims]`, in `[0, 1)`) N-stratified and centred: the point of
/// rank `r` (ties by index) goes to `(r + ½) / N`. A coordinate that already has one point per
/// stratum keeps each point in its stratum, at its centre.
pub fn stratify(set: &mut [f64], n: usize, dims: usize, coords: &[usize]) {
    let nf = n as f64;
    for &d in coords {
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| {
            set[a * dims + d]
                .total_cmp(&set[b * dims + d])
                .then(a.cmp(&b))
        });
        for (rank, &j) in order.iter().enumerate() {
            set[j * dims + d] = (rank as f64 + 0.5) / nf;
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
    use rand::Rng as _;

    #[test]
    fn stratify_gives_one_point_per_stratum_and_keeps_the_order() {
        let n = 257;
        let mut rng = crate::rng::stream(3, 0);
        let mut set: Vec<f64> = (0..2 * n).map(|_| rng.random::<f64>()).collect();
        let before = set.clone();
        stratify(&mut set, n, 2, &[0]);
        let mut strata: Vec<usize> = set
            .chunks_exact(2)
            .map(|p| (p[0] * n as f64) as usize)
            .collect();
        strata.sort_unstable();
        assert_eq!(strata, (0..n).collect::<Vec<_>>());
        assert!(set
            .chunks_exact(2)
            .all(|p| (p[0] * n as f64).fract() == 0.5));
        let again = set.clone();
        stratify(&mut set, n, 2, &[0]);
        assert_eq!(set, again, "a stratified, centred set is left as it is");
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
