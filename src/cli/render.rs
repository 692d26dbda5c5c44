//! `anisospec render`: the depth-of-field image with any 4D sampler, optionally sheared per pixel by
//! the depth oracle, its MSE against a high-count reference, and the reference itself.

use crate::error::{Error, Result};
use crate::points::shear::ShearMode;
use crate::render::image::{
    mse, oracle_shears, reference_image, render_image, write_image_pair, WedgeShear,
    DEFAULT_IMAGE_REF_COUNT,
};
use crate::render::oracle::{oracle_image, require_aperture};
use crate::render::pixel::cache_dir_and_source;
use crate::render::Scene;
use crate::samplers;
use std::path::PathBuf;
use std::time::Instant;

/// Renders the scene and reports the image's MSE against the reference.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// TOML scene file (see --help).
    #[arg(long, help = super::SCENE_HELP)]
    pub scene: Option<PathBuf>,
    /// 4D sampler (see `anisospec samplers`), e.g. random, oa, sobol, padded-mj, xuyv-mj, or
    /// table:PATH (optimized sets), or lattice:Z1:Z2:Z3:Z4 (a rank-1 lattice with that generating
    /// vector). Required, unless --reference is given (which uses none).
    #[arg(long, required_unless_present = "reference")]
    pub sampler: Option<String>,
    /// Samples (rays) per pixel; must be a count the sampler allows (N × 4 at most 2^28 coordinates),
    /// and width × height × spp at most 2^34 rays.
    #[arg(long, default_value_t = 64, value_parser = crate::cli::parse_count, allow_negative_numbers = true)]
    pub spp: usize,
    /// Seed: pixel i uses stream i of it for its set and its toroidal shift.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Shear each pixel's points by the depth oracle's shear in xu and yv (the scene needs an
    /// aperture).
    #[arg(long)]
    pub shear: bool,
    /// How --shear is applied (needs --shear): transported (seam-free inverse-CDF transport) or wrap
    /// (x' = x - s u mod 1).
    #[arg(long, default_value = "transported", value_parser = crate::cli::parse_shear_mode)]
    pub shear_mode: ShearMode,
    /// The shear of double-wedge (occluder) pixels (needs --shear): centre (the shear of the depth at
    /// the pixel and lens centres, measured better on the whole image) or none.
    #[arg(long, value_enum, default_value_t = WedgeShear::Centre, hide_possible_values = true)]
    pub wedge_shear: WedgeShear,
    /// Write the high-count reference image (channels Y and stderr) instead of a sampled one; the
    /// sampler's flags (--sampler, --spp, --seed, --shear) are refused with it.
    #[arg(long, conflicts_with_all = ["sampler", "spp", "seed", "shear"])]
    pub reference: bool,
    /// Rays per pixel of the reference (a power of two, 1024 to 16777216; width × height × count at
    /// most 2^34 rays), in independent
    /// Owen-scrambled Sobol sets whose spread gives its standard error. Every render computes the
    /// reference to report its MSE (the built-in 64x64 scene: about 45 s on 2 cores the first time),
    /// then reads it from the cache.
    #[arg(long, default_value_t = DEFAULT_IMAGE_REF_COUNT)]
    pub ref_count: usize,
    /// Folder the reference image is cached in (default $ANISOSPEC_CACHE or out/cache).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Output image; IMG.exr (float radiance, channel Y) and IMG.png (preview, gamma 2.2, white at
    /// radiance 1, scaled up by a whole factor until its longer side is at least 256 px) are
    /// written: name it IMG.exr, IMG.png or IMG.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// The most rays one image (the reference, or a render) may cast: 2^34, about 50 minutes on 2 cores
/// (the built-in 64 x 64 scene's reference, 2^28 rays, takes about 45 s), and what the largest scene,
/// 4096 x 4096, needs at the smallest --ref-count, 1024.
pub const MAX_RAYS: u64 = 1 << 34;

/// Refuses an image of `pixels` pixels at `per_pixel` rays each beyond [`MAX_RAYS`], naming the flag
/// that sets `per_pixel`.
fn check_rays(pixels: usize, per_pixel: usize, flag: &str) -> Result<()> {
    let rays = (pixels as u64).saturating_mul(per_pixel as u64);
    if rays > MAX_RAYS {
        return Err(Error::Usage(format!(
            "{pixels} pixels at {flag} {per_pixel} rays each is {rays:.3e} rays, more than the {MAX_RAYS:.3e} (2^34, about 50 minutes on 2 cores) one image may cast; lower {flag}, or the scene's width and height"
        )));
    }
    Ok(())
}

/// Runs `anisospec render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let scene = Scene::load(args.scene.as_deref())?;
    let (w, h) = (scene.width(), scene.height());
    // Every render computes (or reads) the reference; a render casts --spp rays per pixel too. Both
    // are checked before any work (the oracle of a large scene takes minutes).
    crate::render::pixel::check_ref_count(args.ref_count)?;
    check_rays(w * h, args.ref_count, "--ref-count")?;
    if !args.reference {
        check_rays(w * h, args.spp, "--spp")?;
    }
    let (cache, cache_source) = cache_dir_and_source(args.cache.as_deref());
    let mut inputs: Vec<PathBuf> = args.scene.iter().cloned().collect();
    inputs.extend(samplers::input_files(
        args.sampler.as_deref().unwrap_or_default(),
    ));
    let files = crate::cli::sibling_outputs(&args.output, &["exr", "png"])?;
    let (exr, png) = (&files[0], &files[1]);
    crate::output::check_outputs(&[exr, png], &inputs)?;
    // The reference is written to the cache once computed (45 s on the built-in scene): a cache path
    // that is a file is refused before that work, as compare refuses it.
    crate::output::check_folder(&cache, cache_source, "cache")?;
    let reference_of = |what: &str| {
        let bar = crate::progress::bar(h as u64, what);
        reference_image(&scene, args.ref_count, Some(&cache), &bar)
    };
    if args.reference {
        let start = Instant::now();
        let r = reference_of("reference image")?;
        write_image_pair(exr, png, w, h, &[("Y", &r.value), ("stderr", &r.stderr)])?;
        let cached = if r.cached {
            format!("cached in {}", cache.display())
        } else {
            format!("not cached in {}: see the warning above", cache.display())
        };
        outln!(
            "reference {w}x{h} at {} rays per pixel in {:.2} s ({cached}); mean squared standard \
             error {:.3e}; wrote {} and {}",
            r.count,
            start.elapsed().as_secs_f64(),
            r.noise_floor(),
            exr.display(),
            png.display()
        );
        return Ok(());
    }
    let name = args.sampler.as_deref().unwrap_or_default();
    let sampler = samplers::build(name, 4)?;
    samplers::validate_n(sampler.as_ref(), args.spp).map_err(|e| match e {
        Error::Usage(m) => Error::Usage(format!("--spp {}: {m}", args.spp)),
        other => other,
    })?;
    let shears = if args.shear {
        require_aperture(&scene, "--shear")?;
        Some(oracle_shears(
            &oracle_image(&scene, &crate::progress::bar(h as u64, "oracle rows"))?,
            args.wedge_shear,
        ))
    } else {
        None
    };
    let reference = reference_of("reference image")?;
    let start = Instant::now();
    let bar = crate::progress::bar(h as u64, "render");
    let image = render_image(
        &scene,
        sampler.as_ref(),
        args.spp,
        args.seed,
        shears.as_deref().map(|s| (s, args.shear_mode)),
        &bar,
    )?;
    let seconds = start.elapsed().as_secs_f64();
    write_image_pair(exr, png, w, h, &[("Y", &image)])?;
    let shear = if args.shear {
        format!("sheared by the oracle ({:?})", args.shear_mode).to_lowercase()
    } else {
        "unsheared".into()
    };
    outln!(
        "{name} {shear}, {} spp: MSE {:.4e} against the reference ({} rays per pixel, its own noise \
         {:.1e}); {:.2} s; wrote {} and {}",
        args.spp,
        mse(&image, &reference.value),
        reference.count,
        reference.noise_floor(),
        seconds,
        exr.display(),
        png.display()
    );
    Ok(())
}
