//! Rendering the whole image with any 4D sampler, optionally sheared per pixel by the oracle, the
//! high-count reference image, and the MSE between them.
//!
//! Pixel `i = py × width + px` draws its set from `rng::stream(seed, i)` and its toroidal shift from
//! `rng::substream(seed, i, 1)`: the image is the same for a seed whatever the thread count. The shift
//! is applied to the pattern before the shear; both maps preserve the uniform measure, so every
//! estimate is unbiased.

use super::oracle::{PixelClass, PixelOracle};
use super::pixel::{check_ref_count, stratified_reference, RENDER_VERSION};
use super::scene::Scene;
use crate::error::{Error, Result};
use crate::points::shear::{shear_set_4d, ShearMode};
use crate::points::toroidal_shift;
use crate::rng;
use crate::samplers::{validate_n, Sampler};
use indicatif::ProgressBar;
use rand::Rng as _;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Default rays per pixel of the reference image: `2^16`.
pub const DEFAULT_IMAGE_REF_COUNT: usize = 1 << 16;

/// The `n` points (`[n, 4]` row-major) of realization `index` of `seed`: a set of `sampler` from
/// `stream(seed, index)`, shifted by a uniform toroidal shift from `substream(seed, index, 1)`, then,
/// if `shear` is `Some((sx, sy, mode))`, sheared by `sx` in `xu` and `sy` in `yv`.
pub fn pixel_points(
    sampler: &dyn Sampler,
    n: usize,
    seed: u64,
    index: u64,
    shear: Option<(f64, f64, ShearMode)>,
) -> Vec<f64> {
    let mut set = sampler.generate(n, &mut rng::stream(seed, index));
    let mut r = rng::substream(seed, index, 1);
    let shift: [f64; 4] = std::array::from_fn(|_| r.random::<f64>());
    toroidal_shift(&mut set, &shift);
    if let Some((sx, sy, mode)) = shear {
        shear_set_4d(&mut set, sx, sy, mode);
    }
    set
}

/// The estimate `(1/n) Σ f_p(x_j)` of pixel `(px, py)` over the points of [`pixel_points`].
pub fn estimate_pixel(scene: &Scene, px: usize, py: usize, points: &[f64]) -> f64 {
    let n = points.len() / 4;
    let sum: f64 = points
        .chunks_exact(4)
        .map(|p| scene.pixel_radiance(px, py, [p[0], p[1], p[2], p[3]]))
        .sum();
    sum / n as f64
}

/// What a pixel the oracle classes as a double wedge (several depths) is sheared by.
///
/// Measured (tests/render.rs, padded MJ at 256 spp, paired renders): shearing double-wedge pixels by
/// their centre depth lowers the whole image's MSE, most of those pixels being slanted surfaces and
/// out-of-focus occluders; but on an in-focus occluder edge in front of the defocused wall it raised
/// that pixel's MSE about 13× at N = 4096, because the shear undoes the pattern's `x` stratification
/// that the in-focus edge needs. Hence the choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum WedgeShear {
    /// The shear of the depth seen through the pixel and lens centres, like every other pixel
    /// (default: lower whole-image MSE).
    #[default]
    Centre,
    /// No shear on double-wedge pixels.
    None,
}

/// The per-pixel shears `(sx, sy)` the oracle gives: a hairline pixel's shear, 0 in focus, and for a
/// double wedge as `wedge` says.
pub fn oracle_shears(oracle: &[PixelOracle], wedge: WedgeShear) -> Vec<(f64, f64)> {
    oracle
        .iter()
        .map(|o| match (o.class, wedge) {
            (PixelClass::InFocus, _) | (PixelClass::DoubleWedge, WedgeShear::None) => (0.0, 0.0),
            _ => (o.sx, o.sy),
        })
        .collect()
}

/// Renders every pixel with `spp` points of `sampler` (4D), seeded by `seed`. With `shear`, the points
/// of pixel `i` are sheared by `shears[i] = (sx, sy)` in the given mode (one entry per pixel,
/// row-major; see [`oracle_shears`]). Returns the image row-major from the top row.
pub fn render_image(
    scene: &Scene,
    sampler: &dyn Sampler,
    spp: usize,
    seed: u64,
    shear: Option<(&[(f64, f64)], ShearMode)>,
    progress: &ProgressBar,
) -> Result<Vec<f64>> {
    if sampler.dims() != 4 {
        return Err(Error::Usage(format!(
            "the renderer needs a 4D sampler (x, y, u, v), but {} makes {}D points; use a 4D sampler such as padded-mj",
            sampler.name(),
            sampler.dims()
        )));
    }
    validate_n(sampler, spp)?;
    let (w, h) = (scene.width(), scene.height());
    if let Some((o, _)) = shear {
        if o.len() != w * h {
            return Err(Error::Input(format!(
                "{} shears were given but the image has {w}x{h} pixels",
                o.len()
            )));
        }
    }
    let rows: Vec<Vec<f64>> = (0..h)
        .into_par_iter()
        .map(|py| {
            let row = (0..w)
                .map(|px| {
                    let i = py * w + px;
                    let s = shear.map(|(o, mode)| (o[i].0, o[i].1, mode));
                    let pts = pixel_points(sampler, spp, seed, i as u64, s);
                    estimate_pixel(scene, px, py, &pts)
                })
                .collect();
            progress.inc(1);
            row
        })
        .collect();
    progress.finish_and_clear();
    Ok(rows.concat())
}

/// A reference image: per pixel the mean of a [`stratified_reference`] and its standard error.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceImage {
    /// Pixel values, row-major from the top row.
    pub value: Vec<f64>,
    /// Standard error of each value.
    pub stderr: Vec<f64>,
    /// Rays per pixel.
    pub count: usize,
    /// Whether the image is in the cache folder now (read from it, or written to it); false without
    /// a cache folder or when writing it failed (a warning says why).
    pub cached: bool,
}

impl ReferenceImage {
    /// The mean squared standard error: the part of a measured MSE that is the reference's own noise.
    pub fn noise_floor(&self) -> f64 {
        self.stderr.iter().map(|s| s * s).sum::<f64>() / self.stderr.len() as f64
    }
}

/// The cache file of a scene's reference image at `count` rays per pixel.
fn reference_cache_file(scene: &Scene, count: usize, dir: &Path) -> PathBuf {
    let key = format!("v{RENDER_VERSION} {} count={count}", scene.config().key());
    dir.join(format!(
        "image-{:016x}.npy",
        crate::output::stable_hash(key.as_bytes())
    ))
}

/// The reference image at `count` rays per pixel (power of two, see [`check_ref_count`]): read from the
/// cache folder if there, else computed (and cached if `cache_dir` is given).
pub fn reference_image(
    scene: &Scene,
    count: usize,
    cache_dir: Option<&Path>,
    progress: &ProgressBar,
) -> Result<ReferenceImage> {
    check_ref_count(count)?;
    let (w, h) = (scene.width(), scene.height());
    let file = cache_dir.map(|d| reference_cache_file(scene, count, d));
    if let Some(f) = file.as_deref().filter(|f| f.exists()) {
        match read_reference(f, w * h, count) {
            Some(img) => {
                progress.finish_and_clear();
                return Ok(img);
            }
            None => crate::eprintln_best_effort!(
                "warning: the cached reference {} is unreadable or not a reference of this scene (shape, or a value that is negative or not finite); computing it again",
                f.display()
            ),
        }
    }
    let rows: Vec<Vec<(f64, f64)>> = (0..h)
        .into_par_iter()
        .map(|py| {
            let row = (0..w)
                .map(|px| {
                    let r = stratified_reference(
                        |p| scene.pixel_radiance(px, py, p),
                        count,
                        (py * w + px) as u32,
                    );
                    (r.value, r.stderr)
                })
                .collect();
            progress.inc(1);
            row
        })
        .collect();
    progress.finish_and_clear();
    let pairs = rows.concat();
    let mut img = ReferenceImage {
        value: pairs.iter().map(|p| p.0).collect(),
        stderr: pairs.iter().map(|p| p.1).collect(),
        count,
        cached: false,
    };
    if let Some(f) = file {
        let data: Vec<f64> = pairs.iter().flat_map(|&(v, s)| [v, s]).collect();
        // As for a pixel's reference: a cache that cannot be written costs the next run the work,
        // not this run its result.
        match crate::output::write_npy(&f, &[h, w, 2], &data) {
            Ok(()) => img.cached = true,
            Err(e) => crate::eprintln_best_effort!(
                "warning: the reference image was computed but not cached: {e}"
            ),
        }
    }
    Ok(img)
}

fn read_reference(file: &Path, pixels: usize, count: usize) -> Option<ReferenceImage> {
    let bytes = std::fs::read(file).ok()?;
    let npy = npyz::NpyFile::new(&bytes[..]).ok()?;
    let data = npy.into_vec::<f64>().ok()?;
    // Radiance and its standard error are finite and never negative (albedos in [0, 1]).
    if data.len() != 2 * pixels || data.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
        return None;
    }
    Some(ReferenceImage {
        value: data.iter().step_by(2).copied().collect(),
        stderr: data.iter().skip(1).step_by(2).copied().collect(),
        count,
        cached: true,
    })
}

/// Mean over pixels of `(image − reference)²`.
///
/// `image` and `reference` hold one value per pixel of the same scene, so they have the same length,
/// which is at least 1 (scenes have 1 to 4096 pixels a side).
///
/// Panics if the lengths differ or the images are empty.
pub fn mse(image: &[f64], reference: &[f64]) -> f64 {
    assert!(
        image.len() == reference.len() && !image.is_empty(),
        "mse needs two images of the same, nonzero number of pixels ({} and {})",
        image.len(),
        reference.len()
    );
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(a, b)| (a - b).powi(2))
        .sum();
    sum / image.len() as f64
}

/// Radiance mapped to white in the PNG preview (gamma 2.2 below it, clipped above). On the built-in
/// scene (64 spp, padded MJ) 3.4 % of the pixels are above 1, the light and the ceiling beside it
/// (at 0.5, 12.6 % were: the walls near the light lost their shading).
pub const PNG_WHITE: f64 = 1.0;

/// Smallest longer side of the PNG preview; smaller images are scaled up by an integer factor
/// (nearest neighbour), so that a 64 × 64 scene is seen at 256 × 256.
pub const PNG_MIN_SIDE: usize = 256;

/// Writes an image as EXR (one float channel per entry of `channels`, e.g. `Y`) at `exr_path`, and a
/// PNG preview of the first channel at `png_path` (see [`PNG_WHITE`], [`PNG_MIN_SIDE`]): both or
/// neither.
pub fn write_image_pair(
    exr_path: &Path,
    png_path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f64])],
) -> Result<()> {
    let chans: Vec<(&str, Vec<f32>)> = channels
        .iter()
        .map(|(n, v)| (*n, v.iter().map(|&x| x as f32).collect()))
        .collect();
    let grey: Vec<u8> = channels[0]
        .1
        .iter()
        .map(|&v| ((v / PNG_WHITE).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8)
        .collect();
    let ([w, h], pixels) =
        crate::output::image::upscaled_rect(&grey, [width, height], PNG_MIN_SIDE);
    crate::output::write_group(&[exr_path, png_path], |staged| {
        crate::output::image::write_exr(&staged(exr_path), width, height, &chans)?;
        crate::output::image::write_png(&staged(png_path), w, h, 1, &pixels)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The preview is the first channel, gamma 2.2 up to PNG_WHITE = 1 and clipped above, each
    /// pixel scaled up to a block of 64 × 64 (4 × 2 pixels: 256 × 128).
    #[test]
    fn the_preview_is_scaled_up_and_tone_mapped() {
        let dir = tempfile::tempdir().unwrap();
        let (exr, png) = (dir.path().join("i.exr"), dir.path().join("i.png"));
        let y = [0.0, 0.25, 1.0, 3.0, 0.5, 0.5, 0.5, 0.5];
        write_image_pair(&exr, &png, 4, 2, &[("Y", &y)]).unwrap();
        let decoded = crate::output::image::decode_png(&png);
        assert_eq!((decoded.width, decoded.height), (256, 128));
        let data = decoded.data;
        // 255 (v / 1)^(1/2.2), rounded: 0.25 -> 135.8, 0.5 -> 186.1; 1 and above (clipped) -> 255.
        let expected = [0, 136, 255, 255, 186, 186, 186, 186];
        for (i, &grey) in expected.iter().enumerate() {
            let (x, row) = (i % 4, i / 4);
            for (dx, dy) in [(0, 0), (63, 63)] {
                assert_eq!(data[(row * 64 + dy) * 256 + x * 64 + dx], grey, "pixel {i}");
            }
        }
    }
}
