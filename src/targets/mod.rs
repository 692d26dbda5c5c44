//! Target spectra for the optimizer (DESIGN §6), read from strict TOML files in `targets/`.
//!
//! A shape target is an expected power spectrum `T(k)` for one 2D projection, with `T = 0` in a *dark*
//! region and `T = 1` elsewhere (image targets may hold any values `≥ 0`); a variance target
//! ([`variance`]) is not a shape but the variance the set predicts for a family of integrands. Every
//! length in a target file is a *normalized frequency* `ν = |k| / sqrt(N)`: a target means the same
//! thing at every `N`, and its dark region holds about the same multiple of `N` frequency cells. A set
//! of `N` points has `2N` degrees of freedom, and with `P` near 1 everywhere else, as a target asks,
//! about `N` dark cells is what it can reach (N-rooks, for example, holds about `0.7 N` cells below `P = 0.1` along its two axes).
//! [`Target::grid`] refuses targets darker than that and reports the reachable fraction. Sets that pay
//! for darkness with peaks darken far more: a rank-1 lattice is dark everywhere but on its dual lattice,
//! where `P = N` ([`crate::samplers::lattice`]). So a target that asks for peaks (an image, e.g. a
//! measured spectrum) may darken `N` cells plus what it asks above `P = 1`, net, over its other cells
//! inside its fit radius, each taken at most `P = N`.
//!
//! File format (one table, `kind` picks the shape, unknown keys are errors):
//!
//! ```toml
//! kind = "double-wedge"   # or "hairline", "blue-noise", "image", "variance"
//! s0 = 0.3                # dark between the lines k2 = s0 k1 and k2 = s1 k1 ...
//! s1 = 0.7
//! radius = 1.6            # ... up to |k| = radius * sqrt(N)
//! ```

use crate::error::{number, Error, Result};
use crate::points::shear::MAX_SHEAR;
use crate::spectrum::frequency;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub mod variance;
pub use variance::Variance;

/// The values of a target file's `kind`.
const KINDS: [&str; 5] = [
    "hairline",
    "double-wedge",
    "blue-noise",
    "image",
    "variance",
];

/// A key error of [`Target::parse`] (`"invalid type: …\nin `radius`\n"`) as one line that names the
/// key and the line of `text` it is on: `invalid type: … (key radius, line 3)`.
fn located(error: &str, text: &str) -> String {
    let mut lines = error.trim_end().lines();
    let what = lines.next().unwrap_or_default().to_string();
    // A value of the wrong type names its key on a line of its own; an unknown key in the message.
    fn named(l: &str) -> Option<&str> {
        l.strip_prefix("in `").and_then(|k| k.strip_suffix('`'))
    }
    let unknown = what
        .strip_prefix("unknown field `")
        .and_then(|rest| rest.split('`').next());
    let Some(key) = lines.find_map(named).or(unknown) else {
        return what;
    };
    // The line of the top-level key the path starts with (a bare key, or a table header).
    let first = key.split('.').next().unwrap_or(key);
    let line = text.lines().position(|l| {
        let l = l.trim_start();
        let key_line = l
            .strip_prefix(first)
            .is_some_and(|rest| rest.trim_start().starts_with('='));
        // `[first]`, `[[first]]` or `[first.sub]`, not `[firsts]`.
        let header = l.starts_with('[')
            && l.trim_start_matches('[')
                .trim_start()
                .strip_prefix(first)
                .is_some_and(|rest| rest.starts_with([']', '.', ' ', '\t']));
        key_line || header
    });
    match line {
        Some(i) => format!("{what} (key {key}, line {})", i + 1),
        None => format!("{what} (key {key})"),
    }
}

/// Below this many points a shape target's refusal searches the N up to `4 × SMALL_N` for the
/// smallest at which it builds (a few cells decide there, so the next N that works is hard to tell
/// from the message alone: a blue-noise disc of radius 0.35 needs N = 9, not the 4 its cell count
/// suggests). Grids that small take microseconds.
pub const SMALL_N: usize = 64;

/// The largest number of dark cells, in units of `N`, that a target may ask of `N` points.
pub const REACH: f64 = 1.0;

/// Cells with a target value at or below this level count as dark (for image targets and metrics).
pub const DARK_LEVEL: f64 = 0.05;

/// The default weight of the dark region's mean squared error relative to the rest (see
/// [`TargetGrid::weight`]).
pub const DEFAULT_DARK_WEIGHT: f64 = 8.0;

/// The largest `dark_weight`, as for the optimizer's other loss weights: the loss's terms are of order
/// 1, and far larger weights stall the solver's line search (measured: from about 1e20 the sets stay
/// where they started) or overflow the loss to infinity (about 1e308).
pub const MAX_DARK_WEIGHT: f64 = 1e6;

/// A widened hairline: dark within perpendicular distance `(half_width + opening · |k| / sqrt(N)) *
/// sqrt(N)` of the line `k2 = shear * k1` up to `|k| = length * sqrt(N)`, and inside the disc
/// `|k| < inner_radius * sqrt(N)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hairline {
    /// Slope `s` of the dark line `k2 = s k1` (the shear of the integrand `f(x + s u)`).
    pub shear: f64,
    /// Half-width of the dark band, in units of `sqrt(N)` frequency cells (0: a hairline).
    pub half_width: f64,
    /// How fast the band opens: its half-width at `|k| = ρ sqrt(N)` is `half_width + opening · ρ`, so
    /// a line of slope within `±opening` of `shear` (an oracle shear error) stays inside it (default 0:
    /// a band of constant width).
    #[serde(default)]
    pub opening: f64,
    /// How far the band reaches, in units of `sqrt(N)`.
    pub length: f64,
    /// Radius of the dark disc around the origin, in units of `sqrt(N)`.
    #[serde(default)]
    pub inner_radius: f64,
    /// Weight of the dark region's error against the rest's (default [`DEFAULT_DARK_WEIGHT`], at most
    /// [`MAX_DARK_WEIGHT`]).
    #[serde(default)]
    pub dark_weight: Option<f64>,
    /// Exponent `α` of a low-frequency emphasis inside the dark region and its rim: cell `k` weighs
    /// in proportion to `|k|^(−α)` there (default 0: uniform; see [`TargetGrid::weight`]).
    #[serde(default)]
    pub falloff: Option<f64>,
}

/// A double wedge: dark between the lines `k2 = s0 k1` and `k2 = s1 k1`, and within `margin * sqrt(N)`
/// of them, up to `|k| = radius * sqrt(N)`, and inside the disc `|k| < inner_radius * sqrt(N)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoubleWedge {
    /// Lower slope (`s0 ≤ s1`).
    pub s0: f64,
    /// Upper slope.
    pub s1: f64,
    /// Perpendicular distance, in units of `sqrt(N)`, by which the dark region reaches beyond the two
    /// lines (default 0): an edge's spectrum is a line smeared by about one frequency cell across, so
    /// the wedge's extreme edges need a margin.
    #[serde(default)]
    pub margin: f64,
    /// Radius of the wedge, in units of `sqrt(N)`.
    pub radius: f64,
    /// Radius of the dark disc around the origin, in units of `sqrt(N)`.
    #[serde(default)]
    pub inner_radius: f64,
    /// Weight of the dark region's error against the rest's (default [`DEFAULT_DARK_WEIGHT`], at most
    /// [`MAX_DARK_WEIGHT`]).
    #[serde(default)]
    pub dark_weight: Option<f64>,
    /// Exponent `α` of a low-frequency emphasis inside the dark region and its rim: cell `k` weighs
    /// in proportion to `|k|^(−α)` there (default 0: uniform; see [`TargetGrid::weight`]).
    #[serde(default)]
    pub falloff: Option<f64>,
}

/// Isotropic blue noise: dark inside the disc `|k| < radius * sqrt(N)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlueNoise {
    /// Radius of the dark disc, in units of `sqrt(N)`.
    pub radius: f64,
    /// Weight of the dark region's error against the rest's (default [`DEFAULT_DARK_WEIGHT`], at most
    /// [`MAX_DARK_WEIGHT`]).
    #[serde(default)]
    pub dark_weight: Option<f64>,
    /// Exponent `α` of a low-frequency emphasis inside the dark region and its rim: cell `k` weighs
    /// in proportion to `|k|^(−α)` there (default 0: uniform; see [`TargetGrid::weight`]).
    #[serde(default)]
    pub falloff: Option<f64>,
}

/// A target read from an image of `T` values: a 2D npy array (`float64` or `float32`, shape
/// `[rows, cols]`, row 0 lowest) or an EXR image (its `Y` channel, else `R`, else its only one; top row highest,
/// the layout `anisospec spectrum -o FILE.exr` writes, so a measured spectrum can serve as a target).
///
/// The image covers normalized frequencies `ν1, ν2 ∈ [−extent, extent)`: column `j` of `cols` spans
/// `ν1 ∈ [−extent + 2·extent·j/cols, …)`, row `i` spans `ν2` likewise (row 0 lowest, the spectrum layout
/// of DESIGN §3). Each frequency cell takes the value of the pixel holding `k / sqrt(N)`; `T = 1` outside
/// the image. A power spectrum is even, so the target is made so: a cell takes the mean of the
/// values at `k` and `−k`. Cells with `T ≤` [`DARK_LEVEL`] are dark.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Image {
    /// Path of the `.npy` or `.exr` file, relative to the TOML file's folder.
    pub file: PathBuf,
    /// Half-width of the image in normalized frequency `ν`.
    pub extent: f64,
    /// Weight of the dark region's error against the rest's (default [`DEFAULT_DARK_WEIGHT`], at most
    /// [`MAX_DARK_WEIGHT`]).
    #[serde(default)]
    pub dark_weight: Option<f64>,
    /// Exponent `α` of a low-frequency emphasis inside the dark region and its rim: cell `k` weighs
    /// in proportion to `|k|^(−α)` there (default 0: uniform; see [`TargetGrid::weight`]).
    #[serde(default)]
    pub falloff: Option<f64>,
    /// The pixel values, row-major, filled in by [`Target::load`].
    #[serde(skip)]
    pub pixels: Vec<f64>,
    /// `[rows, cols]` of the image, filled in by [`Target::load`].
    #[serde(skip)]
    pub shape: [usize; 2],
}

/// A target spectrum: one of the shapes of DESIGN §6.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Target {
    /// Widened hairline (see [`Hairline`]).
    Hairline(Hairline),
    /// Double wedge (see [`DoubleWedge`]).
    DoubleWedge(DoubleWedge),
    /// Isotropic blue noise (see [`BlueNoise`]).
    BlueNoise(BlueNoise),
    /// Loaded from an image (see [`Image`]).
    Image(Image),
    /// The predicted variance of an integrand family (see [`Variance`]).
    Variance(Variance),
}

/// A target laid out on a frequency grid for a given `N`: the values `T(k)`, the loss weights `W(k)`
/// and the dark mask, each `res × res` in the layout of DESIGN §3 (`[i * res + j]`, `k1 = j − res/2`,
/// `k2 = i − res/2`).
#[derive(Clone, Debug, PartialEq)]
pub struct TargetGrid {
    /// Points per set the grid was made for.
    pub n: usize,
    /// Grid size `K` (even).
    pub res: usize,
    /// Fit radius in frequency cells: `W = 0` beyond it.
    pub fit_radius: f64,
    /// `T(k)`.
    pub target: Vec<f64>,
    /// `W(k) ≥ 0`: `dark_weight / (dark + rim cells)` on dark cells and on the rim (non-dark cells next
    /// to a dark one, where pushed-out energy piles up first), `1 / (other cells)` on the others inside
    /// the fit radius, 0 at `k = 0`, on the unpaired row and column `−K/2`, and beyond the fit radius.
    /// The loss is then `dark_weight ×` (mean squared error over dark and rim) `+` (the same elsewhere).
    /// A variance target's: `weight · |ĝ(k)|² / Σ |ĝ|²` inside the fit radius, 0 at the same places.
    pub weight: Vec<f64>,
    /// Dark cells (`T ≤` [`DARK_LEVEL`]) inside the fit radius, excluding `k = 0`.
    pub dark: Vec<bool>,
    /// Number of dark cells.
    pub dark_cells: usize,
    /// Each cell's annulus (see [`TargetGrid::annulus`]).
    rings: Vec<Option<u32>>,
    /// A variance target's grid: the loss is `Σ W P` (the predicted variance, [`variance`]), not
    /// `Σ W (P − T)²`; `T` is unused, no cell is dark and there are no annuli.
    pub variance: bool,
}

impl TargetGrid {
    /// The cells the fit weighs whose target is above `P = N`, which no set of `N` points reaches
    /// (`|F(k)| ≤ N` at every `k`): their count and the largest such target; `None` if there are none
    /// (a variance target has no `T`).
    pub fn above_reach(&self) -> Option<(usize, f64)> {
        if self.variance {
            return None;
        }
        let n = self.n as f64;
        let above: Vec<f64> = self
            .target
            .iter()
            .zip(&self.weight)
            .filter(|&(&t, &w)| w > 0.0 && t > n)
            .map(|(&t, _)| t)
            .collect();
        (!above.is_empty()).then(|| (above.len(), above.iter().copied().fold(n, f64::max)))
    }

    /// Number of annuli compared: `r = 0 ..` this, where annulus `r` holds the frequencies with
    /// `round(|k|) = r` and lies wholly inside the fit radius (`r + ½ ≤` fit radius).
    pub fn annuli(&self) -> usize {
        (self.fit_radius - 0.5).floor().max(0.0) as usize + 1
    }

    /// The annulus (`round(|k|)`, see [`TargetGrid::annuli`]) of the cell at index `idx`, for the
    /// annular-mean comparisons of the fit and of the loss: only non-dark cells with `W > 0`.
    pub fn annulus(&self, idx: usize) -> Option<usize> {
        self.rings[idx].map(|r| r as usize)
    }
}

fn finite(name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::Input(format!(
            "target parameter '{name}' is {}; every parameter must be a finite number",
            number(v)
        )))
    }
}

/// The largest width, length or radius of a shape target, in units of `sqrt(N)`: a target reaching
/// farther is judged on a grid wider than [`crate::spectrum::MAX_RES`] even at the smallest N, 2 (the
/// fit radius is twice its reach and [`Target::check_grid`] judges over twice the fit radius:
/// `4 · 1024 · sqrt(2) ≈ 5793 > 8192 / 2` cells); a width beyond it is wider than any grid. The
/// shipped targets stay below 2.
pub const MAX_SIZE: f64 = 1024.0;

/// A width, length or radius `v` of key `name`: finite, in `[0, MAX_SIZE]`.
fn size(name: &str, v: f64) -> Result<()> {
    finite(name, v)?;
    if !(0.0..=MAX_SIZE).contains(&v) {
        return Err(Error::Input(format!(
            "target parameter '{name}' is {}; it is a width or radius in units of sqrt(N) and must lie in [0, {MAX_SIZE}] (the shipped targets stay at or below 2)",
            number(v)
        )));
    }
    Ok(())
}

/// A slope of a dark line is a shear: at most [`MAX_SHEAR`] in magnitude, as for the variance target
/// and the integrands.
fn max_shear(name: &str, v: f64) -> Result<()> {
    if v.abs() > MAX_SHEAR {
        return Err(Error::Input(format!(
            "target parameter '{name}' is {}; give a finite shear of magnitude at most {MAX_SHEAR:e}",
            number(v)
        )));
    }
    Ok(())
}

fn dark_weight(w: Option<f64>) -> Result<f64> {
    let w = w.unwrap_or(DEFAULT_DARK_WEIGHT);
    finite("dark_weight", w)?;
    if !(w > 0.0 && w <= MAX_DARK_WEIGHT) {
        return Err(Error::Input(format!(
            "target parameter 'dark_weight' is {}; give a number > 0 and at most {MAX_DARK_WEIGHT:e} (larger weights overflow the solver's line search)",
            number(w)
        )));
    }
    Ok(w)
}

fn falloff(a: Option<f64>) -> Result<f64> {
    let a = a.unwrap_or(0.0);
    finite("falloff", a)?;
    if !(0.0..=4.0).contains(&a) {
        return Err(Error::Input(format!(
            "target parameter 'falloff' is {}; it is an exponent of |k| and must lie in [0, 4]",
            number(a)
        )));
    }
    Ok(a)
}

impl Target {
    /// Reads and checks a target file. Unknown keys, non-finite numbers, negative widths and radii,
    /// `s0 > s1` and unreadable images are errors (`Error::Input`) naming the problem. A shipped
    /// target's path (`targets/hairline.toml`, ...) with no file there is read from the copy built
    /// into the binary ([`BUILT_IN`]).
    pub fn load(path: &Path) -> Result<Self> {
        let missing = std::fs::symlink_metadata(path)
            .is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
        let text = match built_in(path) {
            Some(text) if missing => text.to_string(),
            _ => crate::input::read_text(path, "target file")?,
        };
        let mut target = Self::parse(&text).map_err(|e| match e {
            Error::Input(m) => Error::Input(format!("{}: {m}", path.display())),
            other => other,
        })?;
        if let Target::Image(img) = &mut target {
            let dir = path.parent().unwrap_or(Path::new("."));
            let file = dir.join(&img.file);
            // The image's own errors name it; say first which target file refers to it.
            let (pixels, shape) = read_image(&file).map_err(|e| match e {
                Error::Input(m) => Error::Input(format!("{}: its image: {m}", path.display())),
                other => other,
            })?;
            img.pixels = pixels;
            img.shape = shape;
        }
        Ok(target)
    }

    /// Parses and checks a target from TOML text. Image pixels are not read (see [`Target::load`]).
    ///
    /// The text is read as a TOML table first (a syntax error names its line and column), then its
    /// `kind`'s keys are read from the table directly rather than through serde's tagged enum, which
    /// would drop the name of a key whose value has the wrong type: that error names the key and its
    /// line.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = |why: &str| {
            Error::Input(format!(
                "not a valid target (a target file has kind = {} and that kind's keys; see targets/*.toml): {why}",
                KINDS.map(|k| format!("\"{k}\"")).join(" | ")
            ))
        };
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| bad(e.to_string().trim_end()))?;
        let kind = match table.remove("kind") {
            Some(toml::Value::String(kind)) => kind,
            Some(other) => return Err(bad(&format!("kind = {other} is not a string"))),
            None => return Err(bad("it has no kind key")),
        };
        let keys = toml::Value::Table(table);
        let target = match kind.as_str() {
            "hairline" => Hairline::deserialize(keys).map(Target::Hairline),
            "double-wedge" => DoubleWedge::deserialize(keys).map(Target::DoubleWedge),
            "blue-noise" => BlueNoise::deserialize(keys).map(Target::BlueNoise),
            "image" => Image::deserialize(keys).map(Target::Image),
            "variance" => Variance::deserialize(keys).map(Target::Variance),
            other => return Err(bad(&format!("unknown kind \"{other}\""))),
        }
        .map_err(|e| bad(&located(&e.to_string(), text)))?;
        target.validate()?;
        Ok(match target {
            Target::Variance(v) => Target::Variance(v.resolved()),
            shape => shape,
        })
    }

    /// Checks every parameter (finite, widths and radii `≥ 0`, `s0 ≤ s1`).
    pub fn validate(&self) -> Result<()> {
        match self {
            Target::Hairline(h) => {
                finite("shear", h.shear)?;
                max_shear("shear", h.shear)?;
                size("half_width", h.half_width)?;
                size("opening", h.opening)?;
                size("length", h.length)?;
                size("inner_radius", h.inner_radius)?;
                dark_weight(h.dark_weight)?;
                falloff(h.falloff)?;
            }
            Target::DoubleWedge(d) => {
                finite("s0", d.s0)?;
                finite("s1", d.s1)?;
                if d.s0 > d.s1 {
                    return Err(Error::Input(format!(
                        "target has s0 = {} > s1 = {}; the wedge lies between the slopes s0 <= s1, swap them",
                        number(d.s0),
                        number(d.s1)
                    )));
                }
                if d.s0 == d.s1 {
                    return Err(Error::Input(format!(
                        "target has s0 = s1 = {}, a single line, not a wedge; use kind = \"hairline\" with shear = {} or widen [s0, s1]",
                        number(d.s0),
                        number(d.s0)
                    )));
                }
                max_shear("s0", d.s0)?;
                max_shear("s1", d.s1)?;
                size("radius", d.radius)?;
                size("margin", d.margin)?;
                size("inner_radius", d.inner_radius)?;
                dark_weight(d.dark_weight)?;
                falloff(d.falloff)?;
            }
            Target::BlueNoise(b) => {
                size("radius", b.radius)?;
                dark_weight(b.dark_weight)?;
                falloff(b.falloff)?;
            }
            Target::Image(i) => {
                size("extent", i.extent)?;
                if i.extent == 0.0 {
                    return Err(Error::Input(
                        "target parameter 'extent' is 0; the image must cover a positive range of normalized frequency".into(),
                    ));
                }
                dark_weight(i.dark_weight)?;
                falloff(i.falloff)?;
            }
            Target::Variance(v) => v.validate()?,
        }
        Ok(())
    }

    /// The kind's name, as in the file.
    pub fn kind(&self) -> &'static str {
        match self {
            Target::Hairline(_) => "hairline",
            Target::DoubleWedge(_) => "double-wedge",
            Target::BlueNoise(_) => "blue-noise",
            Target::Image(_) => "image",
            Target::Variance(_) => "variance",
        }
    }

    /// How far the target's features reach, in normalized frequency `ν`.
    pub fn extent(&self) -> f64 {
        match self {
            Target::Hairline(h) => h.length.max(h.inner_radius),
            Target::DoubleWedge(d) => d.radius.max(d.inner_radius),
            Target::BlueNoise(b) => b.radius,
            Target::Image(i) => i.extent * std::f64::consts::SQRT_2,
            Target::Variance(v) => v.extent,
        }
    }

    /// The weight of the dark region's error in use: the file's `dark_weight`, or
    /// [`DEFAULT_DARK_WEIGHT`] when left out (and for a variance target, which has no dark region).
    pub fn dark_weight(&self) -> f64 {
        let w = match self {
            Target::Hairline(h) => h.dark_weight,
            Target::DoubleWedge(d) => d.dark_weight,
            Target::BlueNoise(b) => b.dark_weight,
            Target::Image(i) => i.dark_weight,
            Target::Variance(_) => None,
        };
        w.unwrap_or(DEFAULT_DARK_WEIGHT)
    }

    /// The exponent of the dark region's low-frequency emphasis in use: the file's `falloff`, or 0
    /// when left out (and for a variance target).
    pub fn falloff(&self) -> f64 {
        let a = match self {
            Target::Hairline(h) => h.falloff,
            Target::DoubleWedge(d) => d.falloff,
            Target::BlueNoise(b) => b.falloff,
            Target::Image(i) => i.falloff,
            Target::Variance(_) => None,
        };
        a.unwrap_or(0.0)
    }

    /// `T` at the normalized frequency `(ν1, ν2) = k / sqrt(N)` (1 everywhere for a variance target,
    /// which has no shape).
    pub fn value(&self, nu1: f64, nu2: f64) -> f64 {
        let r = nu1.hypot(nu2);
        let dark = match self {
            Target::Hairline(h) => {
                // Perpendicular distance from (ν1, ν2) to the line ν2 = s ν1.
                let dist = (nu2 - h.shear * nu1).abs() / h.shear.hypot(1.0);
                (at_most(dist, h.half_width + h.opening * r) && at_most(r, h.length))
                    || below(r, h.inner_radius)
            }
            Target::DoubleWedge(d) => {
                let near = |s: f64| at_most((nu2 - s * nu1).abs() / s.hypot(1.0), d.margin);
                // Between the edges' lines: ν2 − s ν1 changes sign across each, so the slopes are
                // compared as distances, with the same allowance for rounding.
                let inside = (nu1 != 0.0 && {
                    let (lo, hi) = (
                        (nu2 - d.s0 * nu1) * nu1.signum(),
                        (d.s1 * nu1 - nu2) * nu1.signum(),
                    );
                    at_most(0.0, lo) && at_most(0.0, hi)
                }) || near(d.s0)
                    || near(d.s1);
                (inside && at_most(r, d.radius)) || below(r, d.inner_radius)
            }
            Target::BlueNoise(b) => below(r, b.radius),
            // Symmetrized so that W and T are even in k, as the loss's gradient assumes.
            Target::Image(i) => {
                return 0.5 * (image_value(i, nu1, nu2) + image_value(i, -nu1, -nu2))
            }
            // No shape: the loss is the predicted variance.
            Target::Variance(_) => false,
        };
        if dark {
            0.0
        } else {
            1.0
        }
    }

    /// Lays the target out for `n` points: grid size, `T`, weights and dark mask. Fails with
    /// `Error::Input` when the dark region holds more than [`REACH`]` × N` cells, naming the reachable
    /// fraction; below [`SMALL_N`] points, a shape's refusal names the smallest larger N it builds at.
    pub fn grid(&self, n: usize) -> Result<TargetGrid> {
        self.grid_within(n, self.fit_radius(n))
            .map_err(|e| match e {
                Error::Input(m) if n < SMALL_N && !matches!(self, Target::Variance(_)) => {
                    match (n + 1..=4 * SMALL_N)
                        .find(|&larger| self.grid_within(larger, self.fit_radius(larger)).is_ok())
                    {
                        Some(smallest) => Error::Input(format!(
                        "{m}; the smallest N above {n} at which this target builds is {smallest}"
                    )),
                        None => Error::Input(m),
                    }
                }
                other => other,
            })
    }

    /// The radius of the grid [`Target::grid`] fits at `n` points, in frequency cells: a margin
    /// around the features so the energy they push out is kept flat too; a variance target's extent.
    fn fit_radius(&self, n: usize) -> f64 {
        let sqrt_n = (n as f64).sqrt();
        let ext = self.extent() * sqrt_n;
        match self {
            Target::Variance(_) => ext.max(4.0),
            _ => (2.0 * ext).max(ext + sqrt_n).max(4.0),
        }
    }

    /// The area of the dark region in normalized frequency, i.e. its expected number of frequency
    /// cells in units of `N` (an upper bound where parts overlap). A band lies within the disc of
    /// its length (a wedge within its radius), so its area is at most that disc's: a wide opening or
    /// margin darkens no more than the whole disc.
    fn dark_area(&self) -> f64 {
        use std::f64::consts::PI;
        match self {
            Target::Hairline(h) => {
                (4.0 * h.half_width * h.length + 2.0 * h.opening * h.length.powi(2))
                    .min(PI * h.length.powi(2))
                    + PI * h.inner_radius.powi(2)
            }
            Target::DoubleWedge(d) => {
                ((d.s1.atan() - d.s0.atan()) * d.radius.powi(2) + 4.0 * d.margin * d.radius)
                    .min(PI * d.radius.powi(2))
                    + PI * d.inner_radius.powi(2)
            }
            Target::BlueNoise(b) => PI * b.radius.powi(2),
            Target::Image(i) => {
                let dark = i.pixels.iter().filter(|&&v| v <= DARK_LEVEL).count();
                dark as f64 / i.pixels.len().max(1) as f64 * (2.0 * i.extent).powi(2)
            }
            Target::Variance(_) => 0.0,
        }
    }

    /// What the target asks above `P = 1` at `n` points, integrated over normalized frequency: its
    /// expected [`peak_excess`] over the cells, in units of `N` (an image's peaks; 0 for the shapes).
    fn peak_area(&self, n: usize) -> f64 {
        match self {
            Target::Image(i) => {
                let lit = i.pixels.iter().copied().filter(|&v| v > DARK_LEVEL);
                peak_excess(lit, n) / i.pixels.len().max(1) as f64 * (2.0 * i.extent).powi(2)
            }
            _ => 0.0,
        }
    }

    /// The grid the fit is judged on: twice the fit radius of [`Target::grid`], so that energy pushed
    /// just beyond the optimized range is seen (a variance target: at most the radius its largest
    /// sampling grid allows, [`variance::MAX_SAMPLES`]` / 8 − 1` cells).
    pub fn check_grid(&self, n: usize) -> Result<TargetGrid> {
        let fit = self.grid(n)?.fit_radius;
        let wide = match self {
            Target::Variance(_) => (2.0 * fit)
                .min((variance::MAX_SAMPLES / 8 - 1) as f64)
                .max(fit),
            _ => 2.0 * fit,
        };
        self.grid_within(n, wide)
    }

    /// Like [`Target::grid`] but with the fit radius (in frequency cells) given: used to judge a fit
    /// beyond the radius it was optimized over.
    fn grid_within(&self, n: usize, fit_radius: f64) -> Result<TargetGrid> {
        if n < 2 {
            return Err(Error::Usage(format!(
                "-n {n}: an optimized set needs at least 2 points"
            )));
        }
        // A dark disc is symmetric: the smallest that holds a cell holds the four at |k| = 1, so no
        // radius suits fewer points than that (a smaller one darkens nothing, a larger one too much).
        if matches!(self, Target::BlueNoise(_)) && REACH * (n as f64) < 4.0 {
            return Err(Error::Input(format!(
                "N = {n} is too small for a blue-noise target: its smallest dark disc holds the 4 frequency cells at |k| = 1, and {n} points can darken only about {}",
                number(REACH * n as f64),
            )));
        }
        // Refuse hopeless targets before laying out a grid that may not fit in memory.
        let estimate = self.dark_area() * n as f64;
        let peaks = self.peak_area(n) * n as f64;
        if estimate > 4.0 * (REACH * n as f64 + peaks) {
            return Err(self.beyond_reach(n, Cells::Estimated(estimate), peaks));
        }
        let sqrt_n = (n as f64).sqrt();
        let largest = (crate::spectrum::MAX_RES / 2 - 1) as f64;
        if !(fit_radius.is_finite() && fit_radius <= largest) {
            // The keys that set the reach (see `extent`).
            let keys = match self {
                Target::Hairline(_) => "its length or inner_radius",
                Target::DoubleWedge(_) => "its radius or inner_radius",
                Target::BlueNoise(_) => "its radius",
                Target::Image(_) | Target::Variance(_) => "its extent",
            };
            return Err(Error::Input(format!(
                "the target reaches |k| = {fit_radius:.3e} frequency cells at N = {n}, beyond the largest grid ({} cells, |k| <= {largest}); lower {keys} (in units of sqrt(N)) or N",
                crate::spectrum::MAX_RES
            )));
        }
        let res = 2 * (fit_radius.ceil() as usize) + 2;
        if let Target::Variance(v) = self {
            return variance_grid(v, n, res, fit_radius);
        }
        let half = (res / 2) as i64;
        let mut target = vec![1.0; res * res];
        let mut dark = vec![false; res * res];
        let mut inside = vec![false; res * res];
        for i in 0..res {
            for j in 0..res {
                let idx = i * res + j;
                let (k1, k2) = frequency(idx, res);
                let t = self.value(k1 as f64 / sqrt_n, k2 as f64 / sqrt_n);
                target[idx] = t;
                let r = (k1 as f64).hypot(k2 as f64);
                let paired = k1 > -half && k2 > -half;
                if paired && (k1, k2) != (0, 0) && r <= fit_radius {
                    inside[idx] = true;
                    dark[idx] = t <= DARK_LEVEL;
                }
            }
        }
        let dark_cells = dark.iter().filter(|&&d| d).count();
        if dark_cells == 0 {
            return Err(self.nothing_dark(n));
        }
        // Peaks pay for darkness: what the target asks above P = 1, net, over the cells inside the
        // fit radius that are not dark (an image's peaks, each at most P = N; 0 for the shapes), adds
        // to the cells N points can darken. Noise about 1 adds about nothing.
        let surplus = peak_excess(
            (0..res * res)
                .filter(|&idx| inside[idx] && !dark[idx])
                .map(|idx| target[idx]),
            n,
        );
        if dark_cells as f64 > REACH * n as f64 + surplus {
            return Err(self.beyond_reach(n, Cells::Counted(dark_cells), surplus));
        }
        // The rim: non-dark cells next to a dark one (8-neighbourhood), where the energy pushed out of
        // the dark region piles up first. They get the dark cells' weight.
        let rim: Vec<bool> = (0..res * res)
            .map(|idx| {
                let (i, j) = ((idx / res) as i64, (idx % res) as i64);
                inside[idx]
                    && !dark[idx]
                    && (-1..=1).any(|di| {
                        (-1..=1).any(|dj| {
                            let (a, b) = (i + di, j + dj);
                            a >= 0
                                && b >= 0
                                && a < res as i64
                                && b < res as i64
                                && dark[(a * res as i64 + b) as usize]
                        })
                    })
            })
            .collect();
        let rim_cells = rim.iter().filter(|&&r| r).count();
        let others = inside.iter().filter(|&&c| c).count() - dark_cells - rim_cells;
        // Dark and rim cells share the weight `dark_weight` in proportion to `(|k| / sqrt(N))^(−α)`.
        let alpha = self.falloff();
        let emphasis = |idx: usize| {
            let (k1, k2) = frequency(idx, res);
            ((k1 as f64).hypot(k2 as f64) / sqrt_n).powf(-alpha)
        };
        let dark_total: f64 = (0..res * res)
            .filter(|&idx| dark[idx] || rim[idx])
            .map(emphasis)
            .sum();
        let wd = self.dark_weight();
        let weight = (0..res * res)
            .map(|idx| {
                if !inside[idx] {
                    0.0
                } else if dark[idx] || rim[idx] {
                    wd * emphasis(idx) / dark_total
                } else {
                    1.0 / others.max(1) as f64
                }
            })
            .collect();
        let mut grid = TargetGrid {
            n,
            res,
            fit_radius,
            target,
            weight,
            dark,
            dark_cells,
            rings: Vec::new(),
            variance: false,
        };
        let annuli = grid.annuli();
        grid.rings = (0..res * res)
            .map(|idx| {
                let (k1, k2) = frequency(idx, res);
                let r = (k1 as f64).hypot(k2 as f64).round() as usize;
                (grid.weight[idx] > 0.0 && !grid.dark[idx] && r < annuli).then_some(r as u32)
            })
            .collect();
        Ok(grid)
    }
}

/// The grid of a variance target: `W = weight · |ĝ|² / Σ |ĝ|²` over the paired cells `0 < |k| ≤`
/// `fit_radius`, 0 elsewhere (see [`variance`]).
fn variance_grid(v: &Variance, n: usize, res: usize, fit_radius: f64) -> Result<TargetGrid> {
    let power = v.spectrum(res)?;
    let half = (res / 2) as i64;
    let inside = |idx: usize| {
        let (k1, k2) = frequency(idx, res);
        k1 > -half && k2 > -half && (k1, k2) != (0, 0) && (k1 as f64).hypot(k2 as f64) <= fit_radius
    };
    let total: f64 = (0..res * res)
        .filter(|&i| inside(i))
        .map(|i| power[i])
        .sum();
    let scale = v.weight() / total;
    if !(total > 0.0 && scale.is_finite()) {
        return Err(Error::Input(format!(
            "target integrand '{}' shows no energy at 0 < |k| <= {fit_radius:.1} (N = {n}) on the grid it is sampled on: it is constant there or its features are smaller than the grid's cells, so no set can lower its variance; give a larger feature, a larger extent or another integrand",
            v.integrand
        )));
    }
    let weight = (0..res * res)
        .map(|i| if inside(i) { power[i] * scale } else { 0.0 })
        .collect();
    Ok(TargetGrid {
        n,
        res,
        fit_radius,
        target: vec![1.0; res * res],
        weight,
        dark: vec![false; res * res],
        dark_cells: 0,
        rings: vec![None; res * res],
        variance: true,
    })
}

impl Target {
    /// A shape target whose dark region holds no frequency cell at `n`: there is nothing to darken,
    /// and its dark mean would average over nothing.
    fn nothing_dark(&self, n: usize) -> Error {
        let keys = match self {
            Target::Hairline(_) => "length (with half_width or opening) or inner_radius",
            Target::DoubleWedge(_) => "radius or inner_radius",
            Target::BlueNoise(_) => "radius",
            _ => {
                "extent, or darken more of the image (it is made symmetric, as a power spectrum is: a cell reads the mean \
                 of the image at k and at -k, so a pixel dark where its mirror is lit is not dark)"
            }
        };
        Error::Input(format!(
            "the {} target darkens no frequency cell at N = {n}: its dark region reaches no cell (the nearest \
             lies at normalized frequency 1 / sqrt(N) = {:.3}); raise {keys}, or use a larger N",
            self.kind(),
            1.0 / (n as f64).sqrt()
        ))
    }

    fn beyond_reach(&self, n: usize, cells: Cells, surplus: f64) -> Error {
        let (dark_cells, about) = match cells {
            Cells::Estimated(c) => (c, "about "),
            Cells::Counted(c) => (c as f64, ""),
        };
        let reach = REACH * n as f64 + surplus;
        let paid = if surplus > 0.0 {
            format!(
                " ({} for its N, and {} that its peaks above P = 1 pay for)",
                number((REACH * n as f64).round()),
                number(surplus.round())
            )
        } else {
            String::new()
        };
        let fix = match self {
            Target::Hairline(_) => {
                "shorten length, or lower half_width, opening or inner_radius".to_string()
            }
            Target::DoubleWedge(_) => {
                "narrow s0 .. s1, shorten radius, or lower margin or inner_radius".to_string()
            }
            Target::BlueNoise(_) => "lower radius".to_string(),
            Target::Image(_) => format!(
                "lower extent, or lighten the image (cells at or below {DARK_LEVEL} count as dark; a \
                 spectrum measured from a --latin table is dark along its k1 axis, and those cells \
                 count too)"
            ),
            Target::Variance(_) => unreachable!("a variance target has no dark region"),
        };
        Error::Input(format!(
            "the {} target darkens {about}{} frequency cells at N = {n}, but {n} points can darken only about {reach:.0}{paid}: reachable fraction {}. Shrink its dark region by that factor in area: {fix}",
            self.kind(),
            number(dark_cells.round()),
            crate::output::plot::short_number(reach / dark_cells)
        ))
    }
}

/// The net excess above `P = 1` of the values `t` of a target's cells that are not dark, each taken
/// at most `N` (no set of `n` points has a larger `P`): `Σ (min(t, N) − 1)`, or 0 where the cells
/// ask for less than 1 on average.
fn peak_excess(t: impl Iterator<Item = f64>, n: usize) -> f64 {
    t.map(|t| t.min(n as f64) - 1.0).sum::<f64>().max(0.0)
}

/// The shipped targets that need no other file, built into the binary under their paths in the
/// repository: [`Target::load`] reads one of these paths that does not exist from here, so the
/// default compare suite (whose tables are `targets/*.toml`) runs from any folder. A file at the
/// path is read instead.
const BUILT_IN: [(&str, &str); 8] = [
    (
        "targets/blue-noise.toml",
        include_str!("../../targets/blue-noise.toml"),
    ),
    (
        "targets/double-wedge.toml",
        include_str!("../../targets/double-wedge.toml"),
    ),
    (
        "targets/edge-lattice-mixture.toml",
        include_str!("../../targets/edge-lattice-mixture.toml"),
    ),
    (
        "targets/edge-robust.toml",
        include_str!("../../targets/edge-robust.toml"),
    ),
    (
        "targets/fan-lattice.toml",
        include_str!("../../targets/fan-lattice.toml"),
    ),
    (
        "targets/fan-variance.toml",
        include_str!("../../targets/fan-variance.toml"),
    ),
    (
        "targets/hairline.toml",
        include_str!("../../targets/hairline.toml"),
    ),
    (
        "targets/widened-hairline.toml",
        include_str!("../../targets/widened-hairline.toml"),
    ),
];

/// How many frequency cells a target darkens: estimated from its shape's area (before a grid is laid
/// out) or counted on the grid.
enum Cells {
    Estimated(f64),
    Counted(usize),
}

/// The built-in text of the shipped target at `path` (written as in [`BUILT_IN`], `./` allowed).
fn built_in(path: &Path) -> Option<&'static str> {
    let path = path.strip_prefix(".").unwrap_or(path);
    BUILT_IN
        .iter()
        .find(|(name, _)| path == Path::new(name))
        .map(|(_, text)| *text)
}

fn image_value(img: &Image, nu1: f64, nu2: f64) -> f64 {
    let [rows, cols] = img.shape;
    if rows == 0 || cols == 0 {
        return 1.0;
    }
    let e = img.extent;
    // A frequency on a pixel's left edge (a spectrum of K bins written with extent K/(2 sqrt N) puts
    // every k there) may be computed a rounding below it: positions within PIXEL_EDGE of an edge
    // count as on it, so each k reads its own pixel, not its left neighbour.
    let fj = ((nu1 + e) / (2.0 * e) * cols as f64 + PIXEL_EDGE).floor();
    let fi = ((nu2 + e) / (2.0 * e) * rows as f64 + PIXEL_EDGE).floor();
    if fj < 0.0 || fi < 0.0 || fj >= cols as f64 || fi >= rows as f64 {
        return 1.0;
    }
    img.pixels[fi as usize * cols + fj as usize]
}

/// How close, in normalized frequency `ν = k / sqrt(N)`, a cell must be to a shape's edge to count as
/// on it: far above the rounding of `k / sqrt(N)` and of the distances computed from it (about 1e-13
/// for |ν| up to 10^3), far below a cell's width `1 / sqrt(N)`. Without it a cell exactly on an edge
/// (every dark cell of a hairline of zero width) fell in or out by the rounding of its N and slope.
const SHAPE_EDGE: f64 = 1e-12;

/// `x ≤ limit`, a cell on the edge counting as inside (see [`SHAPE_EDGE`]).
fn at_most(x: f64, limit: f64) -> bool {
    x <= limit + SHAPE_EDGE
}

/// `x < limit`, a cell on the edge counting as outside (see [`SHAPE_EDGE`]).
fn below(x: f64, limit: f64) -> bool {
    x < limit - SHAPE_EDGE
}

/// How close (in pixels) a frequency must be to a pixel's left or lower edge to count as on it: far
/// above the rounding of `(ν + extent) / (2 extent) · cols` (about 1e-13 for 10^4 pixels), far below
/// any real offset of a frequency inside a pixel.
const PIXEL_EDGE: f64 = 1e-9;

/// Reads a target image: a 2D npy array (`float64` or `float32`, row 0 at the lowest `ν2`) or an EXR
/// image (channel `Y`, else `R`, else its only one, several others being refused; top row at the
/// highest `ν2`, as `anisospec spectrum` writes spectra). Every value must be finite, `≥ 0` and at most
/// 2^27 (no set of points has a larger `P`).
fn read_image(path: &Path) -> Result<(Vec<f64>, [usize; 2])> {
    let bad = |why: String| {
        Error::Input(format!(
            "{}: not a usable target image ({why}); give a 2D float64 or float32 npy array, or an EXR image (its Y channel, else R, else its only channel), of values >= 0 (about 1 where the spectrum is flat)",
            path.display()
        ))
    };
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let (pixels, [rows, cols]) = if is_exr {
        crate::input::check_regular(path)?;
        if path.is_dir() {
            return Err(Error::Input(format!(
                "{}: the target image is a folder; name an EXR or npy file in the 'file' key (relative to the TOML file)",
                path.display()
            )));
        }
        if !path.is_file() {
            return Err(missing_image(path));
        }
        let (top_first, shape) = crate::output::image::read_exr_channel(path).map_err(bad)?;
        (
            crate::output::image::spectrum_image_rows(&top_first, shape[1]),
            shape,
        )
    } else {
        read_npy_image(path, &bad)?
    };
    if rows == 0 || cols == 0 {
        return Err(bad("it is empty".into()));
    }
    // P = |F|²/N never exceeds N, and a 2D set holds at most 2^27 points: a larger value is out of
    // any set's reach (and its squared error in the loss could overflow).
    let largest = (crate::points::MAX_COORDINATES / 2) as f64;
    if let Some((at, v)) = pixels
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite() || **v < 0.0 || **v > largest)
    {
        // Named as the file holds it: an EXR's rows count from the top, an npy's from row 0.
        let (row, col) = (at / cols, at % cols);
        let place = if is_exr {
            format!(
                "the pixel in row {} from the top, column {col},",
                rows - 1 - row
            )
        } else {
            format!("the value at [{row}, {col}]")
        };
        let why = if *v > largest {
            format!(
                ", above 2^27 = {}: a spectrum P = |F|²/N is at most N, a 2D set holds at most 2^27 points, and P averages about 1 at high frequencies",
                number(largest)
            )
        } else {
            String::new()
        };
        return Err(bad(format!("{place} is {}{why}", number(*v))));
    }
    Ok((pixels, [rows, cols]))
}

/// The refusal of a target image file that does not exist.
fn missing_image(path: &Path) -> Error {
    Error::Input(format!(
        "{}: the target image does not exist; check the 'file' key (relative to the TOML file)",
        path.display()
    ))
}

/// The values and `[rows, cols]` of a 2D npy array of `float64` or `float32`, in either order.
fn read_npy_image(path: &Path, bad: &dyn Fn(String) -> Error) -> Result<(Vec<f64>, [usize; 2])> {
    // At most 1 GiB of values (2^27 float64 or 2^28 float32 pixels; an 8192 x 8192 spectrum is
    // 2^26) and the header.
    let file = std::fs::File::open(path).map_err(|e| match e.kind() {
        // As for an EXR image: the fix is in the target's 'file' key.
        std::io::ErrorKind::NotFound => missing_image(path),
        _ => Error::read_input(path, e),
    })?;
    let limit = (1u64 << 30) + (1 << 20);
    let size = file
        .metadata()
        .map_err(|e| Error::read_input(path, e))?
        .len();
    if size > limit {
        return Err(bad(format!(
            "{size} bytes, more than 1 GiB of values (2^27 float64 or 2^28 float32 pixels)"
        )));
    }
    let bytes = crate::input::read_npy_bytes(file, path, limit)?.map_err(bad)?;
    let (shape, pixels) = crate::points::io::parse_npy_array(&bytes, true).map_err(bad)?;
    let [rows, cols] = shape[..] else {
        return Err(bad(format!("shape {shape:?}")));
    };
    Ok((pixels, [rows, cols]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bad value of an image target is named where the file holds it (an EXR's rows from the top,
    /// an npy's indices), and an EXR of several channels none of which is Y or R is refused.
    #[test]
    fn image_errors_name_the_files_own_places() {
        let dir = tempfile::tempdir().unwrap();
        let mut values = vec![0.5f64; 4 * 3];
        values[3 + 2] = f64::NAN; // row 1, column 2 of a 4 x 3 image
        let npy = dir.path().join("t.npy");
        crate::output::write_npy(&npy, &[4, 3], &values).unwrap();
        let e = read_image(&npy).unwrap_err().to_string();
        assert!(e.contains("the value at [1, 2] is NaN"), "{e}");
        let exr = dir.path().join("t.exr");
        let f32s: Vec<f32> = values.iter().map(|&v| v as f32).collect();
        crate::output::image::write_exr(&exr, 3, 4, &[("Y", f32s.clone())]).unwrap();
        let e = read_image(&exr).unwrap_err().to_string();
        assert!(e.contains("row 1 from the top, column 2, is NaN"), "{e}");
        let two = dir.path().join("two.exr");
        crate::output::image::write_exr(&two, 3, 4, &[("A", f32s.clone()), ("B", f32s)]).unwrap();
        let e = read_image(&two).unwrap_err().to_string();
        assert!(e.contains("channels A, B and none named Y or R"), "{e}");
        // Beyond any set's reach (3e38 stuck the loss at 3e78; 1e300 made it inf): refused.
        values[3 + 2] = 3e38;
        crate::output::write_npy(&npy, &[4, 3], &values).unwrap();
        let e = read_image(&npy).unwrap_err().to_string();
        assert!(
            e.contains("the value at [1, 2] is 3e38, above 2^27 = 134217728:"),
            "{e}"
        );
        values[3 + 2] = (1u64 << 27) as f64;
        crate::output::write_npy(&npy, &[4, 3], &values).unwrap();
        assert!(read_image(&npy).is_ok());
    }

    #[test]
    fn parse_rejects_bad_files() {
        let ok = "kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 1.5\n";
        assert!(Target::parse(ok).is_ok());
        let unknown = format!("{ok}colour = 3\n");
        assert!(Target::parse(&unknown).is_err());
        let swapped = "kind = \"double-wedge\"\ns0 = 0.7\ns1 = 0.3\nradius = 1.5\n";
        assert!(Target::parse(swapped)
            .unwrap_err()
            .to_string()
            .contains("s0"));
        let nan = "kind = \"blue-noise\"\nradius = nan\n";
        assert!(Target::parse(nan)
            .unwrap_err()
            .to_string()
            .contains("finite"));
        let neg = "kind = \"hairline\"\nshear = 0.5\nhalf_width = -0.1\nlength = 1\n";
        assert!(Target::parse(neg)
            .unwrap_err()
            .to_string()
            .contains("half_width"));
    }

    /// A key of the wrong type, an unknown key and a repeated key name the key and its line; a bad
    /// or missing kind says so.
    #[test]
    fn parse_errors_name_the_key_and_its_line() {
        let cases = [
            (
                "kind = \"blue-noise\"\n# radius in sqrt(N) cells\nradius = \"0.3\"\n",
                "expected f64 (key radius, line 3)",
            ),
            (
                "kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 1.5\ncolour = 3\n",
                "unknown field `colour`",
            ),
            (
                "kind = \"double-wedge\"\ns0 = 0.3\ns1 = 0.7\nradius = 1.5\ncolour = 3\n",
                "(key colour, line 5)",
            ),
            (
                "kind = \"blue-noise\"\nradius = 0.3\nradius = 0.4\n",
                "line 3",
            ),
            ("kind = 3\nradius = 0.3\n", "kind = 3 is not a string"),
            ("kind = \"hairlin\"\n", "unknown kind \"hairlin\""),
            ("radius = 0.3\n", "no kind key"),
            (
                "kind = \"blue-noise\"\nradius = 0.3\n[falloffs]\na = 1\n[falloff]\nb = 2\n",
                "(key falloff, line 5)",
            ),
        ];
        for (text, needle) in cases {
            let m = Target::parse(text).unwrap_err().to_string();
            assert!(m.contains(needle), "{text:?}: '{m}' lacks '{needle}'");
        }
    }

    #[test]
    fn huge_sizes_are_refused_by_key_and_echoed_compactly() {
        let hairline = "kind = \"hairline\"\nshear = 0.5\n";
        for (key, value, rest) in [
            ("half_width", "1e300", "length = 1"),
            ("inner_radius", "1e300", "half_width = 0.1\nlength = 1"),
            ("length", "1025", "half_width = 0.1"),
        ] {
            let text = format!("{hairline}{key} = {value}\n{rest}\n");
            let e = Target::parse(&text).unwrap_err();
            assert!(matches!(e, Error::Input(_)), "{key}: {e}");
            let m = e.to_string();
            assert!(
                m.contains(&format!("'{key}' is {value};")) && m.contains("[0, 1024]"),
                "{key}: {m}"
            );
        }
        // The largest size allowed still gets advice that reads: a finite count and a fraction that
        // is not rounded to 0.
        let wide = Target::parse("kind = \"blue-noise\"\nradius = 1024\n").unwrap();
        let m = wide.grid(4).unwrap_err().to_string();
        assert!(
            m.contains("darkens about 13176795 frequency cells")
                && m.contains("fraction 3.036e-7."),
            "{m}"
        );
        // A reach beyond the largest grid names the keys that set it (a variance target's extent
        // was told to shorten a length or radius it does not have).
        for (text, keys) in [
            (
                "kind = \"variance\"\nintegrand = \"sheared:s=0.5\"\nshear = 0.5\nextent = 1e300\n",
                "lower its extent (in units of sqrt(N)) or N",
            ),
            (
                "kind = \"hairline\"\nshear = 0.5\nhalf_width = 0\nlength = 1024\n",
                "lower its length or inner_radius (in units of sqrt(N)) or N",
            ),
        ] {
            let m = Target::parse(text)
                .unwrap()
                .grid(64)
                .unwrap_err()
                .to_string();
            assert!(m.contains(keys), "{m}");
        }
        let e = Target::parse("kind = \"blue-noise\"\nradius = 0.5\ndark_weight = 1e300\n");
        assert!(e
            .unwrap_err()
            .to_string()
            .contains("'dark_weight' is 1e300;"));
    }

    #[test]
    fn dark_weight_is_bounded() {
        let with = |w: &str| {
            Target::parse(&format!(
                "kind = \"blue-noise\"\nradius = 0.5\ndark_weight = {w}\n"
            ))
        };
        assert!(with("20000").is_ok());
        assert!(with("1e6").is_ok());
        for bad in ["0", "-1", "1.5e6", "1e308"] {
            let e = with(bad).unwrap_err();
            assert!(matches!(e, Error::Input(_)), "{bad}: {e}");
            let m = e.to_string();
            assert!(
                m.contains("'dark_weight'") && m.contains("at most 1e6"),
                "{bad}: {m}"
            );
        }
    }

    /// A blue-noise disc of radius 0.5 (in units of sqrt(N)) darkens exactly the cells
    /// `0 < |k| < 0.5 sqrt(N)`, counted by enumeration: 192, 792 and 3204 at N = 256, 1024 and 4096
    /// (π R² − 1 = 200, 803, 3216; the cells on the circle, e.g. (8, 0) at N = 256, are not dark).
    /// Counting the circle's cells too gives 196 at N = 256 and fails.
    #[test]
    fn dark_area_scales_with_n() {
        let t = Target::parse("kind = \"blue-noise\"\nradius = 0.5\n").unwrap();
        for (n, cells) in [(256, 192), (1024, 792), (4096, 3204)] {
            let radius = 0.5 * (n as f64).sqrt();
            let m = radius as i64;
            let inside = (-m..=m)
                .flat_map(|a| (-m..=m).map(move |b| (a * a + b * b) as f64))
                .filter(|&q| q > 0.0 && q < radius * radius)
                .count();
            assert_eq!(inside, cells, "N = {n}: the enumeration");
            assert_eq!(t.grid(n).unwrap().dark_cells, cells, "N = {n}");
        }
        // A band or wedge wider than its disc darkens that disc, no more: reachable where the
        // disc is (before, an opening of 10 was estimated at 1280 cells and refused at N = 256).
        // They hold the blue-noise disc's cells and the 4 at |k| = 8 (r <= length against r < radius).
        for wide in [
            "kind = \"hairline\"\nshear = 0\nhalf_width = 0\nopening = 10\nlength = 0.5\n",
            "kind = \"double-wedge\"\ns0 = -0.2\ns1 = 0.2\nmargin = 10\nradius = 0.5\n",
        ] {
            let g = Target::parse(wide).unwrap().grid(256).unwrap();
            let disc = t.grid(256).unwrap();
            assert_eq!(g.dark_cells, disc.dark_cells + 4, "{wide}");
        }
        let too_dark = Target::parse("kind = \"blue-noise\"\nradius = 2\n").unwrap();
        let e = too_dark.grid(256).unwrap_err().to_string();
        assert!(e.contains("reachable fraction"), "{e}");
    }

    /// A hairline of zero width darkens exactly the cells on its line `k2 = s k1` (k ≠ 0) up to its
    /// length, whatever the rounding of `k / sqrt(N)`: before, at s = 0.3 it darkened 2, 8 or none of
    /// the 8 at N = 900, 1024 and 1000.
    #[test]
    fn cells_on_a_shapes_edge_count_whatever_the_rounding() {
        for (s, p, q) in [
            (0.3, 3, 10),
            (0.1, 1, 10),
            (0.7, 7, 10),
            (0.25, 1, 4),
            (0.5, 1, 2),
        ] {
            for n in [900usize, 1000, 1024] {
                let length = 1.5;
                let text = format!(
                    "kind = \"hairline\"\nshear = {s}\nhalf_width = 0\nlength = {length}\n"
                );
                let g = Target::parse(&text).unwrap().grid(n).unwrap();
                // The cells j (q, p) with 0 < |j| hypot(q, p) <= length sqrt(N), inside the grid.
                let reach = length * (n as f64).sqrt() / f64::from(p).hypot(f64::from(q));
                let half = (g.res / 2) as i64;
                let on_line = (1..=reach.floor() as i64)
                    .filter(|j| j * i64::from(q) < half && j * i64::from(p) < half)
                    .count()
                    * 2;
                assert_eq!(g.dark_cells, on_line, "s = {s}, N = {n}");
            }
        }
    }

    /// Below SMALL_N a refusal names the smallest larger N that builds, and that N does build while
    /// every N between does not: the fix it names works. Before, a blue-noise disc of radius 0.35 at
    /// N = 2 was told "use N >= 4", refused again up to N = 8.
    #[test]
    fn a_small_n_refusal_names_the_n_that_builds() {
        for (text, n, smallest) in [
            ("kind = \"blue-noise\"\nradius = 0.35\n", 2, 9),
            ("kind = \"blue-noise\"\nradius = 0.35\n", 4, 9),
            ("kind = \"blue-noise\"\nradius = 0.5\n", 2, 5),
            (
                "kind = \"hairline\"\nshear = 0.0\nhalf_width = 0.0625\nopening = 0.09\nlength = 1.27\ninner_radius = 0.35\n",
                3,
                4,
            ),
        ] {
            let t = Target::parse(text).unwrap();
            let m = t.grid(n).unwrap_err().to_string();
            assert!(
                m.ends_with(&format!(
                    "; the smallest N above {n} at which this target builds is {smallest}"
                )),
                "{text} N = {n}: {m}"
            );
            assert!((n + 1..smallest).all(|m| t.grid(m).is_err()), "{text}");
            t.grid(smallest).unwrap();
        }
    }

    /// An image target of `m × m` pixels over `±1` (a cell per pixel at N = 256), as if measured.
    fn measured_image(pixels: Vec<f64>, m: usize) -> Target {
        Target::Image(Image {
            file: PathBuf::from("measured.npy"),
            extent: 1.0,
            dark_weight: None,
            falloff: None,
            pixels,
            shape: [m, m],
        })
    }

    /// An image dark at k = (1, 0) alone is lit at its mirror (-1, 0): made even, it darkens no
    /// cell, and the refusal says why.
    #[test]
    fn a_one_sided_dark_pixel_is_not_dark() {
        let m = 32;
        let mut pixels = vec![1.0; m * m];
        pixels[16 * m + 17] = 0.0;
        let e = measured_image(pixels.clone(), m)
            .grid(256)
            .unwrap_err()
            .to_string();
        assert!(e.contains("darkens no frequency cell"), "{e}");
        assert!(e.contains("made symmetric"), "{e}");
        pixels[16 * m + 15] = 0.0;
        assert_eq!(measured_image(pixels, m).grid(256).unwrap().dark_cells, 2);
    }

    /// Cells asking for P above N are found (no set reaches them); a flat image asks for none.
    #[test]
    fn targets_above_n_are_found() {
        let m = 32;
        // Pixel (row i, column j) holds k = (j − 16, i − 16) at N = 256, extent 1. Dark at k = ±(1, 0).
        let mut pixels = vec![1.0; m * m];
        pixels[16 * m + 17] = 0.0;
        pixels[16 * m + 15] = 0.0;
        let flat = measured_image(pixels.clone(), m).grid(256).unwrap();
        assert_eq!(flat.above_reach(), None);
        // k = (4, 4) and (5, 4) ask for 1000; the image is made symmetric, so they and their mirrors
        // read 500.5, 4 cells in all.
        pixels[20 * m + 20] = 1000.0;
        pixels[20 * m + 21] = 1000.0;
        let peaks = measured_image(pixels, m).grid(256).unwrap();
        assert_eq!(peaks.above_reach(), Some((4, 500.5)));
    }

    /// A spectrum of K bins used as a target with extent K/(2 sqrt N) gives every frequency its own
    /// bin, whatever N (before, at N = 576 and K = 96, k1 = −17 read the pixel of −18: the position
    /// (ν + e)/(2e)·K fell a rounding below the integer).
    #[test]
    fn a_measured_spectrum_as_target_gives_each_frequency_its_own_bin() {
        for (n, k) in [
            (576usize, 96usize),
            (1024, 128),
            (300, 64),
            (4096, 256),
            (2000, 90),
        ] {
            let sqrt_n = (n as f64).sqrt();
            let Target::Image(mut img) = measured_image(Vec::new(), k) else {
                unreachable!()
            };
            img.extent = k as f64 / (2.0 * sqrt_n);
            img.pixels = (0..k * k).map(|p| p as f64).collect();
            let half = (k / 2) as i64;
            for k2 in -half..half {
                for k1 in -half..half {
                    let v = image_value(&img, k1 as f64 / sqrt_n, k2 as f64 / sqrt_n);
                    let want = ((k2 + half) * k as i64 + k1 + half) as f64;
                    assert_eq!(v, want, "N={n} K={k} k=({k1}, {k2})");
                }
            }
        }
    }

    /// An image dark on its whole disc (956 cells at N = 256, extent 1) is beyond N's reach, unless
    /// it asks for peaks that pay for it, as a lattice's spectrum does: each cell of P = p adds
    /// min(p, N) − 1 to the 256 cells N points darken alone. The cells on the image's edge |k| = 16
    /// read 0.5 (the image is made symmetric, and beyond its edge it is 1), −0.5 each: −63 in all.
    #[test]
    fn peaks_pay_for_darkness() {
        let image = |peak: f64, cells: &[(usize, usize)]| {
            let m = 32;
            let mut pixels = vec![0.0; m * m];
            for &(i, j) in cells {
                pixels[i * m + j] = peak;
            }
            measured_image(pixels, m)
        };
        let four = [(16, 24), (16, 8), (24, 16), (8, 16)];
        let e = image(1.0, &four).grid(256).unwrap_err().to_string();
        assert!(
            e.contains("can darken only about 256:") && e.contains("reachable fraction"),
            "{e}"
        );
        let e = image(150.0, &four).grid(256).unwrap_err().to_string();
        assert!(
            e.contains("about 789 (256 for its N, and 533 that its peaks above P = 1 pay for)"),
            "{e}"
        );
        let grid = image(250.0, &four).grid(256).unwrap();
        assert_eq!(grid.dark_cells, 956);
        // No peak pays beyond P = N: two cells of 1e7 pay 2 × 255 (less the edge's 63).
        let e = image(1e7, &four[..2]).grid(256).unwrap_err().to_string();
        assert!(e.contains("256 for its N, and 447 that its peaks"), "{e}");
    }

    /// Every shipped target that needs no image is built in, with its file's text, and nothing else.
    #[test]
    fn shipped_targets_without_an_image_are_built_in() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("targets");
        let mut names = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                let name = format!("targets/{}", path.file_name().unwrap().to_string_lossy());
                match Target::parse(&text).unwrap() {
                    Target::Image(_) => assert_eq!(built_in(Path::new(&name)), None, "{name}"),
                    _ => {
                        assert_eq!(built_in(Path::new(&name)), Some(text.as_str()), "{name}");
                        names.push(name);
                    }
                }
            }
        }
        assert_eq!(names.len(), BUILT_IN.len(), "{names:?}");
    }

    /// Noise about 1 pays for nothing: a dark disc of about 314 cells (radius 10 at N = 256) in cells
    /// alternating 0.5 and 1.62 (mean 1.06) is refused; counting only the cells above 1 would have
    /// let it through (0.62 for each of about 245 cells).
    #[test]
    fn noise_does_not_pay_for_darkness() {
        let m = 32;
        let pixels = (0..m * m)
            .map(|idx| {
                let (i, j) = ((idx / m) as f64 - 16.0, (idx % m) as f64 - 16.0);
                if i.hypot(j) < 10.0 {
                    0.0
                } else if idx % 2 == 0 {
                    0.5
                } else {
                    1.62
                }
            })
            .collect();
        let noisy = measured_image(pixels, m);
        let e = noisy.grid(256).unwrap_err().to_string();
        assert!(e.contains("reachable fraction"), "{e}");
    }
}
