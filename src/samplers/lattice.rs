//! Randomly shifted rank-1 lattices (Korobov 1959; in rendering, Dammertz & Keller 2008): the `N`
//! points `(i / N, frac(g i / N))`, `i = 0 … N−1`, moved together by one uniform toroidal shift
//! (Cranley–Patterson rotation).
//!
//! The shift leaves `|F(k)|` unchanged, so every set has the same power spectrum: `P(k) = N` on the
//! dual lattice `{k : k1 + g k2 ≡ 0 (mod N)}` and exactly 0 everywhere else. With `g` coprime to `N`
//! both coordinates are permutations of the `N` strata (an N-rooks set), so the dual lattice meets the
//! axes only at multiples of `N`. The generator `g` is the classical choice: the one whose dual lattice
//! has the longest shortest nonzero vector (the largest dark disc around `k = 0`), the smallest such
//! `g` on ties.

use super::Sampler;
use crate::rng::Rng;
use rand::Rng as _;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// The largest `N` a lattice is made for: the generator search visits every `g ≤ N / 2`
/// (about 0.1 s at this size, once per `N`).
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

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The searched generator for `n` points (uncached): among `g ≤ n / 2` coprime to `n`, the one with
/// the longest shortest dual vector, the smallest on ties (`g` and `n − g` are mirror images). 1 for
/// `n ≤ 2`.
fn search_generator(n: usize) -> usize {
    let mut best = (0u128, 1usize);
    for g in 1..=n / 2 {
        if gcd(g, n) == 1 {
            let len = shortest_dual_squared(n, g);
            if len > best.0 {
                best = (len, g);
            }
        }
    }
    best.1
}

/// The lattice generator `g` for `n` points (see the module doc), searched once per `n` and kept.
pub fn generator(n: usize) -> usize {
    static FOUND: OnceLock<Mutex<HashMap<usize, usize>>> = OnceLock::new();
    let found = FOUND.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(&g) = found.lock().expect("generator cache").get(&n) {
        return g;
    }
    let g = search_generator(n);
    found.lock().expect("generator cache").insert(n, g);
    g
}

/// The randomly shifted rank-1 lattice of the module doc, in 2D.
#[derive(Clone, Debug)]
pub struct Lattice;

impl Sampler for Lattice {
    fn name(&self) -> String {
        "lattice".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        if n <= LATTICE_MAX_N {
            Ok(())
        } else {
            Err(LATTICE_MAX_N)
        }
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let g = generator(n) as u64;
        let shift: [f64; 2] = [rng.random(), rng.random()];
        let nf = n as f64;
        let mut out = Vec::with_capacity(2 * n);
        for i in 0..n as u64 {
            let row = (g * i) % n as u64;
            for (stratum, s) in [i, row].into_iter().zip(shift) {
                out.push(crate::points::wrap(stratum as f64 / nf + s));
            }
        }
        out
    }
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
            let g = generator(n);
            let best = (1..n)
                .filter(|&h| gcd(h, n) == 1)
                .map(|h| shortest_by_enumeration(n, h))
                .max()
                .unwrap();
            assert_eq!(shortest_by_enumeration(n, g), best, "n = {n}, g = {g}");
            assert!(gcd(g, n) == 1 && g <= n / 2);
        }
        // The Fibonacci lattice is optimal for a Fibonacci N: 89 points, generator 34 (or 55 = 89 − 34).
        assert_eq!(generator(89), 34);
    }
}
