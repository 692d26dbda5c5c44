//! `anisospec pixel-spectrum`: a pixel integrand's `xu` (or any) slice spectrum, by sampling the
//! integrand on a fine grid and an FFT (see [`crate::render::spectrum`]).

use crate::error::{Error, Result};
use crate::points::Projection;
use crate::render::spectrum::{integrand_png_key, slice_spectrum, spectrum_png_pixels};
use crate::render::{PixelIntegrand, Scene};
use std::path::PathBuf;
use std::sync::Arc;

/// The largest `--average` M: an M × M midpoint grid of the two averaged coordinates per cell, so
/// `K² · M²` ray casts in all. The midpoint rule's error on an integrand with an edge in the averaged
/// coordinates falls as about `1/M` (the cells the edge cuts), so M = 256 already puts it near 0.4 % of
/// the cell's value, below what the log-scaled spectrum shows; at the default K = 128 it is 10^9 casts,
/// a couple of minutes on two cores, while a larger M (or a mistyped one) would run for hours or more.
pub const MAX_AVERAGE: usize = 256;

/// The largest number of ray casts, `K² · M²` (`--res` K, `--average` M): 2^30, what the default
/// K = 128 costs at the largest M, [`MAX_AVERAGE`] (a couple of minutes on two cores). Each flag's
/// own limit allows far more together: K = 8192 with M = 256 is 2^42 casts, 4096 times as many,
/// about a week.
pub const MAX_RAY_CASTS: u64 = 1 << 30;

/// Writes |f^(k1, k2)|^2 of one pixel's integrand for a projection, as npy, EXR and PNG.
#[derive(clap::Args, Debug)]
pub struct PixelSpectrumArgs {
    /// TOML scene file (see --help).
    #[arg(long, help = super::SCENE_HELP)]
    pub scene: Option<PathBuf>,
    /// The pixel as COLUMN,ROW (row 0 at the top; 0 to width − 1 and height − 1, 0 to 63 in the
    /// built-in scene), e.g. --pixel 20,20.
    #[arg(long, allow_hyphen_values = true)]
    pub pixel: String,
    /// Projection: two of x,y,u,v, e.g. xu or yv. The other two coordinates are averaged
    /// (see --average), which gives the k_other = 0 slice of the 4D spectrum.
    #[arg(long, default_value = "xu", allow_hyphen_values = true)]
    pub proj: String,
    /// Frequency grid size K: even, from 2 to 8192, and K · M at most 32768 (M of --average: K² · M²
    /// ray casts, at most 2^30, e.g. K = 128 with M = 256, or K = 1024 with M = 32). The integrand is
    /// sampled on a K x K grid of cell centres and k1, k2 run over -K/2..K/2-1. A pixel's edges
    /// alias, most near the border and where |f̂|² is small (pixel 30,40 at K = 64 against K = 512:
    /// -1 % at k = (12, 0), -5 % at (10, -7), +17 % at (5, 3), -13 % at (30, -21), 2.5 times at
    /// (31, 0)); for values up to |k| = k_max, take K of at least 4 k_max and read the centre.
    #[arg(long, default_value_t = 128, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub res: usize,
    /// The other two coordinates are averaged with an M x M midpoint grid; 1 fixes them to 1/2. At
    /// most 256, and K² · M² ray casts in all at most 1073741824 (2^30).
    #[arg(long, default_value_t = 8, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub average: usize,
    /// Output path; FILE.npy (float64 [K, K], P[i, j] at k1 = j - K/2, k2 = i - K/2), FILE.exr (raw
    /// values, largest k2 on top) and FILE.png (log10 of P over its largest non-DC value, from -6 to 0)
    /// are written: name it FILE.npy, FILE.exr, FILE.png or FILE.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Parses `COLUMN,ROW`.
fn parse_pixel(text: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::Usage(format!(
            "--pixel '{text}' is not COLUMN,ROW; give two non-negative integers, e.g. --pixel 20,20"
        ))
    };
    let (a, b) = text.split_once(',').ok_or_else(bad)?;
    Ok((
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ))
}

/// Runs `anisospec pixel-spectrum`.
pub fn run(args: &PixelSpectrumArgs) -> Result<()> {
    let (px, py) = parse_pixel(&args.pixel)?;
    if args.average > MAX_AVERAGE {
        return Err(Error::Usage(format!(
            "--average {} is above the largest, {MAX_AVERAGE} (an M x M grid per cell, K² · M² ray casts in all; 256 already puts the averaging error near 0.4 %); lower it, e.g. --average 8 (the default)",
            args.average
        )));
    }
    crate::spectrum::check_res(args.res)?;
    let casts = (args.res as u64).pow(2) * (args.average as u64).pow(2);
    if casts > MAX_RAY_CASTS {
        // K · M <= sqrt(MAX_RAY_CASTS) = 2^15 (exact in f64); K <= 8192 leaves at least M = 4.
        let largest = (MAX_RAY_CASTS as f64).sqrt() as u64 / args.res as u64;
        return Err(Error::Usage(format!(
            "--res {} with --average {} asks for K² · M² = {casts} ray casts, above the limit of {MAX_RAY_CASTS} (2^30: K = 128 with M = 256, a couple of minutes on two cores); lower --average to {largest} or less at this --res, or lower --res",
            args.res, args.average
        )));
    }
    let outputs = super::sibling_outputs(&args.output, &["npy", "exr", "png"])?;
    let inputs: Vec<std::path::PathBuf> = args.scene.iter().cloned().collect();
    let [npy, exr, png] = [&outputs[0], &outputs[1], &outputs[2]];
    crate::output::check_outputs(&[npy, exr, png], &inputs)?;
    let proj = Projection::parse(&args.proj, 4)?;
    let scene = Arc::new(Scene::load(args.scene.as_deref())?);
    let f = PixelIntegrand::new(scene, px, py)?;
    let p = slice_spectrum(|x| f.value(x), proj, args.res, args.average)?;
    let k = args.res;
    let (side, pixels) = spectrum_png_pixels(&p, k);
    crate::output::write_group(&[npy, exr, png], |staged| {
        crate::output::write_npy(&staged(npy), &[k, k], &p)?;
        crate::output::image::write_spectrum_exr(&staged(exr), &p, k)?;
        let key = format!(
            "Slice spectrum of pixel ({px}, {py}) in {}, K = {k}: {}",
            proj.name(),
            integrand_png_key()
        );
        crate::output::image::write_png_described(&staged(png), [side, side], 1, &pixels, Some(key))
    })?;
    outln!(
        "{} slice spectrum of pixel ({px}, {py}), K = {k}: wrote {}, {} and {} (the PNG: {})",
        proj.name(),
        npy.display(),
        exr.display(),
        png.display(),
        integrand_png_key()
    );
    Ok(())
}
