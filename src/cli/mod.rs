//! The command-line front end: one module per subcommand, each a clap `Args` struct and a `run`.

/// `print!` for a command's results: a failed write to standard output (a full disk, a closed
/// pipe) returns an error from the enclosing function instead of panicking ([`write_stdout`]).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::write_stdout(format_args!($($arg)*))?
    };
}

/// `println!` for a command's results, as [`out!`].
macro_rules! outln {
    () => {
        $crate::cli::write_stdout(format_args!("\n"))?
    };
    ($($arg:tt)*) => {
        $crate::cli::write_stdout(format_args!("{}\n", format_args!($($arg)*)))?
    };
}

pub mod compare;
pub mod converge;
pub mod gallery;
pub mod integrands;
pub mod optimize;
pub mod oracle;
pub mod pixel_spectrum;
pub mod render;
pub mod sample;
pub mod spectrum;
pub mod variance;

use crate::error::{Error, Result};
use crate::points::shear::ShearMode;
use crate::samplers::{self, Sampler};
use std::path::{Path, PathBuf};

/// Writes `text` to standard output; a failure is an I/O error naming standard output (a closed pipe
/// among them: see [`Error::is_broken_pipe`]).
pub fn write_stdout(text: std::fmt::Arguments) -> Result<()> {
    use std::io::Write as _;
    std::io::stdout()
        .lock()
        .write_fmt(text)
        .map_err(|source| Error::Io {
            context: "cannot write the results to standard output".into(),
            source,
        })
}

/// `--shear sx,sy` and `--shear-mode`: a constant shear of a 4D sampler's sets (sample, spectrum,
/// converge; render's `--shear` is the per-pixel oracle's instead).
#[derive(Clone, Debug, clap::Args)]
pub struct ShearArgs {
    /// Shear the 4D sets by sx in xu and sy in yv (written sx,sy, e.g. 0.5,0.5 or -0.5,-0.5; each
    /// magnitude at most 1e6; in pixel widths per lens width, as the oracle gives it: x moves by
    /// −sx·u), aligning their spectra with a defocused pixel's, e.g. the oracle's shear of the
    /// integrand.
    #[arg(long, value_parser = parse_shear, allow_hyphen_values = true)]
    pub shear: Option<(f64, f64)>,
    /// How --shear is applied (needs --shear): transported (seam-free, exactly uniform on the square)
    /// or wrap (x − s u mod 1, which adds a seam on non-periodic integrands).
    #[arg(long, value_parser = parse_shear_mode, default_value = "transported")]
    pub shear_mode: ShearMode,
}

/// Builds the sampler `name` in `dims` dimensions, sheared as `shear` asks (4D only).
pub fn sampler_with_shear(name: &str, dims: usize, shear: &ShearArgs) -> Result<Box<dyn Sampler>> {
    let inner = samplers::build(name, dims)?;
    match shear.shear {
        None => Ok(inner),
        Some(_) if dims != 4 => Err(Error::Usage(
            "--shear applies to the xu and yv projections of 4D sets; ask for 4D sets (--dims 4 in sample and spectrum, a 4D integrand such as sheared:s=0.5@xu in converge and variance)".into(),
        )),
        Some((sx, sy)) => Ok(Box::new(samplers::Sheared::new(
            inner,
            sx,
            sy,
            shear.shear_mode,
        )?)),
    }
}

/// Parses `--shear sx,sy` (two finite numbers).
pub fn parse_shear(text: &str) -> std::result::Result<(f64, f64), String> {
    let parts: Vec<&str> = text.split(',').collect();
    let nums: Option<Vec<f64>> = parts.iter().map(|p| p.trim().parse::<f64>().ok()).collect();
    match nums.as_deref() {
        Some([sx, sy]) if sx.is_finite() && sy.is_finite() => Ok((*sx, *sy)),
        _ => Err(format!(
            "'{text}' is not a shear; write two finite numbers sx,sy (e.g. 0.5,0.5), the shear of xu and of yv"
        )),
    }
}

/// `--scene`'s help, shared by the commands that render or look at the built-in scene.
pub const SCENE_HELP: &str = "TOML scene file overriding the built-in camera, every key optional: width and height \
(pixels; default 64 x 64), fov (vertical field of view, degrees; 33.4), position (lens centre, world units; \
[0, 0, 0], looking down +z), focus (depth of the plane in focus, world units; 3) and aperture (side of the square \
lens, world units; 0.04, 0 a pinhole). Without it the built-in 64x64 Cornell box is used; a camera whose shears \
could pass 1e6 in magnitude is refused.";

/// Parses `--seed`: a whole number from 0 to `u64::MAX`. Negative numbers reach this parser (the
/// flags using it allow them), so that `--seed -1` is answered with the range rather than as an
/// unknown flag.
pub fn parse_seed(text: &str) -> std::result::Result<u64, String> {
    let rule = format!("a seed is a whole number from 0 to {}", u64::MAX);
    match text.trim().parse::<i128>() {
        Ok(v) => u64::try_from(v).map_err(|_| format!("{rule}, not {text}")),
        Err(_) => Err(format!("'{text}' is not a whole number; {rule}, e.g. 1")),
    }
}

/// Parses a whole number of at least `least` (0 or 1), or says what `rule` asks of it. Negative
/// numbers reach this parser (the flags using it allow them) so that `-n -5` or `--res -2` is answered
/// here rather than as an unknown flag.
fn parse_at_least(text: &str, least: i128, rule: &str) -> std::result::Result<usize, String> {
    match text.trim().parse::<i128>() {
        Ok(v) if v >= least => usize::try_from(v)
            .map_err(|_| format!("{text} is above the largest count, {}", usize::MAX)),
        Ok(_) => Err(format!("{rule}, not {text}")),
        Err(_) => Err(format!("'{text}' is not a whole number; {rule}, e.g. 64")),
    }
}

/// Parses a point count N (`-n`, `--spp`): a positive integer.
pub fn parse_count(text: &str) -> std::result::Result<usize, String> {
    parse_at_least(
        text,
        1,
        "a point count must be a positive integer (1 or more)",
    )
}

/// Parses a count flag other than N (`--res`, `--realizations`, `--sets`, `--cones`, `--average`): a
/// whole number, 0 or more (each command then checks its own range).
pub fn parse_whole(text: &str) -> std::result::Result<usize, String> {
    parse_at_least(text, 0, "a count is a whole number, 0 or more")
}

/// Checks that a list of N (`-n 16,64,256`) names each N once, in increasing order: a repeat would
/// measure the same thing twice and print it as two rows, and the rows, CSV and plots follow the
/// list (an unsorted one drew its lines back and forth along N).
pub fn increasing_counts(ns: &[usize]) -> Result<()> {
    use crate::compare::config::{first_descent, first_repeat};
    if let Some(n) = first_repeat(ns) {
        return Err(Error::Usage(format!(
            "-n lists {n} twice; give each N once (e.g. -n 16,64,256)"
        )));
    }
    match first_descent(ns) {
        Some((a, b)) => Err(Error::Usage(format!(
            "-n lists {a} before {b}; list N in increasing order (e.g. -n 16,64,256)"
        ))),
        None => Ok(()),
    }
}

/// Parses `--shear-mode`.
pub fn parse_shear_mode(text: &str) -> std::result::Result<ShearMode, String> {
    ShearMode::parse(text).map_err(|e| e.to_string())
}

/// The kinds of file a spectrum can be written as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    /// numpy `float64 [K, K]`, raw values.
    Npy,
    /// OpenEXR, one `Y` channel of `f32` raw values.
    Exr,
    /// 8-bit greyscale, `log10 P` tone-mapped.
    Png,
}

/// Checks every output path's extension before any work is done.
pub fn image_kinds(outputs: &[PathBuf]) -> Result<Vec<ImageKind>> {
    for p in outputs {
        crate::output::check_file_name(p, &["npy", "exr", "png"])?;
    }
    outputs
        .iter()
        .map(|p| match extension(p).as_deref() {
            Some("npy") => Ok(ImageKind::Npy),
            Some("exr") => Ok(ImageKind::Exr),
            Some("png") => Ok(ImageKind::Png),
            _ => Err(Error::Usage(format!(
                "cannot tell the format of {}; name outputs .npy (raw numbers), .exr (float image) or .png (picture)",
                p.display()
            ))),
        })
        .collect()
}

/// Checks that the file `path` given to `flag` is named `.ext`, the one format `flag` writes (`what`,
/// e.g. "a CSV table").
pub fn require_extension(path: &Path, flag: &str, ext: &str, what: &str) -> Result<()> {
    if crate::output::names_no_file(path) {
        return Err(Error::Usage(format!(
            "{flag} {} has no usable file name; give a path such as out/name.{ext}",
            path.display()
        )));
    }
    if extension(path).as_deref() == Some(ext) {
        return Ok(());
    }
    Err(Error::Usage(format!(
        "{flag} {}: name it .{ext} ({flag} writes {what})",
        path.display()
    )))
}

/// The Fourier method of a command with `--exact` and `--eps`: the exact DFT, or the NUFFT at `eps`
/// (an `eps` out of range is refused, naming `--exact` as the way to exact sums).
pub fn fourier_method(exact: bool, eps: f64) -> Result<crate::spectrum::Method> {
    if exact {
        return Ok(crate::spectrum::Method::Exact);
    }
    crate::spectrum::Method::nufft(eps).map_err(|e| match e {
        Error::Usage(m) => Error::Usage(format!("{m}, or give --exact for the exact DFT")),
        other => other,
    })
}

/// The files a command writes beside one another from `-o output`, one per extension of `exts` (e.g.
/// `out/oracle.exr` and `out/oracle.npy`). `output` may carry one of `exts`, in any case, or no
/// extension; the file of its own extension is `output` exactly as given (`-o out/o.NPY` writes
/// `out/o.NPY` and `out/o.exr`, as every command writes at the path it is given). A path with no file
/// name (`out/`, a folder; `out/.npy`, an extension alone), or with another extension (which would not
/// be written), is a usage error naming the files and the fix.
pub fn sibling_outputs(output: &Path, exts: &[&str]) -> Result<Vec<PathBuf>> {
    crate::output::check_file_name(output, exts)?;
    let own = extension(output);
    let files: Vec<PathBuf> = exts
        .iter()
        .map(|e| match &own {
            Some(x) if x == e => output.to_path_buf(),
            _ => output.with_extension(e),
        })
        .collect();
    if let Some(ext) = own.filter(|x| !exts.contains(&x.as_str())) {
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        let dotted: Vec<String> = exts.iter().map(|e| format!(".{e}")).collect();
        return Err(Error::Usage(format!(
            "-o {}: the outputs are {}, not a .{ext}; name -o with {}, or with no extension",
            output.display(),
            spoken_list(&names, "and"),
            spoken_list(&dotted, "or")
        )));
    }
    Ok(files)
}

/// `n` and `noun`, in the plural (`noun` and an `s`) unless `n` is 1: `1 set`, `8 sets`.
pub fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// `a, b and c` (with `word` = "and").
fn spoken_list(items: &[String], word: &str) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} {word} {last}", rest.join(", ")),
    }
}

/// The lower-case extension of a path.
pub fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

#[cfg(test)]
mod tests {
    use crate::spectrum::nufft::{EPS_MAX, EPS_MIN};
    use clap::{Args, Command};

    /// The help of one subcommand's flags.
    fn help<A: Args>() -> String {
        A::augment_args(Command::new("t")).render_help().to_string()
    }

    /// Each `--help` states the limits its command enforces, with the constants' values.
    #[test]
    fn help_states_the_limits() {
        assert_eq!(crate::points::MAX_COORDINATES, 1 << 28);
        let res = format!("at most {}", crate::spectrum::MAX_RES);
        let shear = format!("at most {:e}", crate::points::shear::MAX_SHEAR);
        let eps = format!("from {:e} to {:e}", EPS_MIN, EPS_MAX);
        // A sheared sampler's prediction samples its pulled-back integrand on 4K points per side.
        let pullback = format!(
            "with --shear at most {}",
            crate::variance::MAX_PULLBACK_SAMPLES / 4
        );
        let cases: [(String, &[&String]); 6] = [
            (help::<super::sample::SampleArgs>(), &[&shear]),
            (
                help::<super::spectrum::SpectrumArgs>(),
                &[&res, &shear, &eps],
            ),
            (
                help::<super::variance::VarianceArgs>(),
                &[&res, &eps, &shear, &pullback],
            ),
            (help::<super::gallery::GalleryArgs>(), &[&res, &eps]),
            (help::<super::optimize::OptimizeArgs>(), &[&eps]),
            (help::<super::converge::ConvergeArgs>(), &[&shear]),
        ];
        for (text, needles) in &cases {
            for needle in *needles {
                assert!(text.contains(needle.as_str()), "{needle} not in {text}");
            }
        }
        for text in [
            help::<super::sample::SampleArgs>(),
            help::<super::optimize::OptimizeArgs>(),
        ] {
            assert!(text.contains("at most 2^28 "), "{text}");
        }
    }

    #[test]
    fn sibling_outputs_need_a_file_name() {
        use std::path::Path;
        let exts = ["exr", "npy"];
        // A folder (written beside it as out.exr) or an extension alone (hidden .npy.exr files).
        for bad in [
            "out/", "out//", "out/.", ".", "out/..", "out/.npy", "out/.NPY", ".exr", "out/.png",
            "/",
        ] {
            let e = super::sibling_outputs(Path::new(bad), &exts).unwrap_err();
            assert!(e.to_string().contains("no usable file name"), "{bad}: {e}");
            assert_eq!(e.exit_code(), 2);
        }
        let files = super::sibling_outputs(Path::new("out/o.npy"), &exts).unwrap();
        assert_eq!(files, [Path::new("out/o.exr"), Path::new("out/o.npy")]);
        let files = super::sibling_outputs(Path::new("out/.hidden"), &exts).unwrap();
        assert_eq!(
            files,
            [Path::new("out/.hidden.exr"), Path::new("out/.hidden.npy")]
        );
    }
}
