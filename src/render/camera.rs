//! The thin-lens camera with a square aperture, and the shear its defocus puts on a pixel's integrand.
//!
//! Coordinates of one pixel's integrand (DESIGN §2): `(x, y)` in `[0,1)²` is the position inside pixel
//! `(px, py)` (x to the right, y downwards, like image rows), `(u, v)` in `[0,1)²` the position on the
//! square lens of side `A`, oriented the same way: the lens point is
//! `position + ((u − ½) A, (½ − v) A, 0)`.
//!
//! A ray through lens point `L` and pixel point `(x, y)` passes through the point of the focal plane
//! (depth `F`) that pixel point sees through a pinhole. A surface point at depth `d` is then seen at
//! pixel coordinate `x = c − s u` for a constant `c`, with
//!
//! `s = A (F − d) / (F d) × H / (2 tan(fov/2))`,
//!
//! i.e. DESIGN §5's `x' = x + u (F − d)/d` with the lens-to-pixel scale `A/F × H/(2 tan(fov/2))`
//! (pixels per unit of image-plane slope). The integrand is constant along `x + s u = c`: it varies
//! along `t = x + s u`, which is what `points::shear::shear_pair(.., s, ..)` stratifies. The same `s`
//! holds for `y` and `v` since pixels are square.

use super::scene::SceneConfig;
use glam::DVec3;

/// A thin-lens camera looking down `+z` with `+y` up.
#[derive(Clone, Debug)]
pub struct Camera {
    position: DVec3,
    width: f64,
    height: f64,
    /// `tan(fov/2)` horizontally and vertically.
    tan_x: f64,
    tan_y: f64,
    focus: f64,
    aperture: f64,
}

impl Camera {
    /// The camera of a (validated) scene configuration.
    pub fn new(c: &SceneConfig) -> Self {
        let tan_y = (c.fov.to_radians() / 2.0).tan();
        Self {
            position: DVec3::from_array(c.position),
            width: c.width as f64,
            height: c.height as f64,
            tan_x: tan_y * c.width as f64 / c.height as f64,
            tan_y,
            focus: c.focus,
            aperture: c.aperture,
        }
    }

    /// Lens centre, world units.
    pub fn position(&self) -> DVec3 {
        self.position
    }

    /// Aperture side `A`, world units (0: pinhole).
    pub fn aperture(&self) -> f64 {
        self.aperture
    }

    /// The primary ray (origin on the lens, unit direction) for pixel `(px, py)` and integrand point
    /// `(x, y, u, v)` in `[0,1)^4`.
    pub fn ray(&self, px: usize, py: usize, p: [f64; 4]) -> (DVec3, DVec3) {
        let sx = (2.0 * (px as f64 + p[0]) / self.width - 1.0) * self.tan_x;
        let sy = (1.0 - 2.0 * (py as f64 + p[1]) / self.height) * self.tan_y;
        let focal = DVec3::new(sx * self.focus, sy * self.focus, self.focus);
        let lens = DVec3::new(
            (p[2] - 0.5) * self.aperture,
            (0.5 - p[3]) * self.aperture,
            0.0,
        );
        (self.position + lens, (focal - lens).normalize())
    }

    /// Pixels per unit of image-plane slope, `H / (2 tan(fov/2))`.
    fn pixels_per_slope(&self) -> f64 {
        self.height / (2.0 * self.tan_y)
    }

    /// The shear `s` of the `xu` (and `yv`) slice at depth `d` (world units, `d > 0`): the integrand
    /// varies along `x + s u`, in units of pixels per lens width. Zero in the focal plane and for a
    /// pinhole.
    pub fn shear(&self, depth: f64) -> f64 {
        self.aperture * (self.focus - depth) / (self.focus * depth) * self.pixels_per_slope()
    }
}
