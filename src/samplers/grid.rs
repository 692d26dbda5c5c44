//! Stratified constructions on regular grids: uniform random, jittered, N-rooks (Latin hypercube),
//! multi-jittered (Chiu, Shirley & Wang 1994) and correlated multi-jittered (Kensler 2013), in 2D and
//! (random, jittered, N-rooks) 4D.

use super::{nearest_valid, Sampler};
use crate::rng::Rng;
use rand::seq::SliceRandom;
use rand::Rng as _;

/// A uniform point in stratum `k` of `count` equal strata of `[0,1)`: `(k + ξ) / count`, nudged down
/// if rounding pushed it into stratum `k + 1`, so that `floor(x * count) == k` holds in `f64`.
pub(crate) fn in_stratum(k: usize, count: usize, rng: &mut Rng) -> f64 {
    let c = count as f64;
    let mut x = (k as f64 + rng.random::<f64>()) / c;
    while x >= 1.0 || (x * c).floor() > k as f64 {
        x = x.next_down();
    }
    x
}

/// A random permutation of `0..n`.
pub(crate) fn permutation(n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut p: Vec<usize> = (0..n).collect();
    p.shuffle(rng);
    p
}

/// Integer `r` with `r^k <= n < (r+1)^k`.
pub(crate) fn int_root(n: usize, k: u32) -> usize {
    let mut r = (n as f64).powf(1.0 / k as f64).round() as usize;
    while r > 0 && r.pow(k) > n {
        r -= 1;
    }
    while (r + 1).pow(k) <= n {
        r += 1;
    }
    r
}

/// Nearest perfect `k`-th power `m^k` (m >= 1) to `n`; ties go to the smaller one.
fn nearest_power(n: usize, k: u32) -> usize {
    let r = int_root(n, k).max(1);
    let (lo, hi) = (r.pow(k), (r + 1).pow(k));
    if n <= lo || n - lo <= hi - n {
        lo
    } else {
        hi
    }
}

/// Uniform random points in `[0,1)^dims` (white noise: `E[P(k)] = 1` for `k != 0`).
#[derive(Clone, Debug)]
pub struct Random {
    /// 2 or 4.
    pub dims: usize,
}

impl Sampler for Random {
    fn name(&self) -> String {
        "random".into()
    }
    fn dims(&self) -> usize {
        self.dims
    }
    fn check_n(&self, _n: usize) -> std::result::Result<(), usize> {
        Ok(())
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        (0..n * self.dims).map(|_| rng.random::<f64>()).collect()
    }
}

/// Jittered (stratified) sampling: one uniform point in each cell of an `m^dims` grid, `N = m^dims`.
#[derive(Clone, Debug)]
pub struct Jittered {
    /// 2 (N = m²) or 4 (N = m⁴).
    pub dims: usize,
}

impl Sampler for Jittered {
    fn name(&self) -> String {
        "jittered".into()
    }
    fn dims(&self) -> usize {
        self.dims
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        let near = nearest_power(n, self.dims as u32);
        if near == n {
            Ok(())
        } else {
            Err(near)
        }
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let d = self.dims;
        let m = int_root(n, d as u32);
        let mut out = Vec::with_capacity(n * d);
        for cell in 0..n {
            let mut c = cell;
            for _ in 0..d {
                out.push(in_stratum(c % m, m, rng));
                c /= m;
            }
        }
        out
    }
}

/// N-rooks (Latin hypercube): every 1D projection has one point in each of the `N` strata; the
/// dimensions are joined by independent random permutations. Any `N`.
#[derive(Clone, Debug)]
pub struct NRooks {
    /// 2 or 4.
    pub dims: usize,
}

impl Sampler for NRooks {
    fn name(&self) -> String {
        "nrooks".into()
    }
    fn dims(&self) -> usize {
        self.dims
    }
    fn check_n(&self, _n: usize) -> std::result::Result<(), usize> {
        Ok(())
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let d = self.dims;
        let mut out = vec![0.0; n * d];
        for dim in 0..d {
            let perm = permutation(n, rng);
            for (j, &k) in perm.iter().enumerate() {
                out[j * d + dim] = in_stratum(k, n, rng);
            }
        }
        out
    }
}

/// The `m × n` coarse grid of a multi-jittered set of `N` points: `m = floor(sqrt N)` columns (width
/// `1/m`) and `n = N / m` rows (height `1/n`). `None` unless `m` divides `N`.
pub fn mj_shape(count: usize) -> Option<(usize, usize)> {
    let m = int_root(count, 2);
    (m > 0 && count.is_multiple_of(m)).then_some((m, count / m))
}

fn check_mj(n: usize) -> std::result::Result<(), usize> {
    if mj_shape(n).is_some() {
        Ok(())
    } else {
        Err(nearest_valid(n, |c| mj_shape(c).is_some()))
    }
}

/// Shared body of MJ and CMJ: point `(i, j)` (column `i < m`, row `j < n`) sits in coarse cell
/// `(i, j)`, its x in fine stratum `i n + sx(i, j)` of `N`, its y in fine stratum `j m + sy(i, j)`.
fn multi_jitter(
    count: usize,
    rng: &mut Rng,
    x_perm: &[Vec<usize>],
    y_perm: &[Vec<usize>],
    m: usize,
    n: usize,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * count);
    for j in 0..n {
        for i in 0..m {
            let sx = x_perm[i % x_perm.len()][j];
            let sy = y_perm[j % y_perm.len()][i];
            out.push(in_stratum(i * n + sx, count, rng));
            out.push(in_stratum(j * m + sy, count, rng));
        }
    }
    out
}

/// Multi-jittered sampling (Chiu, Shirley & Wang 1994): one point per cell of the `m × n` coarse grid
/// of [`mj_shape`] and one per each of the `N` strata of x and of y (N-rooks). The fine offsets are
/// shuffled independently within every column (x) and every row (y).
#[derive(Clone, Debug)]
pub struct MultiJittered;

impl Sampler for MultiJittered {
    fn name(&self) -> String {
        "mj".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_mj(n)
    }
    fn generate(&self, count: usize, rng: &mut Rng) -> Vec<f64> {
        let (m, n) = mj_shape(count).expect("check_n passed");
        let xp: Vec<Vec<usize>> = (0..m).map(|_| permutation(n, rng)).collect();
        let yp: Vec<Vec<usize>> = (0..n).map(|_| permutation(m, rng)).collect();
        multi_jitter(count, rng, &xp, &yp, m, n)
    }
}

/// Correlated multi-jittered sampling (Kensler 2013): like [`MultiJittered`], but one permutation of
/// the fine x offsets is shared by every column and one of the fine y offsets by every row, which
/// keeps the points of neighbouring cells apart.
#[derive(Clone, Debug)]
pub struct CorrelatedMultiJittered;

impl Sampler for CorrelatedMultiJittered {
    fn name(&self) -> String {
        "cmj".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_mj(n)
    }
    fn generate(&self, count: usize, rng: &mut Rng) -> Vec<f64> {
        let (m, n) = mj_shape(count).expect("check_n passed");
        let xp = vec![permutation(n, rng)];
        let yp = vec![permutation(m, rng)];
        multi_jitter(count, rng, &xp, &yp, m, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_and_powers() {
        assert_eq!(int_root(49, 2), 7);
        assert_eq!(int_root(48, 2), 6);
        assert_eq!(int_root(81, 4), 3);
        assert_eq!(int_root(80, 4), 2);
        assert_eq!(nearest_power(50, 2), 49);
        assert_eq!(nearest_power(100, 4), 81);
        assert_eq!(nearest_power(1, 4), 1);
    }

    #[test]
    fn mj_shapes() {
        assert_eq!(mj_shape(16), Some((4, 4)));
        assert_eq!(mj_shape(20), Some((4, 5)));
        assert_eq!(mj_shape(24), Some((4, 6)));
        assert_eq!(mj_shape(17), None);
    }
}
