//! Seeded random streams.
//!
//! Every realization (set, trial, pixel, ...) draws from its own stream, derived from the user's seed and
//! the realization's index only. Work can then be split over any number of threads and still give the
//! same bits for the same seed.

use rand::SeedableRng;

/// The generator used everywhere in anisospec (PCG-XSL-RR 128/64).
pub type Rng = rand_pcg::Pcg64;

/// SplitMix64 finaliser: a bijective mix of 64 bits.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The independent stream number `index` of the run seeded with `seed`.
pub fn stream(seed: u64, index: u64) -> Rng {
    Rng::seed_from_u64(mix64(
        mix64(seed) ^ mix64(index.wrapping_add(0x5851_F42D_4C95_7F2D)),
    ))
}

/// A sub-stream of a stream, for work that needs several independent generators per realization
/// (e.g. the point set and its toroidal shift).
pub fn substream(seed: u64, index: u64, part: u64) -> Rng {
    stream(mix64(seed ^ mix64(part.wrapping_add(1))), index)
}
