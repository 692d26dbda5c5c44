//! `anisospec oracle`: the per-pixel depth, shear, shear range and class of the scene (DESIGN §5).

use crate::error::Result;
use crate::output::oracle_map::{write_oracle_png, OracleMaps};
use crate::render::oracle::{oracle_array, oracle_image, PixelClass, ORACLE_CHANNELS};
use crate::render::Scene;
use std::path::PathBuf;

/// The classes in class order (their numbers in the EXR and npy, their colours in the PNG).
const CLASSES: [PixelClass; 3] = [
    PixelClass::InFocus,
    PixelClass::Hairline,
    PixelClass::DoubleWedge,
];

/// Writes the depth oracle of the scene as EXR, npy and a PNG picture.
#[derive(clap::Args, Debug)]
pub struct OracleArgs {
    /// TOML scene file (see --help).
    #[arg(long, help = super::SCENE_HELP)]
    pub scene: Option<PathBuf>,
    /// Output path; FILE.exr (channels depth, sx, sy, s_min, s_max, class), FILE.npy (float64
    /// [height, width, 6], same channel order, row 0 at the top of the image) and FILE.png (the
    /// class map beside the shear map, with legend and colour bar) are written: name it FILE.exr,
    /// FILE.npy, FILE.png or FILE. Depth is in world units along the view axis; shears are in pixels
    /// per lens width (the integrand varies along x + s*u); class is 0 in focus, 1 hairline, 2 double
    /// wedge.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Runs `anisospec oracle`.
pub fn run(args: &OracleArgs) -> Result<()> {
    let files = crate::cli::sibling_outputs(&args.output, &["exr", "npy", "png"])?;
    let (exr, npy, png) = (&files[0], &files[1], &files[2]);
    let inputs: Vec<std::path::PathBuf> = args.scene.iter().cloned().collect();
    crate::output::check_outputs(&[exr, npy, png], &inputs)?;
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
    let classes: Vec<usize> = oracle.iter().map(|o| o.class as usize).collect();
    let shear: Vec<f64> = oracle.iter().map(|o| o.sx).collect();
    let class_names = CLASSES.map(PixelClass::name);
    let maps = OracleMaps {
        size: [w, h],
        classes: &classes,
        class_names: &class_names,
        shear: &shear,
    };
    crate::output::write_group(&[npy, exr, png], |staged| {
        crate::output::write_npy(&staged(npy), &[h, w, ORACLE_CHANNELS.len()], &data)?;
        crate::output::image::write_exr(&staged(exr), w, h, &channels)?;
        write_oracle_png(
            &staged(png),
            &format!(
                "Depth oracle of {}, {w} x {h} pixels: class and shear per pixel",
                // The file's name alone: a long folder path would run off the picture.
                args.scene.as_ref().map_or_else(
                    || "the built-in scene".to_string(),
                    |p| p.file_name().map_or_else(
                        || p.display().to_string(),
                        |f| f.to_string_lossy().into_owned()
                    )
                )
            ),
            &maps,
        )
    })?;
    let count = |c: PixelClass| oracle.iter().filter(|o| o.class == c).count();
    outln!(
        "oracle of {w}x{h} pixels: {} in focus, {} hairline, {} double wedge; wrote {}, {} and {}",
        count(PixelClass::InFocus),
        count(PixelClass::Hairline),
        count(PixelClass::DoubleWedge),
        exr.display(),
        npy.display(),
        png.display()
    );
    Ok(())
}
