//! Point sets on the unit torus: storage `[sets, N, D]`, projections, toroidal shift and shear
//! (DESIGN §2, §5).

pub mod io;
pub mod shear;

use crate::error::{Error, Result};

/// Names of the four dimensions of a 4D set: pixel position `x, y`, lens position `u, v`.
pub const DIM_NAMES: [char; 4] = ['x', 'y', 'u', 'v'];

/// The most coordinates (`N × sets × D`) one array of points may hold: 2^28 `f64`, 2 GiB. Sizes are
/// checked against it before a set is drawn, so a mistyped `-n` is a message rather than an abort.
pub const MAX_COORDINATES: usize = 1 << 28;

/// `sets × n × dims`, the number of coordinates of `sets` sets of `n` points in `dims` dimensions, if it
/// is at most [`MAX_COORDINATES`]; else a message naming the size, the limit and the fix.
pub fn coordinate_count(sets: usize, n: usize, dims: usize) -> std::result::Result<usize, String> {
    let total = sets.checked_mul(n).and_then(|c| c.checked_mul(dims));
    match total {
        Some(c) if c <= MAX_COORDINATES => Ok(c),
        _ => {
            let approx = sets as f64 * n as f64 * dims as f64;
            let short = |x: f64| {
                if x < 1e6 {
                    format!("{x:.1}")
                } else {
                    format!("{x:.2e}")
                }
            };
            let count = total.map_or_else(|| format!("{approx:.2e}"), |c| c.to_string());
            let gib = |c: f64| c * 8.0 / f64::from(1u32 << 30);
            // One set at a time (a spectrum, a gallery): only N can shrink.
            let (product, fix) = if sets == 1 {
                (format!("N × D = {n} × {dims}"), "use a smaller N")
            } else {
                (
                    format!("N × sets × D = {n} × {sets} × {dims}"),
                    "use a smaller N or fewer sets",
                )
            };
            Err(format!(
                "{product} = {count} coordinates ({} GiB) is above the limit of {MAX_COORDINATES} ({} GiB); {fix}",
                short(gib(approx)),
                gib(MAX_COORDINATES as f64)
            ))
        }
    }
}

/// `sets` point sets of `n` points each in `dims` dimensions, on the torus `[0,1)^dims`.
///
/// Stored row-major as `[sets, n, dims]`, like the npy files: coordinate `d` of point `j` of set `s` is
/// `data[(s * n + j) * dims + d]`.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSets {
    sets: usize,
    n: usize,
    dims: usize,
    data: Vec<f64>,
}

impl PointSets {
    /// Checks shape and values: `dims` is 2 or 4, at least one set of at least one point, at most
    /// [`MAX_COORDINATES`] coordinates, as many as the shape needs, every coordinate finite and in
    /// `[0, 1]`; a coordinate equal to 1 is the torus point 0 and is stored so.
    pub fn new(sets: usize, n: usize, dims: usize, mut data: Vec<f64>) -> Result<Self> {
        if dims != 2 && dims != 4 {
            return Err(Error::Input(format!(
                "point sets must have 2 or 4 dimensions, found {dims}; anisospec works on 2D (x,y) and 4D (x,y,u,v) sets"
            )));
        }
        if sets == 0 || n == 0 {
            return Err(Error::Input(format!(
                "the point set is empty ({sets} sets of {n} points); give at least one set of at least one point"
            )));
        }
        let len = coordinate_count(sets, n, dims).map_err(Error::Input)?;
        if data.len() != len {
            return Err(Error::Input(format!(
                "{} coordinates do not fill {sets} sets x {n} points x {dims} dims",
                data.len()
            )));
        }
        for (i, c) in data.iter_mut().enumerate() {
            if !c.is_finite() || *c < 0.0 || *c > 1.0 {
                let (s, j, d) = (i / (n * dims), (i / dims) % n, i % dims);
                return Err(Error::Input(format!(
                    "coordinate {d} of point {j} in set {s} is {}; every coordinate must be a finite number in [0, 1) (the unit torus; exactly 1 is taken as 0)",
                    crate::error::number(*c)
                )));
            }
            if *c == 1.0 {
                *c = 0.0;
            }
        }
        Ok(Self {
            sets,
            n,
            dims,
            data,
        })
    }

    /// Joins single sets (each `n * dims` coordinates, all the same length) into one array.
    pub fn from_sets(dims: usize, sets: Vec<Vec<f64>>) -> Result<Self> {
        let count = sets.len();
        let len = sets.first().map_or(0, Vec::len);
        if sets.iter().any(|s| s.len() != len) {
            return Err(Error::Input(
                "the sets have different numbers of points; every set must have the same N".into(),
            ));
        }
        let n = len.checked_div(dims).unwrap_or(0);
        Self::new(count, n, dims, sets.concat())
    }

    /// Number of sets.
    pub fn sets(&self) -> usize {
        self.sets
    }

    /// Points per set.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Dimensions per point (2 or 4).
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// All coordinates, `[sets, n, dims]` row-major.
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The coordinates of set `s`, `[n, dims]` row-major.
    pub fn set(&self, s: usize) -> &[f64] {
        let len = self.n * self.dims;
        &self.data[s * len..(s + 1) * len]
    }

    /// Set `s` projected onto the dimensions of `proj`.
    pub fn project(&self, s: usize, proj: Projection) -> Vec<[f64; 2]> {
        project(self.set(s), self.dims, proj)
    }
}

/// Projects one set (`[n, dims]` row-major) onto the pair of dimensions `proj`.
pub fn project(set: &[f64], dims: usize, proj: Projection) -> Vec<[f64; 2]> {
    set.chunks_exact(dims)
        .map(|p| [p[proj.a], p[proj.b]])
        .collect()
}

/// The largest `f64` below 1: where coordinates that round up to 1 are clamped, to stay in `[0, 1)`.
pub const BELOW_ONE: f64 = 1.0 - f64::EPSILON / 2.0;

/// Wraps a coordinate onto `[0, 1)` (DESIGN §2: `rem_euclid`, never `fract`).
pub fn wrap(c: f64) -> f64 {
    let w = c.rem_euclid(1.0);
    // rem_euclid can round up to exactly 1.0 for tiny negative inputs.
    if w >= 1.0 {
        0.0
    } else {
        w
    }
}

/// Cranley–Patterson rotation: adds `shift` (one entry per dimension) to every point of one set, mod 1.
pub fn toroidal_shift(set: &mut [f64], shift: &[f64]) {
    for p in set.chunks_exact_mut(shift.len()) {
        for (c, s) in p.iter_mut().zip(shift) {
            *c = wrap(*c + s);
        }
    }
}

/// An ordered pair of dimensions `(a, b)`: `a` is the first (horizontal, `k1`) axis of a spectrum,
/// `b` the second (vertical, `k2`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Projection {
    /// First dimension (0 = x, 1 = y, 2 = u, 3 = v).
    pub a: usize,
    /// Second dimension.
    pub b: usize,
}

impl Projection {
    /// `xy`: the pixel plane, or the whole of a 2D set.
    pub const XY: Projection = Projection { a: 0, b: 1 };
    /// `uv`: the lens plane.
    pub const UV: Projection = Projection { a: 2, b: 3 };
    /// `xu`: pixel x against lens u, where defocus shears the integrand.
    pub const XU: Projection = Projection { a: 0, b: 2 };
    /// `yv`: pixel y against lens v.
    pub const YV: Projection = Projection { a: 1, b: 3 };

    /// Parses `xu`-style names (two of `x, y, u, v`) or index pairs `0,2`, and checks them against `dims`.
    pub fn parse(text: &str, dims: usize) -> Result<Self> {
        let t = text.trim();
        let idx: Option<Vec<usize>> = if t.contains(',') {
            t.split(',').map(|p| p.trim().parse().ok()).collect()
        } else {
            t.chars()
                .map(|c| DIM_NAMES.iter().position(|&d| d == c.to_ascii_lowercase()))
                .collect()
        };
        let bad = || {
            Error::Usage(format!(
                "--proj '{text}' is not a projection; write two of x,y,u,v (e.g. xy, xu, yv) or two dimension indices (e.g. 0,2)"
            ))
        };
        let idx = idx.ok_or_else(bad)?;
        if idx.len() != 2 {
            return Err(bad());
        }
        let (a, b) = (idx[0], idx[1]);
        if a == b {
            return Err(Error::Usage(format!(
                "--proj '{text}' names the same dimension twice; a projection needs two different dimensions"
            )));
        }
        if a >= dims || b >= dims {
            let valid = if dims == 2 {
                "xy or yx"
            } else {
                "any two of x,y,u,v"
            };
            return Err(Error::Usage(format!(
                "--proj '{text}' names dimension {} but the points have {dims} (0 to {}); use {valid}",
                a.max(b),
                dims - 1
            )));
        }
        Ok(Self { a, b })
    }

    /// The short name, e.g. `xu`.
    pub fn name(&self) -> String {
        let n = |d: usize| DIM_NAMES.get(d).copied().unwrap_or('?');
        format!("{}{}", n(self.a), n(self.b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_handles_negatives_and_rounding() {
        assert_eq!(wrap(-0.25), 0.75);
        assert_eq!(wrap(1.0), 0.0);
        assert!(wrap(-1e-18) < 1.0);
    }

    #[test]
    fn projections_parse_and_check_dims() {
        assert_eq!(Projection::parse("xu", 4).unwrap(), Projection::XU);
        assert_eq!(Projection::parse("2,3", 4).unwrap(), Projection::UV);
        assert!(Projection::parse("xu", 2).is_err());
        assert!(Projection::parse("xx", 4).is_err());
        assert!(Projection::parse("xq", 4).is_err());
    }

    #[test]
    fn sizes_are_checked_without_overflow() {
        // 2^62 x 2^62 x 4 wraps to 0, which an empty vector would match.
        let e = PointSets::new(1 << 62, 1 << 62, 4, Vec::new()).unwrap_err();
        assert!(e.to_string().contains("above the limit"), "{e}");
        let e = coordinate_count(1, 1_000_000_000, 2).unwrap_err();
        assert!(e.contains("2000000000 coordinates (14.9 GiB)"), "{e}");
        assert_eq!(coordinate_count(4, 1 << 25, 2), Ok(MAX_COORDINATES));
        assert!(coordinate_count(4, (1 << 25) + 1, 2).is_err());
        assert!(PointSets::new(1, 2, 2, vec![0.5; 3]).is_err());
    }

    #[test]
    fn new_rejects_out_of_range_and_wraps_one() {
        let e = PointSets::new(1, 1, 2, vec![0.5, 1.5])
            .unwrap_err()
            .to_string();
        // The message states the accepted 1 (taken as 0), not a bare half-open range.
        assert!(
            e.contains("[0, 1)") && e.contains("exactly 1 is taken as 0"),
            "{e}"
        );
        assert!(PointSets::new(1, 1, 2, vec![0.5, f64::NAN]).is_err());
        let p = PointSets::new(1, 1, 2, vec![1.0, 0.5]).unwrap();
        assert_eq!(p.data(), &[0.0, 0.5]);
    }
}
