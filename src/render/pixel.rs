//! One pixel of the scene as a 4D integrand `f_p(x, y, u, v)` (DESIGN §5), with a cached
//! high-count reference.
//!
//! The pixel value is `∫ f_p` over `[0,1)^4`: a box filter over the pixel footprint and a uniform
//! weight over the square lens. The reference is the mean of `R` independent Owen-scrambled Sobol
//! estimates ([`stratified_reference`]); its standard error is their standard deviation over `√R`.
//! References are cached as small JSON files, keyed by the scene configuration, the pixel and the count.

use super::scene::Scene;
use crate::error::{Error, Result};
use crate::integrands::{Integrand, Reference};
use crate::stats::mean_and_stderr;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// Version of the renderer's geometry and shading, part of every cache key: bump it when the scene
/// changes so stale references are not reused.
pub const RENDER_VERSION: u32 = 1;

/// Default number of rays of a single pixel's reference: `2^20`, in 32 scrambled Sobol sets of `2^15`.
pub const DEFAULT_PIXEL_REF_COUNT: usize = 1 << 20;

/// Independent scrambles a reference is split into (its standard error comes from their spread).
const REF_REPLICATES_MIN: usize = 32;

/// Largest Sobol set sobol_burley supports.
const SOBOL_MAX: usize = 1 << 16;

/// The folder references are cached in: `$ANISOSPEC_CACHE` if set and not empty, else `out/cache`
/// (an empty value is taken as unset, as shells often leave it).
pub fn default_cache_dir() -> PathBuf {
    cache_dir_and_source(None).0
}

/// The cache folder a command uses, and where that choice came from, to name in a message about
/// it: `given` (a `--cache` flag), else `$ANISOSPEC_CACHE` when set and non-empty, else `out/cache`
/// (named as `--cache`, the flag that chooses another).
pub fn cache_dir_and_source(given: Option<&std::path::Path>) -> (PathBuf, &'static str) {
    if let Some(dir) = given {
        return (dir.to_path_buf(), "--cache");
    }
    match std::env::var_os("ANISOSPEC_CACHE").filter(|v| !v.is_empty()) {
        Some(dir) => (PathBuf::from(dir), "$ANISOSPEC_CACHE"),
        None => (PathBuf::from("out/cache"), "--cache"),
    }
}

/// Checks a reference count: a power of two from `2^10` to `2^24`.
pub fn check_ref_count(count: usize) -> Result<()> {
    if !count.is_power_of_two() || !(1 << 10..=1 << 24).contains(&count) {
        let nearest = count
            .clamp(1 << 10, 1 << 24)
            .next_power_of_two()
            .min(1 << 24);
        return Err(Error::Usage(format!(
            "a reference count of {count} is not allowed; it must be a power of two from 1024 to 16777216 \
             (scrambled Sobol sets), e.g. {nearest}"
        )));
    }
    Ok(())
}

/// The integral of `f` over `[0,1)^4` from `count` points (a power of two, see [`check_ref_count`]):
/// `R = max(32, count / 2^16)` independent Owen-scrambled Sobol sets of `count / R` points, scrambled by
/// `seed`. Returns their mean and its standard error. Deterministic for any thread count.
pub fn stratified_reference<F>(f: F, count: usize, seed: u32) -> Reference
where
    F: Fn([f64; 4]) -> f64 + Sync,
{
    let replicates = (count / SOBOL_MAX).max(REF_REPLICATES_MIN);
    let per = (count / replicates).max(1);
    let estimates: Vec<f64> = (0..replicates)
        .into_par_iter()
        .map(|r| {
            let scramble = seed.wrapping_mul(0x9E37_79B9).wrapping_add(r as u32);
            let sum: f64 = (0..per)
                .map(|i| {
                    let p = sobol_burley::sample_4d(i as u32, 0, scramble);
                    f(p.map(f64::from))
                })
                .sum();
            sum / per as f64
        })
        .collect();
    let (value, stderr) = mean_and_stderr(estimates.iter().copied());
    Reference { value, stderr }
}

/// The integrand of pixel `(px, py)` of a scene: `f(x, y, u, v)` is the radiance along the thin-lens
/// ray through pixel point `(x, y)` and lens point `(u, v)` (see [`super::camera`]).
pub struct PixelIntegrand {
    scene: Arc<Scene>,
    px: usize,
    py: usize,
    ref_count: usize,
    cache_dir: Option<PathBuf>,
    label: String,
    reference: OnceLock<Reference>,
}

impl PixelIntegrand {
    /// Pixel `(px, py)` (column, row from the top) of `scene`; a pixel outside the image is
    /// [`Error::Usage`] naming the image size. The reference uses [`DEFAULT_PIXEL_REF_COUNT`] rays and
    /// is cached in [`default_cache_dir`].
    pub fn new(scene: Arc<Scene>, px: usize, py: usize) -> Result<Self> {
        let (w, h) = (scene.width(), scene.height());
        if px >= w || py >= h {
            return Err(Error::Usage(format!(
                "pixel ({px}, {py}) is outside the {w}x{h} image; use 0 <= px < {w} and 0 <= py < {h}"
            )));
        }
        Ok(Self {
            scene,
            px,
            py,
            ref_count: DEFAULT_PIXEL_REF_COUNT,
            cache_dir: Some(default_cache_dir()),
            label: format!("pixel:px={px},py={py}"),
            reference: OnceLock::new(),
        })
    }

    /// Uses `count` rays for the reference (see [`check_ref_count`]); the name then gives the count
    /// unless it is the default, so that `converge --integrand NAME` uses the same reference.
    pub fn with_ref_count(mut self, count: usize) -> Result<Self> {
        check_ref_count(count)?;
        self.ref_count = count;
        let (px, py) = (self.px, self.py);
        self.label = if count == DEFAULT_PIXEL_REF_COUNT {
            format!("pixel:px={px},py={py}")
        } else {
            format!("pixel:px={px},py={py},refcount={count}")
        };
        self.reference = OnceLock::new();
        Ok(self)
    }

    /// Caches the reference in `dir`, or nowhere (`None`: computed on every run).
    pub fn with_cache_dir(mut self, dir: Option<PathBuf>) -> Self {
        self.cache_dir = dir;
        self
    }

    /// Sets the name reported by [`Integrand::name`].
    fn with_label(mut self, label: String) -> Self {
        self.label = label;
        self
    }

    /// The pixel `(px, py)`.
    pub fn pixel(&self) -> (usize, usize) {
        (self.px, self.py)
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// `f(x, y, u, v)`: radiance of the ray through pixel point `(x, y)` and lens point `(u, v)`.
    pub fn value(&self, p: [f64; 4]) -> f64 {
        self.scene.pixel_radiance(self.px, self.py, p)
    }

    fn cache_key(&self) -> String {
        format!(
            "v{RENDER_VERSION} {} px={} py={} count={}",
            self.scene.config().key(),
            self.px,
            self.py,
            self.ref_count
        )
    }

    fn cache_file(&self, dir: &Path, key: &str) -> PathBuf {
        dir.join(format!(
            "pixel-{:016x}.json",
            crate::output::stable_hash(key.as_bytes())
        ))
    }

    fn compute_reference(&self) -> Reference {
        let key = self.cache_key();
        if let Some(dir) = &self.cache_dir {
            let file = self.cache_file(dir, &key);
            if let Some(r) = read_cached(&file, &key) {
                return r;
            }
            if file.exists() {
                crate::eprintln_best_effort!(
                    "warning: the cached reference {} is unreadable or not this pixel's (its key, or a value that is negative or not finite); computing it again",
                    file.display()
                );
            }
            let r = stratified_reference(|p| self.value(p), self.ref_count, 1);
            let json = serde_json::json!({"key": key, "value": r.value, "stderr": r.stderr});
            let written = crate::output::write_atomic(&file, |w| {
                use std::io::Write;
                write!(w, "{json}")
            });
            if let Err(e) = written {
                crate::eprintln_best_effort!(
                    "warning: the reference was computed but not cached: {e}"
                );
            }
            return r;
        }
        stratified_reference(|p| self.value(p), self.ref_count, 1)
    }
}

/// A cached reference if the file exists and holds the same key.
fn read_cached(file: &Path, key: &str) -> Option<Reference> {
    let text = std::fs::read_to_string(file).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v.get("key")?.as_str()? != key {
        return None;
    }
    let value = v.get("value")?.as_f64()?;
    let stderr = v.get("stderr")?.as_f64()?;
    // Radiance and its standard error are finite and never negative (albedos in [0, 1]).
    let valid = |v: f64| v.is_finite() && v >= 0.0;
    (valid(value) && valid(stderr)).then_some(Reference { value, stderr })
}

impl Integrand for PixelIntegrand {
    fn name(&self) -> String {
        self.label.clone()
    }

    fn dims(&self) -> usize {
        4
    }

    fn eval(&self, x: &[f64]) -> f64 {
        self.value([x[0], x[1], x[2], x[3]])
    }

    /// Computed on first use at the reference count (or read from the cache), then kept.
    fn reference(&self) -> Reference {
        *self.reference.get_or_init(|| self.compute_reference())
    }
}

/// Parses the parameters of a `pixel:` integrand, `px=…,py=…[,scene=FILE][,refcount=N]` (the
/// `pixel:` prefix may be included): the pixel's column and row, an optional TOML scene file, and the
/// reference count (default [`DEFAULT_PIXEL_REF_COUNT`]). The reference is cached in `cache` (a
/// `--cache` flag), else in [`default_cache_dir`].
pub fn parse_pixel_spec(
    params: &str,
    cache: Option<&std::path::Path>,
) -> Result<Box<dyn Integrand>> {
    let body = params.strip_prefix("pixel:").unwrap_or(params);
    let (mut px, mut py, mut scene, mut count) = (None, None, None, DEFAULT_PIXEL_REF_COUNT);
    let usage = |m: String| {
        Error::Usage(format!(
            "{m} in 'pixel:{body}'; write pixel:px=COLUMN,py=ROW[,scene=FILE][,refcount=N]"
        ))
    };
    let mut seen: Vec<&str> = Vec::new();
    for part in body.split(',').filter(|p| !p.trim().is_empty()) {
        let (k, v) = part
            .split_once('=')
            .ok_or_else(|| usage(format!("'{part}' is not key=value")))?;
        if seen.contains(&k.trim()) {
            return Err(usage(format!("key '{}' is given twice", k.trim())));
        }
        seen.push(k.trim());
        let int = |v: &str| {
            v.trim()
                .parse::<usize>()
                .map_err(|_| usage(format!("{k}={v} is not a non-negative integer")))
        };
        match k.trim() {
            "px" => px = Some(int(v)?),
            "py" => py = Some(int(v)?),
            "refcount" => count = int(v)?,
            "scene" => scene = Some(PathBuf::from(v.trim())),
            other => return Err(usage(format!("unknown parameter '{other}'"))),
        }
    }
    let (px, py) = match (px, py) {
        (Some(a), Some(b)) => (a, b),
        _ => return Err(usage("both px and py are needed".into())),
    };
    let scene = Arc::new(Scene::load(scene.as_deref())?);
    let label = format!("pixel:{}", body.trim());
    let pixel = PixelIntegrand::new(scene, px, py)?
        .with_ref_count(count)?
        .with_label(label);
    Ok(Box::new(match cache {
        Some(dir) => pixel.with_cache_dir(Some(dir.to_path_buf())),
        None => pixel,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cached reference reads back bit for bit, so a fresh run and a cached one give the same MSE
    /// bits. serde_json's default float parser misread 5338 of 20000 such values by a unit in the
    /// last place (among them a pixel reference of the default compare suite); its `float_roundtrip`
    /// parser, which Cargo.toml asks for, is exact.
    #[test]
    fn a_cached_reference_reads_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("pixel.json");
        let mut rng = crate::rng::stream(1, 0);
        let mut misread = 0;
        for _ in 0..2000 {
            use rand::Rng as _;
            let value: f64 = rng.random::<f64>();
            let stderr: f64 = rng.random::<f64>() * 1e-6;
            let json = serde_json::json!({"key": "k", "value": value, "stderr": stderr});
            std::fs::write(&file, json.to_string()).unwrap();
            let r = read_cached(&file, "k").unwrap();
            if r.value.to_bits() != value.to_bits() || r.stderr.to_bits() != stderr.to_bits() {
                misread += 1;
            }
        }
        assert_eq!(misread, 0, "of 2000 cached references");
    }
}
