//! `anisospec oracle`: the per-pixel depth, shear, shear range and class of the scene (DESIGN §5).

use crate::error::Result;
use crate::render::oracle::{oracle_array, oracle_image, PixelClass, ORACLE_CHANNELS};
use crate::render::Scene;
use std::path::PathBuf;

/// Writes the depth oracle of the scene as EXR and npy.
#[derive(clap::Args, Debug)]
pub struct OracleArgs {
    /// TOML scene file overriding the built-in camera (width, height, fov, position, focus, aperture);
    /// without it the built-in 64x64 Cornell box is used.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Output path; FILE.exr (channels depth, sx, sy, s_min, s_max, class) and FILE.npy (float64
    /// [height, width, 6], same channel order, row 0 at the top of the image) are written: name it
    /// FILE.exr, FILE.npy or FILE. Depth is in world units along the view axis; shears are in pixels per lens
    /// width (the integrand varies along x + s*u); class is 0 in focus, 1 hairline, 2 double wedge.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Runs `anisospec oracle`.
pub fn run(args: &OracleArgs) -> Result<()> {
    let files = crate::cli::sibling_outputs(&args.output, &["exr", "npy"])?;
    let (exr, npy) = (&files[0], &files[1]);
    let inputs: Vec<std::path::PathBuf> = args.scene.iter().cloned().collect();
    crate::output::check_outputs(&[exr, npy], &inputs)?;
    let scene = Scene::load(args.scene.as_deref())?;
    let (w, h) = (scene.width(), scene.height());
    let oracle = oracle_image(&scene, &crate::progress::bar(h as u64, "oracle rows"))?;
    let data = oracle_array(&oracle);
    let channels: Vec<(&str, Vec<f32>)> = ORACLE_CHANNELS
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let plane = data
                .iter()
                .skip(c)
                .step_by(ORACLE_CHANNELS.len())
                .map(|&v| v as f32)
                .collect();
            (*name, plane)
        })
        .collect();
    crate::output::write_group(&[npy, exr], |staged| {
        crate::output::write_npy(&staged(npy), &[h, w, ORACLE_CHANNELS.len()], &data)?;
        crate::output::image::write_exr(&staged(exr), w, h, &channels)
    })?;
    let count = |c: PixelClass| oracle.iter().filter(|o| o.class == c).count();
    outln!(
        "oracle of {w}x{h} pixels: {} in focus, {} hairline, {} double wedge; wrote {} and {}",
        count(PixelClass::InFocus),
        count(PixelClass::Hairline),
        count(PixelClass::DoubleWedge),
        exr.display(),
        npy.display()
    );
    Ok(())
}
