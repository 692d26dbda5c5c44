//! Progressive multi-jittered (0,2) sequences (Christensen, Kensler & Kilpatrick 2018), with the
//! valid-strata enumeration of Pharr (2019).
//!
//! The sequence grows from one random point by rounds that quadruple it. With `n = 4^k` points placed
//! and the unit square cut into a `2^(k+1)`-per-side grid of sub-quadrants, a round places
//! 1. for each old point `i`, a point in the sub-quadrant diagonally opposite `i`'s (`n -> 2n`);
//! 2. for each old point `i`, a point in the sub-quadrant beside `i`'s in x (`2n -> 3n`);
//! 3. for each point `2n + i` of step 2, a point in the sub-quadrant diagonally opposite it.
//!
//! Within its sub-quadrant a new point takes a random x stratum and a random y stratum among those that
//! leave every elementary interval of the next power of two empty. Inside a sub-quadrant the x and y
//! choices are independent (each interval shape constrains the low bits of one coordinate only), so
//! the valid choices are enumerated per coordinate. Every prefix of length `2^m` is then a
//! (0, m, 2)-net: one point in each `2^-a × 2^-(m-a)` elementary interval.

use super::Sampler;
use crate::rng::Rng;
use rand::Rng as _;

/// Fixed-point resolution of the coordinates: `x = bits / 2^32`.
const BITS: u32 = 32;

/// Longest sequence generated (`2^20`; the occupancy tables take `(m + 1) 2^m` bytes).
pub const PMJ02_MAX_N: usize = 1 << 20;

/// Top `k` bits of a 32-bit fixed-point coordinate.
fn top(c: u64, k: u32) -> u64 {
    c >> (BITS - k)
}

/// Occupied elementary intervals of all shapes `2^a × 2^(m-a)` at one level `m`.
struct Occupancy {
    m: u32,
    /// `cells[a]` is the grid with `2^a` columns and `2^(m-a)` rows.
    cells: Vec<Vec<bool>>,
}

impl Occupancy {
    fn new(m: u32, points: &[(u64, u64)]) -> Self {
        let mut occ = Self {
            m,
            cells: vec![vec![false; 1 << m]; m as usize + 1],
        };
        for &p in points {
            occ.insert(p);
        }
        occ
    }

    fn index(&self, a: u32, x: u64, y: u64) -> usize {
        ((top(y, self.m - a) << a) | top(x, a)) as usize
    }

    fn insert(&mut self, (x, y): (u64, u64)) {
        for a in 0..=self.m {
            let i = self.index(a, x, y);
            self.cells[a as usize][i] = true;
        }
    }

    fn free(&self, a: u32, x: u64, y: u64) -> bool {
        !self.cells[a as usize][self.index(a, x, y)]
    }

    /// The strata (multiples of `2^-m`) below `base`, whose top `high` bits are fixed, at which every
    /// prefix of length `high + 1 ..= m` passes `free(length, prefix)`, in increasing order. A shape
    /// looks at a prefix of the coordinate only, so a depth-first walk over the free bits, pruned at
    /// the first taken interval, finds them in about (valid strata × `low`) checks instead of `2^low`
    /// candidates × `low` shapes (Pharr 2019).
    fn valid_strata(&self, high: u32, base: u64, free: impl Fn(u32, u64) -> bool) -> Vec<u64> {
        let mut found = Vec::new();
        let mut stack = vec![(high, base)];
        while let Some((len, prefix)) = stack.pop() {
            if len == self.m {
                found.push(prefix);
                continue;
            }
            // Bit 1 first onto the stack, so bit 0's subtree comes out first: increasing order.
            for bit in [1u64, 0] {
                let child = prefix | (bit << (BITS - len - 1));
                if free(len + 1, child) {
                    stack.push((len + 1, child));
                }
            }
        }
        found
    }

    /// Places a point in sub-quadrant `(qx, qy)` of the `2^high` grid: random valid x and y strata of
    /// `2^m`, then uniform bits below.
    fn place(&mut self, high: u32, qx: u64, qy: u64, rng: &mut Rng) -> (u64, u64) {
        let m = self.m;
        let base_x = qx << (BITS - high);
        let base_y = qy << (BITS - high);
        let step = 1u64 << (BITS - m);
        // Shapes with more than `high` x bits have fewer than `low` y bits, all inside the fixed
        // sub-quadrant: they constrain the low x bits only (and symmetrically for y).
        let valid_x = self.valid_strata(high, base_x, |a, x| self.free(a, x, base_y));
        let valid_y = self.valid_strata(high, base_y, |len, y| self.free(m - len, base_x, y));
        assert!(
            !valid_x.is_empty() && !valid_y.is_empty(),
            "pmj02: no free stratum in a sub-quadrant (construction invariant broken)"
        );
        let x = valid_x[rng.random_range(0..valid_x.len())] | rng.random_range(0..step);
        let y = valid_y[rng.random_range(0..valid_y.len())] | rng.random_range(0..step);
        self.insert((x, y));
        (x, y)
    }
}

/// The first `count` points of a pmj02 sequence as 32-bit fixed-point pairs.
fn sequence(count: usize, rng: &mut Rng) -> Vec<(u64, u64)> {
    let mut pts: Vec<(u64, u64)> = Vec::with_capacity(count.next_power_of_two());
    let full = 1u64 << BITS;
    pts.push((rng.random_range(0..full), rng.random_range(0..full)));
    let mut k = 0u32; // pts.len() == 4^k at the start of a round
    while pts.len() < count {
        let n = pts.len();
        let high = k + 1;
        let sub = |c: u64| top(c, high);
        // n -> 2n: diagonal sub-quadrants.
        let mut occ = Occupancy::new(2 * k + 1, &pts);
        for i in 0..n {
            let (x, y) = pts[i];
            let p = occ.place(high, sub(x) ^ 1, sub(y) ^ 1, rng);
            pts.push(p);
        }
        if pts.len() >= count {
            break;
        }
        // 2n -> 3n: sub-quadrants beside the old points in x; 3n -> 4n: diagonal to those.
        let mut occ = Occupancy::new(2 * k + 2, &pts);
        for i in 0..n {
            let (x, y) = pts[i];
            let p = occ.place(high, sub(x) ^ 1, sub(y), rng);
            pts.push(p);
        }
        for i in 0..n {
            let (x, y) = pts[2 * n + i];
            let p = occ.place(high, sub(x) ^ 1, sub(y) ^ 1, rng);
            pts.push(p);
        }
        k += 1;
    }
    pts.truncate(count);
    pts
}

/// Progressive multi-jittered (0,2) sampling: the prefix of length `N` of a random pmj02 sequence.
/// Any `N` up to [`PMJ02_MAX_N`]; for `N = 2^m` every elementary interval of area `1/N` holds one
/// point. Coordinates have 32-bit resolution.
#[derive(Clone, Debug)]
pub struct Pmj02;

impl Sampler for Pmj02 {
    fn name(&self) -> String {
        "pmj02".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        if n <= PMJ02_MAX_N {
            Ok(())
        } else {
            Err(PMJ02_MAX_N)
        }
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let scale = 1.0 / (1u64 << BITS) as f64;
        sequence(n, rng)
            .into_iter()
            .flat_map(|(x, y)| [x as f64 * scale, y as f64 * scale])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng;

    /// The depth-first walk finds exactly the strata that checking every candidate against every
    /// shape finds, in the same order, on occupancy tables of random points at every level and for
    /// every split of the bits.
    #[test]
    fn walk_finds_every_valid_stratum() {
        let mut rng = rng::substream(11, 0, 0);
        for m in 1..=10u32 {
            for trial in 0..20 {
                let count = (trial * (1usize << m)) / 20;
                let points: Vec<(u64, u64)> = (0..count)
                    .map(|_| (rng.random::<u32>() as u64, rng.random::<u32>() as u64))
                    .collect();
                let occ = Occupancy::new(m, &points);
                for high in 0..=m {
                    let low = m - high;
                    let step = 1u64 << (BITS - m);
                    let q = rng.random_range(0..1u64 << high);
                    let base = if high == 0 { 0 } else { q << (BITS - high) };
                    let other = rng.random::<u32>() as u64;
                    let every: Vec<u64> = (0..1u64 << low).map(|l| base | (l * step)).collect();
                    let brute_x: Vec<u64> = every
                        .iter()
                        .copied()
                        .filter(|&x| (high + 1..=m).all(|a| occ.free(a, x, other)))
                        .collect();
                    let brute_y: Vec<u64> = every
                        .iter()
                        .copied()
                        .filter(|&y| (0..low).all(|a| occ.free(a, other, y)))
                        .collect();
                    assert_eq!(
                        occ.valid_strata(high, base, |a, x| occ.free(a, x, other)),
                        brute_x,
                        "x, m = {m}, high = {high}, {count} points"
                    );
                    assert_eq!(
                        occ.valid_strata(high, base, |len, y| occ.free(m - len, other, y)),
                        brute_y,
                        "y, m = {m}, high = {high}, {count} points"
                    );
                }
            }
        }
    }
}
