//! Randomly shifted rank-1 lattices (Korobov 1959; in rendering, Dammertz & Keller 2008): the `N`
//! points `frac(i z / N)`, `i = 0 … N−1`, for a generating vector `z` with `z_0 = 1`, moved together by
//! one uniform toroidal shift (Cranley–Patterson rotation).
//!
//! The shift leaves `|F(k)|` unchanged, so every set has the same power spectrum: `P(k) = N` on the
//! dual lattice `{k : k·z ≡ 0 (mod N)}` and exactly 0 everywhere else. With every `z_d` coprime to `N`
//! each coordinate is a permutation of the `N` strata (an N-rooks set), so the dual lattice meets the
//! axes only at multiples of `N`. The generators are the classical choices (the smallest on ties):
//! - 2D, `z = (1, g)`: the `g` whose dual lattice has the longest shortest nonzero vector (the largest
//!   dark disc around `k = 0`);
//! - 4D, Korobov's `z = (1, a, a², a³)` in `(x, y, u, v)`: the `a` whose six 2D projections have the
//!   longest shortest dual vector at their worst (each projection `(z_i, z_j)` is the 2D lattice
//!   `(1, z_j / z_i mod N)`), then the largest sum of their squares. For N = 2, 3, 4, 6, 8, 12 and 24
//!   every `a` has `a² ≡ 1 (mod N)`, so `u` repeats `x` and `v` repeats `y`.
//!
//! [`GivenLattice`] (sampler `lattice:Z1:Z2` or `lattice:Z1:Z2:Z3:Z4`) takes a generating vector
//! from the user instead.

use super::Sampler;
use crate::error::{Error, Result};
use crate::rng::Rng;
use rand::Rng as _;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The largest `N` a lattice is made for: the generator search visits every candidate `≤ N / 2`
/// (at this size about 0.1 s in 2D and 0.4 s in 4D, once per `N`).
pub const LATTICE_MAX_N: usize = 1 << 20;

/// The squared length of the shortest nonzero vector of the dual lattice `{k : k1 + g k2 ≡ 0 (mod n)}`,
/// by Lagrange–Gauss reduction of its basis `(n, 0)`, `(−g, 1)`. Needs `1 ≤ g < n`.
pub fn shortest_dual_squared(n: usize, g: usize) -> u128 {
    let norm = |v: (i128, i128)| (v.0 * v.0 + v.1 * v.1) as u128;
    // `b` is always the shorter vector.
    let (mut a, mut b) = ((n as i128, 0i128), (-(g as i128), 1i128));
    if norm(a) < norm(b) {
        std::mem::swap(&mut a, &mut b);
    }
    loop {
        let nb = norm(b) as i128;
        let dot = a.0 * b.0 + a.1 * b.1;
        // The integer nearest to dot / nb.
        let mu = (2 * dot + nb).div_euclid(2 * nb);
        a = (a.0 - mu * b.0, a.1 - mu * b.1);
        if norm(a) >= norm(b) {
            return norm(b);
        }
        std::mem::swap(&mut a, &mut b);
    }
}

/// The greatest common divisor of `a` and `b`.
pub(crate) fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The inverse of `a` modulo `n` (`a` coprime to `n`, `n ≥ 2`), by the extended Euclidean algorithm.
fn inverse_mod(a: usize, n: usize) -> usize {
    let (mut r0, mut r1) = (n as i128, a as i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    while r1 != 0 {
        let q = r0 / r1;
        (r0, r1) = (r1, r0 - q * r1);
        (t0, t1) = (t1, t0 - q * t1);
    }
    t0.rem_euclid(n as i128) as usize
}

/// Korobov's vector `(1, a, a², a³) mod n`.
fn korobov(n: usize, a: usize) -> [usize; 4] {
    let (n, a) = (n as u128, a as u128);
    [1, a % n, a * a % n, a * a % n * a % n].map(|v| v as usize)
}

/// The squared shortest dual vectors of the six 2D projections of the 4D lattice `z` (every entry
/// coprime to `n`, `n ≥ 2`): the worst of them, then their sum, which breaks ties among equally bad
/// worst projections (at small `n`, where every `a` ties with the diagonal `a = 1`).
fn projection_score(n: usize, z: &[usize; 4]) -> (u128, u128) {
    let (mut worst, mut sum) = (u128::MAX, 0u128);
    for i in 0..3 {
        let inv = inverse_mod(z[i], n) as u128;
        for &zj in &z[i + 1..] {
            let g = (zj as u128 * inv % n as u128) as usize;
            let len = shortest_dual_squared(n, g);
            worst = worst.min(len);
            sum += len;
        }
    }
    (worst, sum)
}

/// Among `c ≤ n / 2` coprime to `n`, the one with the largest `score(c)`, the smallest on ties (`c` and
/// `n − c` give mirror images); 1 when there is no candidate (`n = 1`).
fn best_coprime<S: Ord>(n: usize, score: impl Fn(usize) -> S) -> usize {
    let mut best: Option<(S, usize)> = None;
    for c in (1..=n / 2).filter(|&c| gcd(c, n) == 1) {
        let s = score(c);
        if best.as_ref().is_none_or(|(b, _)| s > *b) {
            best = Some((s, c));
        }
    }
    best.map_or(1, |(_, c)| c)
}

/// The generating vector for `n` points in `dims` (2 or 4) dimensions (see the module doc), searched
/// once per `(n, dims)` and kept; threads that ask for it meanwhile wait for that one search.
pub fn generating_vector(n: usize, dims: usize) -> Vec<usize> {
    type Found = Mutex<HashMap<(usize, usize), Arc<OnceLock<Vec<usize>>>>>;
    static FOUND: OnceLock<Found> = OnceLock::new();
    let slot = FOUND
        .get_or_init(|| Mutex::new(HashMap::new()))
        .lock()
        .expect("generator cache")
        .entry((n, dims))
        .or_default()
        .clone();
    slot.get_or_init(|| {
        if dims == 2 {
            vec![1, best_coprime(n, |g| shortest_dual_squared(n, g))]
        } else {
            let a = best_coprime(n, |a| projection_score(n, &korobov(n, a)));
            korobov(n, a).to_vec()
        }
    })
    .clone()
}

/// The randomly shifted rank-1 lattice of the module doc.
#[derive(Clone, Debug)]
pub struct Lattice {
    /// 2 or 4.
    pub dims: usize,
}

impl Sampler for Lattice {
    fn name(&self) -> String {
        "lattice".into()
    }
    fn dims(&self) -> usize {
        self.dims
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_lattice_n(n)
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let z: Vec<u64> = generating_vector(n, self.dims)
            .into_iter()
            .map(|c| c as u64)
            .collect();
        shifted_lattice(&z, n, rng)
    }
}

/// A randomly shifted rank-1 lattice with a generating vector the user gives (sampler
/// `lattice:Z1:Z2` or `lattice:Z1:Z2:Z3:Z4`), e.g. a published one: the points
/// `frac(i z / N + shift)`, each `z_d` taken mod N. Every entry must be coprime to N, which keeps
/// each coordinate N-stratified: an entry sharing the factor `d` with N gives only N / d distinct
/// values in its coordinate (0 gives one).
#[derive(Clone, Debug)]
pub struct GivenLattice {
    z: Vec<u64>,
}

impl GivenLattice {
    /// Parses the generating vector `spec` (the part after `lattice:`, entries separated by colons, as
    /// `converge --sampler` splits its list at commas) for `dims` dimensions; a usage error names what
    /// is wrong and the form to use.
    pub fn parse(spec: &str, dims: usize) -> Result<Self> {
        let form = "write the generating vector's entries separated by colons, e.g. lattice:1:34 (2D) or lattice:1:163:271:141 (4D)";
        let z = spec
            .split(':')
            .map(|t| {
                t.trim().parse::<u64>().map_err(|_| {
                    let what = if t.trim().parse::<u128>().is_ok() {
                        format!("is above the largest entry, {}", u64::MAX)
                    } else {
                        "is not a whole number >= 0".to_string()
                    };
                    Error::Usage(format!("lattice:{spec}: '{t}' {what}; {form}"))
                })
            })
            .collect::<Result<Vec<u64>>>()?;
        if z.len() != dims {
            return Err(Error::Usage(format!(
                "lattice:{spec} has {} entries but the sets are {dims}D; give {dims} ({form})",
                z.len()
            )));
        }
        Ok(Self { z })
    }
}

impl Sampler for GivenLattice {
    fn name(&self) -> String {
        let z: Vec<String> = self.z.iter().map(u64::to_string).collect();
        format!("lattice:{}", z.join(":"))
    }
    fn dims(&self) -> usize {
        self.z.len()
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_lattice_n(n)
    }
    fn check_parameters(&self, n: usize) -> Result<()> {
        let residue = |zd: u64| (zd % n as u64) as usize;
        let Some((d, &zd)) = self
            .z
            .iter()
            .enumerate()
            .find(|&(_, &zd)| gcd(residue(zd), n) != 1)
        else {
            return Ok(());
        };
        let (r, factor) = (residue(zd), gcd(residue(zd), n));
        // The residue nearest r that is coprime to n and that no other entry has, nor its negative
        // (equal residues put two axes on one diagonal, opposite ones on an anti-diagonal), the
        // smaller on ties; else the nearest coprime one (1 always is). Suggested as the entry
        // nearest zd with that residue that fits in a u64.
        let taken: Vec<usize> = self
            .z
            .iter()
            .enumerate()
            .filter(|&(e, _)| e != d)
            .flat_map(|(_, &z)| [residue(z), (n - residue(z)) % n])
            .collect();
        let nearest_coprime = |free: &dyn Fn(usize) -> bool| {
            (1..n)
                .flat_map(|step| [r.checked_sub(step), Some(r + step)])
                .flatten()
                .find(|&c| (1..n).contains(&c) && gcd(c, n) == 1 && free(c))
        };
        let coprime = nearest_coprime(&|c| !taken.contains(&c))
            .or_else(|| nearest_coprime(&|_| true))
            .unwrap_or(1);
        let base = zd - r as u64;
        let suggestion = base
            .checked_add(coprime as u64)
            .unwrap_or_else(|| base - (n - coprime) as u64);
        let axis = ["x", "y", "u", "v"][d];
        let values = match n / factor {
            1 => "a single value".to_string(),
            v => format!("only {v} distinct values"),
        };
        Err(Error::Usage(format!(
            "{}: the entry {zd} for {axis} shares the factor {factor} with N = {n}, so {axis} takes {values}; give an entry coprime to {n} instead, e.g. {suggestion}",
            self.name()
        )))
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        shifted_lattice(&self.z, n, rng)
    }
}

/// Any `n` up to [`LATTICE_MAX_N`], else that limit as the nearest valid `n`.
fn check_lattice_n(n: usize) -> std::result::Result<(), usize> {
    if n <= LATTICE_MAX_N {
        Ok(())
    } else {
        Err(LATTICE_MAX_N)
    }
}

/// The `n` points `frac(i z / n + shift)` of the rank-1 lattice with generating vector `z` (one entry
/// per dimension), for one uniform random `shift` drawn from `rng`; `[n, z.len()]` row-major.
fn shifted_lattice(z: &[u64], n: usize, rng: &mut Rng) -> Vec<f64> {
    let shift: Vec<f64> = z.iter().map(|_| rng.random()).collect();
    let (nf, n64) = (n as f64, n as u64);
    let mut out = Vec::with_capacity(z.len() * n);
    for i in 0..n64 {
        for (&zd, s) in z.iter().zip(&shift) {
            // (zd mod n) · i < 2^40 for n <= 2^20: no overflow.
            let stratum = zd % n64 * i % n64;
            out.push(crate::points::wrap(stratum as f64 / nf + s));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shortest dual vector by enumeration: every `k2` in `[−n, n]` with the two `k1` nearest 0.
    fn shortest_by_enumeration(n: usize, g: usize) -> u128 {
        let n = n as i128;
        (-n..=n)
            .flat_map(|k2| {
                let k1 = (-(g as i128) * k2).rem_euclid(n);
                [(k1, k2), (k1 - n, k2)]
            })
            .filter(|&v| v != (0, 0))
            .map(|(a, b)| (a * a + b * b) as u128)
            .min()
            .unwrap()
    }

    /// The built-in generating vectors (2D, Korobov 4D, Fibonacci) pass the coprimality check that
    /// `lattice:Z` must; an entry sharing a factor with N, 0 included, is refused naming it.
    #[test]
    fn built_in_vectors_are_coprime_and_degenerate_ones_refused() {
        for n in (1..=300).chain([1000, 1024, 4096]) {
            for dims in [2, 4] {
                let z: Vec<u64> = generating_vector(n, dims)
                    .iter()
                    .map(|&c| c as u64)
                    .collect();
                assert!(
                    GivenLattice { z }.check_parameters(n).is_ok(),
                    "n = {n}, {dims}D"
                );
            }
        }
        assert!(GivenLattice { z: vec![1, 34] }.check_parameters(89).is_ok());
        let near_max = format!(
            "give an entry coprime to 15 instead, e.g. {}",
            u64::MAX - 13
        );
        for (z, n, says) in [
            (vec![0, 0], 8, "the entry 0 for x shares the factor 8 with N = 8, so x takes a single value"),
            (vec![1, 4], 8, "the entry 4 for y shares the factor 4 with N = 8, so y takes only 2 distinct values; give an entry coprime to 8 instead, e.g. 3"),
            (vec![1, 163, 271, 141], 9, "the entry 141 for v shares the factor 3 with N = 9, so v takes only 3 distinct values; give an entry coprime to 9 instead, e.g. 140"),
            // 1 and 3 are nearer but taken by x and u: y = 1 would put x and y on one diagonal.
            (vec![1, 2, 3, 4], 16, "the entry 2 for y shares the factor 2 with N = 16, so y takes only 8 distinct values; give an entry coprime to 16 instead, e.g. 5"),
            // 1 is nearer but −15 mod 16: y = 1 would put the points on x + y ≡ 0.
            (vec![15, 2], 16, "give an entry coprime to 16 instead, e.g. 3"),
            // The entry nearest u64::MAX with residue 2 lies below it (u64::MAX is 0 mod 15).
            (vec![1, u64::MAX], 15, near_max.as_str()),
        ] {
            let e = GivenLattice { z }.check_parameters(n).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(says), "{e}");
        }
    }

    #[test]
    fn reduction_finds_the_shortest_dual_vector() {
        for n in 2..160 {
            for g in (1..n).filter(|&g| gcd(g, n) == 1) {
                assert_eq!(
                    shortest_dual_squared(n, g),
                    shortest_by_enumeration(n, g),
                    "n = {n}, g = {g}"
                );
            }
        }
    }

    #[test]
    fn generator_is_the_best_over_every_g() {
        for n in [3usize, 16, 64, 89, 100, 144, 256, 1000] {
            let g = generating_vector(n, 2)[1];
            let best = (1..n)
                .filter(|&h| gcd(h, n) == 1)
                .map(|h| shortest_by_enumeration(n, h))
                .max()
                .unwrap();
            assert_eq!(shortest_by_enumeration(n, g), best, "n = {n}, g = {g}");
            assert!(gcd(g, n) == 1 && g <= n / 2);
        }
        // The Fibonacci lattice is optimal for a Fibonacci N: 89 points, generator 34 (or 55 = 89 − 34).
        assert_eq!(generating_vector(89, 2), [1, 34]);
    }

    #[test]
    fn korobov_vector_is_the_best_over_every_a() {
        for n in [8usize, 12, 16, 24, 64, 81, 100, 256] {
            let z = generating_vector(n, 4);
            // (worst, sum) of the six projections' shortest dual vectors by enumeration.
            let score = |z: &[usize; 4]| {
                let lens: Vec<u128> = (0..4)
                    .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                    .map(|(i, j)| {
                        let g = z[j] * inverse_mod(z[i], n) % n;
                        assert_eq!(g * z[i] % n, z[j] % n, "inverse of {} mod {n}", z[i]);
                        shortest_by_enumeration(n, g)
                    })
                    .collect();
                (*lens.iter().min().unwrap(), lens.iter().sum::<u128>())
            };
            let best = (1..n)
                .filter(|&a| gcd(a, n) == 1)
                .map(|a| score(&korobov(n, a)))
                .max()
                .unwrap();
            let z: [usize; 4] = z.try_into().unwrap();
            assert_eq!(score(&z), best, "n = {n}, z = {z:?}");
            assert!(z.iter().all(|&c| gcd(c, n) == 1) && z[0] == 1);
            // Not the diagonal, whose x, y, u and v would be one coordinate.
            assert_ne!(z, [1, 1, 1, 1], "n = {n}");
        }
    }
}
