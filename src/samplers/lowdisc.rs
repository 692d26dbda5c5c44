//! Randomized low-discrepancy sequences: scrambled Halton and Owen-scrambled Sobol.

use super::Sampler;
use crate::rng::Rng;
use rand::Rng as _;

/// Bases of the Halton sequence, one per dimension `x, y, u, v`.
const HALTON_BASES: [u64; 4] = [2, 3, 5, 7];

/// The Halton sequence in bases 2, 3 (2D) or 2, 3, 5, 7 (4D), scrambled by an independent random
/// permutation of the digits `0..b` at every digit position of every dimension (random digit
/// scrambling, which keeps the sequence's stratification). Point `j` is the scrambled radical inverse
/// of `j`, `j = 0..N`; any `N`. The digits are scrambled down to `2^-53`, the precision of `f64`.
#[derive(Clone, Debug)]
pub struct Halton {
    /// 2 or 4.
    pub dims: usize,
}

/// Number of base-`b` digits that resolve `f64`: `b^digits >= 2^53`.
fn digits_for(b: u64) -> usize {
    (53.0 / (b as f64).log2()).ceil() as usize
}

impl Sampler for Halton {
    fn name(&self) -> String {
        "halton".into()
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
        for (dim, &b) in HALTON_BASES.iter().take(d).enumerate() {
            let perms: Vec<Vec<usize>> = (0..digits_for(b))
                .map(|_| super::grid::permutation(b as usize, rng))
                .collect();
            let inv_b = 1.0 / b as f64;
            for j in 0..n {
                let mut idx = j as u64;
                let mut scale = inv_b;
                let mut value = 0.0;
                for perm in &perms {
                    value += perm[(idx % b) as usize] as f64 * scale;
                    idx /= b;
                    scale *= inv_b;
                }
                out[j * d + dim] = value.min(crate::points::BELOW_ONE);
            }
        }
        out
    }
}

/// Longest prefix `sobol_burley` provides.
pub const SOBOL_MAX_N: usize = 1 << 16;

/// Owen-scrambled Sobol points (Burley 2020, via the `sobol_burley` crate): dimensions 0–1 (2D) or
/// 0–3 (4D) of one randomly seeded sequence (the seed also shuffles the sequence order, keeping every
/// prefix of length `2^m` a (0, m, 2)-net in the first two dimensions). Any `N` up to `2^16`;
/// coordinates have `f32` (24-bit) resolution.
#[derive(Clone, Debug)]
pub struct Sobol {
    /// 2 or 4.
    pub dims: usize,
}

impl Sampler for Sobol {
    fn name(&self) -> String {
        "sobol".into()
    }
    fn dims(&self) -> usize {
        self.dims
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        if n <= SOBOL_MAX_N {
            Ok(())
        } else {
            Err(SOBOL_MAX_N)
        }
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let seed: u32 = rng.random();
        let mut out = Vec::with_capacity(n * self.dims);
        for j in 0..n as u32 {
            let p = sobol_burley::sample_4d(j, 0, seed);
            out.extend(p[..self.dims].iter().map(|&c| f64::from(c)));
        }
        out
    }
}
