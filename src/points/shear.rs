//! Shearing 4D sets so their `xu` and `yv` spectra align with a defocused pixel's (DESIGN §5).
//!
//! A defocused pixel's integrand varies along `t = x + s u`. A pattern whose first coordinate is
//! stratified can be moved so that `t` inherits that stratification. Two ways are offered:
//!
//! - [`ShearMode::Transported`] (the default) maps the pattern through the exact inverse CDF of `t`
//!   over the unit square (a trapezoid on `[0, 1 + |s|]`), then draws `u` from its conditional. The result
//!   is exactly uniform on the square, has no seam, and is stratified along the shear direction.
//!   DESIGN §5 measured it: sheared N-rooks reached slope −1.99 on a sheared edge.
//! - [`ShearMode::Wrap`] sets `x' = (x − s u) mod 1`. It keeps the structure only for integrands periodic
//!   in `x`; on a pixel footprint the wrap seam is a discontinuity of its own, and DESIGN §5 measured
//!   slope −1.06, no better than unsheared.

use super::{wrap, BELOW_ONE};

/// How a shear is applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShearMode {
    /// Seam-free: inverse-CDF transport along the sheared coordinate (default).
    #[default]
    Transported,
    /// Wrap-around: `x' = (x − s u) mod 1`.
    Wrap,
}

impl ShearMode {
    /// Parses `transported` or `wrap`.
    pub fn parse(text: &str) -> crate::error::Result<Self> {
        match text {
            "transported" | "seamfree" | "seam-free" => Ok(Self::Transported),
            "wrap" => Ok(Self::Wrap),
            _ => Err(crate::error::Error::Usage(format!(
                "unknown shear mode '{text}'; use 'transported' (seam-free, default) or 'wrap'"
            ))),
        }
    }
}

/// Below this magnitude a shear is the identity (the transport formulas divide by `s`).
pub(crate) const NO_SHEAR: f64 = 1e-12;

/// The largest shear magnitude accepted anywhere. `x = t − s u` cancels about `|s| · 1e-16` of `x`'s
/// precision, so at `1e6` a sheared coordinate is still good to 1e-10; at `1e17` it is noise.
pub const MAX_SHEAR: f64 = 1e6;

/// Shears one pair `(a, b)` of pattern coordinates in `[0,1)^2` into `(x, u)` such that `x + s u` carries
/// the stratification of `a`.
///
/// Transported, a negative shear is the transport of `|s|` reflected in `u`: `u = 1 − u⁺` with `u⁺`
/// the `u` of `|s|`, which makes `x + s u = x + |s| u⁺ − |s|`, stratified the same way. So `b` maps to
/// a `u` that decreases with it for `s < 0` and increases for `s > 0`, and as `s` crosses 0 the map
/// jumps from `u = 1 − b` to `u = b` (each side exactly uniform). For a negative shear the pattern's
/// `xu` spectrum `P(k1, k2)` (`k2` along `u`) thus enters the transport as `P(k1, −k2)`.
pub fn shear_pair(a: f64, b: f64, s: f64, mode: ShearMode) -> (f64, f64) {
    if s.abs() < NO_SHEAR {
        return (a, b);
    }
    match mode {
        ShearMode::Wrap => (wrap(a - s * b), b),
        ShearMode::Transported => {
            let (x, u) = transport(a, b, s.abs());
            if s < 0.0 {
                // x − |s| u' with u' = 1 − u is x + |s| u' − |s|: the same transport, reflected in u.
                (x, (1.0 - u).min(BELOW_ONE))
            } else {
                (x, u)
            }
        }
    }
}

/// Seam-free transport for `s > 0`: `t = x + s u` from its trapezoid inverse CDF at `a`, then `u` uniform
/// on its feasible interval at `b`, and `x = t − s u`.
fn transport(a: f64, b: f64, s: f64) -> (f64, f64) {
    // t is the sum of U[0,1] and U[0,s]; let p <= q be the two widths.
    let (p, q) = if s < 1.0 { (s, 1.0) } else { (1.0, s) };
    let ramp = p / (2.0 * q);
    let t = if a < ramp {
        (2.0 * p * q * a).sqrt()
    } else if a <= 1.0 - ramp {
        q * a + p / 2.0
    } else {
        p + q - (2.0 * p * q * (1.0 - a)).max(0.0).sqrt()
    };
    let lo = ((t - 1.0) / s).max(0.0);
    let hi = (t / s).min(1.0);
    let u = (lo + b * (hi - lo)).clamp(0.0, BELOW_ONE);
    let x = (t - s * u).clamp(0.0, BELOW_ONE);
    (x, u)
}

/// Shears every point of one 4D set (`[n, 4]` row-major) by `sx` in `xu` and `sy` in `yv`.
pub fn shear_set_4d(set: &mut [f64], sx: f64, sy: f64, mode: ShearMode) {
    for p in set.chunks_exact_mut(4) {
        let (x, u) = shear_pair(p[0], p[2], sx, mode);
        let (y, v) = shear_pair(p[1], p[3], sy, mode);
        p.copy_from_slice(&[x, y, u, v]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transported shear is measure-preserving: uniform random pattern points stay uniform, so
    /// each of 16 coarse cells holds a binomial count of mean M/16 (M = 400 000 points, standard
    /// deviation sqrt(M (1/16)(15/16)) = 153), here within 4.5 of them (by chance one of the 80 cells
    /// over 5 shears would exceed it with probability 80 · 2Φ(−4.5) = 5.4e-4; a map 5 % off uniform on a cell, 1250 points, fails).
    #[test]
    fn transport_is_uniform_and_stratifies_t() {
        use rand::Rng as _;
        let count = 400_000;
        let expect = count as f64 / 16.0;
        let sd = (expect * 15.0 / 16.0).sqrt();
        for (stream, &s) in [0.3, 0.5, 1.0, 2.5, -0.7].iter().enumerate() {
            let mut rng = crate::rng::stream(11, stream as u64);
            let mut counts = [0usize; 16];
            for _ in 0..count {
                let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
                let (x, u) = shear_pair(a, b, s, ShearMode::Transported);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&u));
                counts[(x * 4.0) as usize * 4 + (u * 4.0) as usize] += 1;
            }
            for c in counts {
                assert!(
                    (c as f64 - expect).abs() < 4.5 * sd,
                    "s={s}: {c} vs {expect} ± {sd}"
                );
            }
            // t is monotone in a: the first coordinate's stratification carries over.
            let m = 400;
            let ts: Vec<f64> = (0..m)
                .map(|i| {
                    let (x, u) = shear_pair(
                        (i as f64 + 0.5) / m as f64,
                        0.5 / m as f64,
                        s,
                        ShearMode::Transported,
                    );
                    x + s * u
                })
                .collect();
            assert!(ts.windows(2).all(|w| w[1] >= w[0]));
        }
    }

    #[test]
    fn zero_shear_is_identity() {
        assert_eq!(
            shear_pair(0.3, 0.7, 0.0, ShearMode::Transported),
            (0.3, 0.7)
        );
        assert_eq!(shear_pair(0.3, 0.7, 0.0, ShearMode::Wrap), (0.3, 0.7));
    }
}
