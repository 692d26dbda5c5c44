//! The depth oracle (DESIGN §5): per pixel, the depth the scene shows, the shear it puts on the `xu`
//! and `yv` slices of the pixel's integrand, the range of shears over the pixel footprint and the
//! aperture, and a class that says which sampling spectrum would fit.
//!
//! The shear is [`super::camera::Camera::shear`] of the depth, in pixels per lens width: the
//! integrand varies along `x + s u` (and `y + s v`). With square pixels `sx = sy` for a given depth;
//! both are reported because the sampling code takes them separately.

use super::scene::Scene;
use crate::error::{Error, Result};
use indicatif::ProgressBar;
use rayon::prelude::*;

/// Probes per axis of the `(x, y, u, v)` grid the shear range is taken over (`PROBES^4` rays a pixel,
/// from [`PROBE_INSET`] to `1 − PROBE_INSET` in equal steps: the footprint's and the lens's edges,
/// 1e-6 inside them, and four steps between).
pub const PROBES: usize = 6;

/// How far inside the footprint and the lens the outermost probes lie, in units of a pixel and of the
/// lens side. A probe on the edge itself belongs to two pixels: rounded, `47 + (1 − 2^−52)` is
/// exactly 48, and a scene edge that lies on that pixel boundary (the default scene's middle box
/// ends at x = 48) was seen by column 47, which the oracle then called a double wedge although none
/// of its rays reaches the box behind.
pub const PROBE_INSET: f64 = 1e-6;

/// A pixel whose shears all have `|s| ≤ IN_FOCUS` (pixel per lens width) is in focus: the defocus blur
/// is under a twentieth of a pixel.
pub const IN_FOCUS: f64 = 0.05;

/// A pixel whose shears spread over at most this width (pixel per lens width) shows a single depth: its
/// `xu` spectrum is a (slightly widened) hairline. A wider spread is a fan: a double wedge.
pub const HAIRLINE_SPREAD: f64 = 0.1;

/// What a pixel's `xu` / `yv` spectrum looks like.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelClass {
    /// No shear: every depth seen is (nearly) in the focal plane.
    InFocus = 0,
    /// One depth, one shear: a hairline spectrum.
    Hairline = 1,
    /// Several depths (an occluder edge): a fan of shears, a double-wedge spectrum.
    DoubleWedge = 2,
}

impl PixelClass {
    /// A short name: `in-focus`, `hairline` or `double-wedge`.
    pub fn name(self) -> &'static str {
        match self {
            Self::InFocus => "in-focus",
            Self::Hairline => "hairline",
            Self::DoubleWedge => "double-wedge",
        }
    }
}

/// The oracle's answer for one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelOracle {
    /// Depth (world units along the optical axis) seen through the pixel centre and the lens centre.
    pub depth: f64,
    /// Shear of the `xu` slice at that depth, pixels per lens width.
    pub sx: f64,
    /// Shear of the `yv` slice at that depth (equal to `sx`: square pixels).
    pub sy: f64,
    /// Smallest shear over the probe grid of the footprint and aperture.
    pub s_min: f64,
    /// Largest shear over the probe grid.
    pub s_max: f64,
    /// In focus, hairline or double wedge.
    pub class: PixelClass,
}

/// Fails with [`Error::Usage`] if the scene's aperture is 0: a pinhole has no shear to give.
pub fn require_aperture(scene: &Scene, what: &str) -> Result<()> {
    if scene.camera().aperture() <= 0.0 {
        return Err(Error::Usage(format!(
            "{what} needs a shear, but the aperture is 0 (a pinhole: every pixel is in focus); \
             set aperture > 0 in the scene file, e.g. aperture = 0.04"
        )));
    }
    Ok(())
}

/// The oracle for pixel `(px, py)` (inside the image). Rays that escape the room (none do from inside)
/// are skipped.
pub fn oracle_pixel(scene: &Scene, px: usize, py: usize) -> PixelOracle {
    let cam = scene.camera();
    let centre = cam.ray(px, py, [0.5, 0.5, 0.5, 0.5]);
    let depth = scene.depth(centre.0, centre.1).unwrap_or(f64::INFINITY);
    let s = if depth.is_finite() {
        cam.shear(depth)
    } else {
        0.0
    };
    // An escaping ray has no depth: it takes no part in the range (the centre's 0 neither).
    let (mut s_min, mut s_max) = if depth.is_finite() {
        (s, s)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY)
    };
    let at = |i: usize| PROBE_INSET + (1.0 - 2.0 * PROBE_INSET) * i as f64 / (PROBES - 1) as f64;
    for i in 0..PROBES.pow(4) {
        let p = [
            at(i % PROBES),
            at(i / PROBES % PROBES),
            at(i / PROBES.pow(2) % PROBES),
            at(i / PROBES.pow(3)),
        ];
        let (o, d) = cam.ray(px, py, p);
        if let Some(z) = scene.depth(o, d) {
            let sz = cam.shear(z);
            s_min = s_min.min(sz);
            s_max = s_max.max(sz);
        }
    }
    if s_min > s_max {
        // No ray met the room: the centre's shear of 0 stands for the pixel.
        (s_min, s_max) = (s, s);
    }
    let class = if s_min.abs().max(s_max.abs()) <= IN_FOCUS {
        PixelClass::InFocus
    } else if s_max - s_min <= HAIRLINE_SPREAD {
        PixelClass::Hairline
    } else {
        PixelClass::DoubleWedge
    };
    PixelOracle {
        depth,
        sx: s,
        sy: s,
        s_min,
        s_max,
        class,
    }
}

/// The oracle for every pixel, row-major from the top row; `bar` advances by one per row (pass
/// `ProgressBar::hidden()` for none). Needs a positive aperture.
pub fn oracle_image(scene: &Scene, bar: &ProgressBar) -> Result<Vec<PixelOracle>> {
    require_aperture(scene, "the oracle")?;
    let w = scene.width();
    let rows: Vec<Vec<PixelOracle>> = (0..scene.height())
        .into_par_iter()
        .map(|py| {
            let row = (0..w).map(|px| oracle_pixel(scene, px, py)).collect();
            bar.inc(1);
            row
        })
        .collect();
    bar.finish_and_clear();
    Ok(rows.concat())
}

/// Channel names of the oracle's EXR and the last axis of its npy, in order.
pub const ORACLE_CHANNELS: [&str; 6] = ["depth", "sx", "sy", "s_min", "s_max", "class"];

/// The oracle as a `[height, width, 6]` row-major array, channels in [`ORACLE_CHANNELS`] order
/// (class as 0 in focus, 1 hairline, 2 double wedge).
pub fn oracle_array(oracle: &[PixelOracle]) -> Vec<f64> {
    oracle
        .iter()
        .flat_map(|o| [o.depth, o.sx, o.sy, o.s_min, o.s_max, o.class as u8 as f64])
        .collect()
}
