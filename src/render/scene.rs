//! The built-in scene: a grey Cornell box with three boxes at increasing depths, a fine checker on the
//! back wall, diffuse surfaces, one point light with hard shadows, and a thin-lens camera (DESIGN §5).
//!
//! World units: the room is the box `[-1, 1] × [-1, 1] × [-1, 6]`; `+x` is right, `+y` up, and the
//! camera looks down `+z` from the origin. The back wall (`z = 6`) carries a checker of cell side
//! [`CHECKER_CELL`]; seen from the default camera a cell is about 0.9 pixel wide, so the wall is a
//! high-frequency texture. No acceleration structure: every ray tests the room and the three boxes.

use super::camera::Camera;
use crate::error::{number, Error, Result};
use crate::points::shear::MAX_SHEAR;
use glam::DVec3;
use std::path::Path;

/// Side of one checker cell on the back wall, in world units.
pub const CHECKER_CELL: f64 = 0.05;

/// The room's inner bounds: walls at `x = ±1`, floor `y = −1`, ceiling `y = 1`, back wall `z = 6`
/// (the wall at `z = −1` is behind the camera).
const ROOM_MIN: DVec3 = DVec3::new(-1.0, -1.0, -1.0);
const ROOM_MAX: DVec3 = DVec3::new(1.0, 1.0, 6.0);

/// Light position and intensity: radiance from a lit diffuse point is
/// `albedo × (AMBIENT + LIGHT_POWER cos θ / r²)` (no 1/π; the image is relative).
const LIGHT_POS: DVec3 = DVec3::new(0.0, 0.9, 2.5);
const LIGHT_POWER: f64 = 3.0;
const AMBIENT: f64 = 0.08;

/// Offset along the normal for shadow-ray origins, in world units.
const RAY_EPS: f64 = 1e-9;

/// An axis-aligned box, opaque and diffuse.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: DVec3,
    max: DVec3,
    albedo: f64,
}

/// The three boxes standing on the floor, near-left to far-right: front faces at depths 1.6, 3.0 and
/// 4.5. With the default focus `F = 3` the middle box is in focus.
const BOXES: [Aabb; 3] = [
    Aabb {
        min: DVec3::new(-0.45, -1.0, 1.6),
        max: DVec3::new(-0.1, -0.1, 1.95),
        albedo: 0.8,
    },
    Aabb {
        min: DVec3::new(0.05, -1.0, 3.0),
        max: DVec3::new(0.45, 0.3, 3.4),
        albedo: 0.7,
    },
    Aabb {
        min: DVec3::new(0.6, -1.0, 4.5),
        max: DVec3::new(0.95, 0.6, 4.9),
        albedo: 0.75,
    },
];

/// What a ray hit: distance along the (unit) ray, point, outward normal facing the ray, albedo.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the unit direction, world units.
    pub t: f64,
    /// The hit point.
    pub point: DVec3,
    /// Unit surface normal, facing the incoming ray.
    pub normal: DVec3,
    /// Diffuse albedo at the point (texture included), in `[0, 1]`.
    pub albedo: f64,
}

/// The overridable parameters of the scene, as read from a TOML scene file. Every key is optional;
/// a missing key keeps the default, an unknown key is an error.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneConfig {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// Camera (lens centre) position in world units; the camera always looks down `+z`, `+y` up.
    #[serde(deserialize_with = "crate::exact_array::exactly")]
    pub position: [f64; 3],
    /// Focal distance `F`: depth (world units along `z` from the lens) of the plane in focus, in
    /// `(1e-3, 1e6)`.
    pub focus: f64,
    /// Side `A` of the square aperture, world units; 0 is a pinhole.
    pub aperture: f64,
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            width: 64,
            height: 64,
            fov: 2.0 * 0.3f64.atan().to_degrees(),
            position: [0.0, 0.0, 0.0],
            focus: 3.0,
            aperture: 0.04,
        }
    }
}

impl SceneConfig {
    /// Reads a TOML scene file; a syntax error, an unknown key or a value out of range is
    /// [`Error::Input`] naming the file and the key.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = crate::input::read_text(path, "scene file").map_err(|e| match e {
            // Every reason to refuse the file (missing, forbidden, a folder, not UTF-8) with its fix.
            Error::Input(m) => Error::Input(format!("{m} (a TOML scene file)")),
            other => other,
        })?;
        let config: SceneConfig = toml::from_str(&text).map_err(|e| {
            // toml's Display quotes the offending line (so the key) with a caret under the value.
            Error::Input(format!(
                "scene file {}: {}\nallowed keys: width, height, fov, position, focus, aperture",
                path.display(),
                e.to_string().trim_end()
            ))
        })?;
        config
            .validate()
            .map_err(|m| Error::Input(format!("scene file {}: {m}", path.display())))?;
        Ok(config)
    }

    /// Checks every value; the message names the offending key and its allowed range.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let range = |key: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v > lo && v < hi {
                Ok(())
            } else {
                Err(format!(
                    "{key} = {} is out of range; it must lie in ({lo}, {hi})",
                    number(v)
                ))
            }
        };
        for (key, v) in [("width", self.width), ("height", self.height)] {
            if !(1..=4096).contains(&v) {
                return Err(format!(
                    "{key} = {v} is out of range; it must lie in 1..=4096 pixels"
                ));
            }
        }
        range("fov", self.fov, 0.0, 170.0)?;
        // Nearer than 1e-3 world units the oracle's shears (about aperture / focus) run past any useful range.
        range("focus", self.focus, 1e-3, 1e6)?;
        if !(self.aperture.is_finite() && (0.0..1.0).contains(&self.aperture)) {
            return Err(format!(
                "aperture = {} is out of range; it must lie in [0, 1) world units (0 is a pinhole)",
                number(self.aperture)
            ));
        }
        let free = |p: DVec3| {
            p.cmpgt(ROOM_MIN).all()
                && p.cmplt(ROOM_MAX).all()
                && !BOXES
                    .iter()
                    .any(|b| p.cmpge(b.min).all() && p.cmple(b.max).all())
        };
        let centre = DVec3::from_array(self.position);
        let h = self.aperture / 2.0;
        let corners =
            [(-h, -h), (-h, h), (h, -h), (h, h)].map(|(x, y)| centre + DVec3::new(x, y, 0.0));
        if !free(centre) || !corners.into_iter().all(free) {
            return Err(format!(
                "position = {:?} with aperture = {} puts the lens outside free space; the whole lens \
                 must be inside the room (-1 < x < 1, -1 < y < 1, -1 < z < 6) and outside the three boxes",
                self.position,
                number(self.aperture)
            ));
        }
        let bound = self.shear_bound();
        if bound.is_nan() || bound > MAX_SHEAR {
            return Err(format!(
                "this camera (fov = {}, aperture = {}, focus = {}, height = {}, position = {:?}) can put a \
                 shear of magnitude up to {bound:.3e} pixels per lens width on a pixel, beyond the largest \
                 supported shear {MAX_SHEAR:e}; widen fov, make aperture smaller, move focus towards the \
                 scene's depths, or move position away from the walls and boxes (the defaults are fov = 33.4, aperture = 0.04, focus = 3)",
                number(self.fov),
                number(self.aperture),
                number(self.focus),
                self.height,
                self.position
            ));
        }
        Ok(())
    }

    /// An upper bound on `|s|` over every depth the camera can see, for [`Camera::shear`]'s
    /// `s = A (F − d)/(F d) × H/(2 tan(fov/2))`: `|1/d − 1/F|` is largest at an end of the depth range,
    /// and every visible depth lies between a lower bound `d_lo` (the lateral gap from the lens to each
    /// wall and box over the steepest ray slope, or a box's front face) and the back wall. Infinite if
    /// a surface can come arbitrarily close to the lens; 0 for a pinhole. Call on a configuration whose
    /// other values are in range.
    pub fn shear_bound(&self) -> f64 {
        if self.aperture == 0.0 {
            return 0.0;
        }
        let tan_y = (self.fov.to_radians() / 2.0).tan();
        let tan_x = tan_y * self.width as f64 / self.height as f64;
        let h = self.aperture / 2.0;
        let p = DVec3::from_array(self.position);
        // Steepest lateral slope of a ray (per unit of depth): pixel slope plus lens offset / focus.
        let slope = [tan_x + h / self.focus, tan_y + h / self.focus];
        let reach = |gap: f64, axis: usize| gap.max(0.0) / slope[axis];
        // Side walls, floor and ceiling.
        let mut d_lo = (0..2)
            .map(|a| reach((ROOM_MAX[a] - p[a]).min(p[a] - ROOM_MIN[a]) - h, a))
            .fold(ROOM_MAX.z - p.z, f64::min);
        for b in BOXES.iter().filter(|b| b.max.z > p.z) {
            let gap = |a: usize| (b.min[a] - (p[a] + h)).max((p[a] - h) - b.max[a]);
            let d = (b.min.z - p.z).max(reach(gap(0), 0)).max(reach(gap(1), 1));
            d_lo = d_lo.min(d);
        }
        let d_hi = ROOM_MAX.z - p.z;
        let camera = Camera::new(self);
        camera.shear(d_lo).abs().max(camera.shear(d_hi).abs())
    }

    /// A stable text key for caches: the configuration as JSON.
    pub fn key(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The scene: fixed geometry and lighting, and a camera built from a [`SceneConfig`].
#[derive(Clone, Debug)]
pub struct Scene {
    config: SceneConfig,
    camera: Camera,
}

impl Scene {
    /// Builds the scene; the configuration must pass [`SceneConfig::validate`].
    pub fn new(config: SceneConfig) -> Result<Self> {
        config.validate().map_err(Error::Input)?;
        let camera = Camera::new(&config);
        Ok(Self { config, camera })
    }

    /// The built-in scene with its defaults, or with the overrides of a TOML file.
    pub fn load(path: Option<&Path>) -> Result<Self> {
        match path {
            Some(p) => Self::new(SceneConfig::from_file(p)?),
            None => Self::new(SceneConfig::default()),
        }
    }

    /// The configuration the scene was built from.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The thin-lens camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Image width in pixels.
    pub fn width(&self) -> usize {
        self.config.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> usize {
        self.config.height
    }

    /// Nearest surface along the ray `origin + t dir` (`dir` unit length), or `None` if it leaves the
    /// room (impossible from inside, kept for robustness).
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        let inv = dir.recip();
        let mut best = room_exit(origin, dir, inv);
        for b in &BOXES {
            if let Some(h) = box_entry(b, origin, dir, inv) {
                if best.is_none_or(|x| h.t < x.t) {
                    best = Some(h);
                }
            }
        }
        best
    }

    /// True if the segment from `point` to the light is blocked by a box.
    fn shadowed(&self, point: DVec3) -> bool {
        let to_light = LIGHT_POS - point;
        let dist = to_light.length();
        let dir = to_light / dist;
        let inv = dir.recip();
        BOXES
            .iter()
            .any(|b| box_entry(b, point, dir, inv).is_some_and(|h| h.t < dist))
    }

    /// Radiance leaving a hit point towards the camera: diffuse albedo times ambient plus the point
    /// light's `cos θ / r²` when the light is visible.
    fn shade(&self, hit: &Hit) -> f64 {
        let p = hit.point + hit.normal * RAY_EPS;
        let to_light = LIGHT_POS - p;
        let r2 = to_light.length_squared();
        let cos = hit.normal.dot(to_light) / r2.sqrt();
        let direct = if cos > 0.0 && !self.shadowed(p) {
            LIGHT_POWER * cos / r2
        } else {
            0.0
        };
        hit.albedo * (AMBIENT + direct)
    }

    /// Radiance along a camera ray (0 if it escapes).
    pub fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        self.intersect(origin, dir).map_or(0.0, |h| self.shade(&h))
    }

    /// The pixel integrand `f(x, y, u, v)` of pixel `(px, py)`: the radiance of the camera's ray
    /// through pixel point `(x, y)` and lens point `(u, v)`, `p` in `[0,1)^4`.
    pub fn pixel_radiance(&self, px: usize, py: usize, p: [f64; 4]) -> f64 {
        let (origin, dir) = self.camera.ray(px, py, p);
        self.radiance(origin, dir)
    }

    /// Depth (distance along the optical axis `z` from the lens plane) of the first surface on the ray,
    /// or `None` if it escapes.
    pub fn depth(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        self.intersect(origin, dir)
            .map(|h| h.point.z - self.camera.position().z)
    }
}

/// The room seen from inside: the ray leaves through the nearest wall.
fn room_exit(origin: DVec3, dir: DVec3, inv: DVec3) -> Option<Hit> {
    let t1 = (ROOM_MIN - origin) * inv;
    let t2 = (ROOM_MAX - origin) * inv;
    let far = t1.max(t2);
    let t = far.min_element();
    if !t.is_finite() || t <= 0.0 {
        return None;
    }
    let axis = if far.x == t {
        0
    } else if far.y == t {
        1
    } else {
        2
    };
    let point = origin + dir * t;
    let mut normal = DVec3::ZERO;
    normal[axis] = -dir[axis].signum();
    let albedo = match (axis, dir[axis] > 0.0) {
        (0, false) => 0.75, // left wall
        (0, true) => 0.45,  // right wall
        (1, _) => 0.7,      // floor and ceiling
        (2, true) => checker(point),
        _ => 0.5,
    };
    Some(Hit {
        t,
        point,
        normal,
        albedo,
    })
}

/// Entry into a solid box (slab test), for rays starting outside it.
fn box_entry(b: &Aabb, origin: DVec3, dir: DVec3, inv: DVec3) -> Option<Hit> {
    let t1 = (b.min - origin) * inv;
    let t2 = (b.max - origin) * inv;
    let near = t1.min(t2);
    let far = t1.max(t2);
    let t_near = near.max_element();
    let t_far = far.min_element();
    if !(t_near <= t_far && t_near > 0.0) {
        return None;
    }
    let axis = if near.x == t_near {
        0
    } else if near.y == t_near {
        1
    } else {
        2
    };
    let mut normal = DVec3::ZERO;
    normal[axis] = -dir[axis].signum();
    Some(Hit {
        t: t_near,
        point: origin + dir * t_near,
        normal,
        albedo: b.albedo,
    })
}

/// The back wall's checker: albedo 0.15 or 0.85 in cells of side [`CHECKER_CELL`].
fn checker(p: DVec3) -> f64 {
    let i = (p.x / CHECKER_CELL).floor() as i64 + (p.y / CHECKER_CELL).floor() as i64;
    if i.rem_euclid(2) == 0 {
        0.85
    } else {
        0.15
    }
}
