//! Progressive multi-jittered (0,2) sequences (Christensen, Kensler & Kilpatrick 2018), with the
//! valid-strata enumeration of Pharr (2019) done on bit masks.
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

/// Longest sequence generated (`2^20`).
pub const PMJ02_MAX_N: usize = 1 << 20;

/// Most free bits of a coordinate inside a sub-quadrant: `m - high <= 10` at the last level `m = 20`.
const MAX_LOW: u32 = PMJ02_MAX_N.trailing_zeros().div_ceil(2);

/// Words of a [`Strata`] mask at `MAX_LOW` free bits.
const STRATA_WORDS: usize = 1 << (MAX_LOW - 6);

/// Top `k` bits of a 32-bit fixed-point coordinate.
fn top(c: u64, k: u32) -> u64 {
    c >> (BITS - k)
}

/// Every byte with each bit doubled: bit `i` of `v` sets bits `2i` and `2i + 1` of `DOUBLED[v]`.
const DOUBLED: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut v = 0;
    while v < 256 {
        let mut bit = 0;
        while bit < 8 {
            if (v >> bit) & 1 == 1 {
                table[v] |= 0b11 << (2 * bit);
            }
            bit += 1;
        }
        v += 1;
    }
    table
};

/// The low 32 bits of `v` with every bit doubled: bit `i` goes to bits `2i` and `2i + 1`.
fn doubled(v: u64) -> u64 {
    (0..4).fold(0, |acc, byte| {
        acc | u64::from(DOUBLED[((v >> (8 * byte)) & 0xFF) as usize]) << (16 * byte)
    })
}

/// The valid strata of one coordinate inside a sub-quadrant, as a mask over its `2^low` strata
/// (bit `l` of word `l / 64`).
#[derive(Default)]
struct Strata {
    words: [u64; STRATA_WORDS],
    /// Words in use: `max(1, 2^low / 64)`.
    len: usize,
    /// The first bit of the sub-quadrant's window in the table of each depth (at `depth - 1`).
    windows: [usize; MAX_LOW as usize],
}

impl Strata {
    fn count(&self) -> usize {
        self.words[..self.len]
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// The index of the `rank`-th valid stratum (from 0, in increasing order); `rank < count()`.
    fn nth(&self, mut rank: usize) -> u64 {
        for (i, &word) in self.words[..self.len].iter().enumerate() {
            // The last word holds it if no other does: no need to count its strata.
            let ones = word.count_ones() as usize;
            if i + 1 == self.len || rank < ones {
                let mut w = word;
                for _ in 0..rank {
                    w &= w - 1;
                }
                assert!(w != 0, "pmj02: stratum rank beyond the valid strata");
                return 64 * i as u64 + u64::from(w.trailing_zeros());
            }
            rank -= ones;
        }
        unreachable!("a mask has at least one word")
    }
}

/// Which coordinate a table or a stratum search is about.
#[derive(Clone, Copy)]
enum Axis {
    X,
    Y,
}

/// Occupied elementary intervals at one level `m`, as seen from the sub-quadrants of the `2^high`
/// grid (`low = m - high` free bits per coordinate).
///
/// Inside a sub-quadrant, an interval shape with `b = high + depth` bits of one coordinate (the
/// major one) has `m - b < low` bits of the other, all fixed by the sub-quadrant: it constrains the
/// major coordinate's free bits only, through the `2^depth` cells of one row that the sub-quadrant
/// spans (its window). Those shapes, `depth = 1 ..= low` for x and for y, are the only ones a
/// placement checks, and the only ones kept: one bit table each, window after window, `2^m` cells.
///
/// The tables of the shallow depths are stored expanded so that every window is as wide as the
/// strata search's first word, `2^min(low, 6)` bits, each cell repeated: the search then reads one
/// word per depth and needs no doubling. A table of depth `d` has windows of `2^e` bits,
/// `e = max(d, min(low, 6))`, each cell taking `2^(e - d)` of them. One buffer serves every level.
#[derive(Default)]
struct Occupancy {
    m: u32,
    high: u32,
    /// `min(low, 6)`: the log2 of the width of an expanded window.
    expanded_log: u32,
    /// First word of each table, by axis and depth - 1.
    starts: [[usize; MAX_LOW as usize]; 2],
    bits: Vec<u64>,
}

impl Occupancy {
    /// Empties the tables for level `m` seen from the `2^high` grid, then inserts `points`.
    fn reset(&mut self, m: u32, high: u32, points: &[(u64, u64)]) {
        let low = m - high;
        self.m = m;
        self.high = high;
        self.expanded_log = low.min(6);
        let mut words = 0;
        for depth in 1..=low {
            // 2^(m - depth) windows of 2^e bits each.
            let size = (1usize << (m - depth + self.window_log(depth))).div_ceil(64);
            for axis in [Axis::X, Axis::Y] {
                self.starts[axis as usize][depth as usize - 1] = words;
                words += size;
            }
        }
        self.bits.clear();
        self.bits.resize(words, 0);
        // One table at a time, so that the shifts stay fixed over the points.
        for depth in 1..=low {
            let e = self.window_log(depth);
            let run = (1u64 << (1 << (e - depth))) - 1;
            for axis in [Axis::X, Axis::Y] {
                let start = 64 * self.starts[axis as usize][depth as usize - 1];
                for &(x, y) in points {
                    let (major, minor) = match axis {
                        Axis::X => (x, y),
                        Axis::Y => (y, x),
                    };
                    // The window of row `top(minor, low - depth)` and sub-quadrant
                    // `top(major, high)`, then the cell `top(major, high + depth)` inside it.
                    let bit = start
                        + ((top(minor, low - depth) << (high + e)) as usize)
                        + ((top(major, high + depth) << (e - depth)) as usize);
                    self.bits[bit / 64] |= run << (bit % 64);
                }
            }
        }
    }

    /// The log2 of the width of a window of the tables at `depth`.
    fn window_log(&self, depth: u32) -> u32 {
        depth.max(self.expanded_log)
    }

    /// The first bit of the window of sub-quadrant `q` of the major coordinate, in the table of
    /// `axis` at `depth`, with the minor coordinate at `minor`.
    fn window(&self, axis: Axis, depth: u32, q: u64, minor: u64) -> usize {
        let row = top(minor, self.low() - depth);
        let window = ((row << self.high) | q) as usize;
        64 * self.starts[axis as usize][depth as usize - 1] + (window << self.window_log(depth))
    }

    fn low(&self) -> u32 {
        self.m - self.high
    }

    /// Marks the cells of leaf stratum `leaf` of a sub-quadrant whose windows are `strata`'s.
    fn mark(&mut self, strata: &Strata, leaf: u64) {
        let low = self.low();
        for depth in 1..=low {
            let e = self.window_log(depth);
            let bit = strata.windows[depth as usize - 1]
                + ((leaf >> (low - depth)) << (e - depth)) as usize;
            // The cell's 2^(e - depth) <= 32 bits, inside one word.
            let run = (1u64 << (1 << (e - depth))) - 1;
            self.bits[bit / 64] |= run << (bit % 64);
        }
    }

    /// The strata of `2^-m` of coordinate `axis` inside sub-quadrant `q` (of the `2^high` grid) at
    /// which every prefix of length `high + 1 ..= m` lies in a free interval, with the other
    /// coordinate at `minor`. The expanded tables give the free prefixes of length up to
    /// `high + 6` at once; below, going down one bit at a time, the mask of valid prefixes is
    /// doubled (a prefix is valid only if its parent is) and cut by the free cells of the next
    /// shape: the pruned walk of Pharr (2019) on all prefixes of a depth at once.
    fn valid_strata(&self, axis: Axis, q: u64, minor: u64, strata: &mut Strata) {
        let mut taken = 0;
        for depth in 1..=self.low() {
            let bit = self.window(axis, depth, q, minor);
            strata.windows[depth as usize - 1] = bit;
            if depth <= self.expanded_log {
                taken |= self.bits[bit / 64] >> (bit % 64);
            }
        }
        let width = 1u32 << self.expanded_log;
        strata.words[0] = !taken & (u64::MAX >> (64 - width));
        strata.len = 1;
        for depth in 7..=self.low() {
            // Double the mask from the top word down, so that no word is overwritten before it is read.
            for i in (0..strata.len).rev() {
                let w = strata.words[i];
                strata.words[2 * i + 1] = doubled(w >> 32);
                strata.words[2 * i] = doubled(w);
            }
            strata.len *= 2;
            let word = strata.windows[depth as usize - 1] / 64;
            let taken = &self.bits[word..word + strata.len];
            for (w, &t) in strata.words[..strata.len].iter_mut().zip(taken) {
                *w &= !t;
            }
        }
    }
}

/// A sequence under construction: the occupancy tables, and the strata searches' masks kept from one
/// point to the next.
#[derive(Default)]
struct Builder {
    occupancy: Occupancy,
    valid_x: Strata,
    valid_y: Strata,
}

impl Builder {
    /// Places a point in sub-quadrant `(qx, qy)` of the `2^high` grid: random valid x and y strata of
    /// `2^m`, then uniform bits below.
    fn place(&mut self, qx: u64, qy: u64, rng: &mut Rng) -> (u64, u64) {
        let occ = &mut self.occupancy;
        let base_x = qx << (BITS - occ.high);
        let base_y = qy << (BITS - occ.high);
        let shift = BITS - occ.m;
        occ.valid_strata(Axis::X, qx, base_y, &mut self.valid_x);
        occ.valid_strata(Axis::Y, qy, base_x, &mut self.valid_y);
        let (count_x, count_y) = (self.valid_x.count(), self.valid_y.count());
        assert!(
            count_x > 0 && count_y > 0,
            "pmj02: no free stratum in a sub-quadrant (construction invariant broken)"
        );
        let leaf_x = self.valid_x.nth(rng.random_range(0..count_x));
        let x = base_x | (leaf_x << shift) | rng.random_range(0..1u64 << shift);
        let leaf_y = self.valid_y.nth(rng.random_range(0..count_y));
        let y = base_y | (leaf_y << shift) | rng.random_range(0..1u64 << shift);
        occ.mark(&self.valid_x, leaf_x);
        occ.mark(&self.valid_y, leaf_y);
        (x, y)
    }
}

/// The first `count` points of a pmj02 sequence as 32-bit fixed-point pairs.
fn sequence(count: usize, rng: &mut Rng) -> Vec<(u64, u64)> {
    assert!(count <= PMJ02_MAX_N, "pmj02: at most {PMJ02_MAX_N} points");
    let mut pts: Vec<(u64, u64)> = Vec::with_capacity(count.next_power_of_two());
    let full = 1u64 << BITS;
    pts.push((rng.random_range(0..full), rng.random_range(0..full)));
    let mut builder = Builder::default();
    let mut k = 0u32; // pts.len() == 4^k at the start of a round
    while pts.len() < count {
        let n = pts.len();
        let high = k + 1;
        let sub = |c: u64| top(c, high);
        // n -> 2n: diagonal sub-quadrants.
        builder.occupancy.reset(2 * k + 1, high, &pts);
        for i in 0..n {
            let (x, y) = pts[i];
            let p = builder.place(sub(x) ^ 1, sub(y) ^ 1, rng);
            pts.push(p);
        }
        if pts.len() >= count {
            break;
        }
        // 2n -> 3n: sub-quadrants beside the old points in x; 3n -> 4n: diagonal to those.
        builder.occupancy.reset(2 * k + 2, high, &pts);
        for i in 0..n {
            let (x, y) = pts[i];
            let p = builder.place(sub(x) ^ 1, sub(y), rng);
            pts.push(p);
        }
        for i in 0..n {
            let (x, y) = pts[2 * n + i];
            let p = builder.place(sub(x) ^ 1, sub(y) ^ 1, rng);
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

    /// The mask search finds exactly the strata that checking every candidate against every shape
    /// finds, in the same order, on random points at every level up to 14 (masks of one to sixteen
    /// words) and for every split of the bits. The reference marks each point's cell in every shape
    /// on its own.
    #[test]
    fn mask_search_finds_every_valid_stratum() {
        let mut rng = rng::substream(11, 0, 0);
        let mut occ = Occupancy::default();
        for m in 1..=14u32 {
            for trial in 0..20 {
                let count = (trial * (1usize << m)) / 20;
                let points: Vec<(u64, u64)> = (0..count)
                    .map(|_| (rng.random::<u32>() as u64, rng.random::<u32>() as u64))
                    .collect();
                // taken[a]: the grid of 2^a columns and 2^(m-a) rows.
                let cell = |a: u32, x: u64, y: u64| ((top(y, m - a) << a) | top(x, a)) as usize;
                let mut taken = vec![vec![false; 1 << m]; m as usize + 1];
                for &(x, y) in &points {
                    for a in 0..=m {
                        taken[a as usize][cell(a, x, y)] = true;
                    }
                }
                let free = |a: u32, x: u64, y: u64| !taken[a as usize][cell(a, x, y)];
                for high in m.saturating_sub(MAX_LOW)..=m {
                    occ.reset(m, high, &points);
                    let low = m - high;
                    let step = 1u64 << (BITS - m);
                    let q = rng.random_range(0..1u64 << high);
                    let base = if high == 0 { 0 } else { q << (BITS - high) };
                    let other = rng.random::<u32>() as u64;
                    let every: Vec<u64> = (0..1u64 << low).map(|l| base | (l * step)).collect();
                    let brute_x: Vec<u64> = every
                        .iter()
                        .copied()
                        .filter(|&x| (high + 1..=m).all(|a| free(a, x, other)))
                        .collect();
                    let brute_y: Vec<u64> = every
                        .iter()
                        .copied()
                        .filter(|&y| (0..low).all(|a| free(a, other, y)))
                        .collect();
                    for (axis, brute, name) in [(Axis::X, brute_x, "x"), (Axis::Y, brute_y, "y")] {
                        let mut strata = Strata::default();
                        occ.valid_strata(axis, q, other, &mut strata);
                        let found: Vec<u64> = (0..strata.count())
                            .map(|r| base | (strata.nth(r) * step))
                            .collect();
                        assert_eq!(
                            found, brute,
                            "{name}, m = {m}, high = {high}, {count} points"
                        );
                    }
                }
            }
        }
    }

    /// Marking a placed point's cells through its sub-quadrant's windows leaves the tables exactly as
    /// rebuilding them with the point does, at every level up to 14 and every split of the bits.
    #[test]
    fn marking_a_point_matches_rebuilding() {
        let mut rng = rng::substream(12, 0, 0);
        let (mut marked, mut rebuilt) = (Occupancy::default(), Occupancy::default());
        let mut strata = Strata::default();
        for m in 1..=14u32 {
            for high in m.saturating_sub(MAX_LOW)..=m {
                let low = m - high;
                let mut points: Vec<(u64, u64)> = (0..(1usize << m) / 3)
                    .map(|_| (rng.random::<u32>() as u64, rng.random::<u32>() as u64))
                    .collect();
                marked.reset(m, high, &points);
                let (x, y) = (rng.random::<u32>() as u64, rng.random::<u32>() as u64);
                let leaf = |c: u64| top(c, m) & ((1 << low) - 1);
                marked.valid_strata(Axis::X, top(x, high), y, &mut strata);
                marked.mark(&strata, leaf(x));
                marked.valid_strata(Axis::Y, top(y, high), x, &mut strata);
                marked.mark(&strata, leaf(y));
                points.push((x, y));
                rebuilt.reset(m, high, &points);
                assert!(marked.bits == rebuilt.bits, "m = {m}, high = {high}");
            }
        }
    }
}
