//! 4D sets built from other samplers: padding (Cook 1986), the `xu`/`yv` construction, and shearing.

use super::Sampler;
use crate::error::{Error, Result};
use crate::points::shear::{shear_set_4d, ShearMode, MAX_SHEAR, NO_SHEAR};
use crate::rng::Rng;

/// Which pairs of 4D dimensions receive the two 2D sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// `(x, y)` and `(u, v)`: Cook's padding. `xy` and `uv` carry the 2D sampler's structure; `xu` and
    /// `yv` are only as good as the 1D projections (N-rooks for an N-rooks-type sampler, else white).
    Padded,
    /// `(x, u)` and `(y, v)`: the projections a defocused pixel shears carry the 2D structure.
    Xuyv,
}

impl Pairing {
    /// Registry prefix: `padded` or `xuyv`.
    pub fn prefix(self) -> &'static str {
        match self {
            Pairing::Padded => "padded",
            Pairing::Xuyv => "xuyv",
        }
    }

    /// The 4D dimensions that take the first and the second coordinate of each of the two sets.
    fn dims(self) -> [[usize; 2]; 2] {
        match self {
            Pairing::Padded => [[0, 1], [2, 3]],
            Pairing::Xuyv => [[0, 2], [1, 3]],
        }
    }
}

/// Two independent 2D sets of the same sampler, joined by a random permutation into a 4D set: point
/// `j` takes point `j` of the first set and point `π(j)` of the second, in the dimension pairs of
/// [`Pairing`]. Valid for the `N` the 2D sampler allows.
pub struct Paired {
    inner: Box<dyn Sampler>,
    pairing: Pairing,
}

impl Paired {
    /// Pairs a 2D sampler; `Error::Usage` if `inner` is not 2D.
    pub fn new(inner: Box<dyn Sampler>, pairing: Pairing) -> Result<Self> {
        if inner.dims() != 2 {
            return Err(Error::Usage(format!(
                "{}-{} needs a 2D sampler, but {} is {}D",
                pairing.prefix(),
                inner.name(),
                inner.name(),
                inner.dims()
            )));
        }
        Ok(Self { inner, pairing })
    }
}

impl Sampler for Paired {
    fn name(&self) -> String {
        format!("{}-{}", self.pairing.prefix(), self.inner.name())
    }
    fn dims(&self) -> usize {
        4
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        self.inner.check_n(n)
    }
    fn check_parameters(&self, n: usize) -> Result<()> {
        self.inner.check_parameters(n)
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let first = self.inner.generate(n, rng);
        let second = self.inner.generate(n, rng);
        let perm = super::grid::permutation(n, rng);
        let [da, db] = self.pairing.dims();
        let mut out = vec![0.0; 4 * n];
        for (j, &k) in perm.iter().enumerate() {
            for c in 0..2 {
                out[4 * j + da[c]] = first[2 * j + c];
                out[4 * j + db[c]] = second[2 * k + c];
            }
        }
        out
    }
}

/// A 4D sampler whose sets are sheared by `sx` in `xu` and `sy` in `yv`
/// ([`crate::points::shear::shear_set_4d`]). Valid for the `N` the inner sampler allows.
pub struct Sheared {
    inner: Box<dyn Sampler>,
    sx: f64,
    sy: f64,
    mode: ShearMode,
}

impl Sheared {
    /// Shears a 4D sampler; `Error::Usage` if `inner` is not 4D or a shear is not finite or above
    /// [`MAX_SHEAR`] in magnitude.
    pub fn new(inner: Box<dyn Sampler>, sx: f64, sy: f64, mode: ShearMode) -> Result<Self> {
        if inner.dims() != 4 {
            return Err(Error::Usage(format!(
                "a shear acts on 4D (x,y,u,v) sets, but {} is {}D; use a 4D sampler (e.g. xuyv-{})",
                inner.name(),
                inner.dims(),
                inner.name()
            )));
        }
        if !(sx.abs() <= MAX_SHEAR && sy.abs() <= MAX_SHEAR) {
            return Err(Error::Usage(format!(
                "shear ({}, {}) is not a finite shear of magnitude at most {MAX_SHEAR:e}; give shears for xu and yv in that range (beyond it the sheared coordinates lose their precision)",
                crate::error::number(sx),
                crate::error::number(sy)
            )));
        }
        Ok(Self {
            inner,
            sx,
            sy,
            mode,
        })
    }
}

impl Sampler for Sheared {
    fn name(&self) -> String {
        let mode = match self.mode {
            ShearMode::Transported => "transported",
            ShearMode::Wrap => "wrap",
        };
        format!(
            "{}+shear({},{},{mode})",
            self.inner.name(),
            crate::error::number(self.sx),
            crate::error::number(self.sy)
        )
    }
    fn dims(&self) -> usize {
        4
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        self.inner.check_n(n)
    }
    fn check_parameters(&self, n: usize) -> Result<()> {
        self.inner.check_parameters(n)
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let mut set = self.inner.generate(n, rng);
        shear_set_4d(&mut set, self.sx, self.sy, self.mode);
        set
    }
    /// Shifts the unsheared pattern, then shears: the sheared set itself is not periodic.
    fn generate_shifted(&self, n: usize, rng: &mut Rng, shift: &[f64]) -> Vec<f64> {
        let mut set = self.inner.generate_shifted(n, rng, shift);
        shear_set_4d(&mut set, self.sx, self.sy, self.mode);
        set
    }
    /// `None` for a shear of 0 in both planes (magnitudes below [`NO_SHEAR`]), which moves no point.
    fn shear_frame(&self) -> Option<super::ShearFrame<'_>> {
        (self.sx.abs() >= NO_SHEAR || self.sy.abs() >= NO_SHEAR).then(|| super::ShearFrame {
            pattern: self.inner.as_ref(),
            sx: self.sx,
            sy: self.sy,
            mode: self.mode,
        })
    }
}
