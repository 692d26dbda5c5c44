//! `anisospec gallery`: the built-in default job — expected spectra of the classical samplers, 2D sets
//! in `xy` and 4D sets in `xu`, written as PNG, npy and radial CSV with an index page.

use super::ImageKind;
use crate::error::{Error, Result};
use crate::output::sheet::{write_sheet, Panel};
use crate::output::{write_atomic, write_folder, ReportMarker};
use crate::points::Projection;
use crate::samplers::{self, usable_n};
use crate::spectrum::expected::of_sampler;
use crate::spectrum::profiles::{dark_withheld_note, radial_profile, write_radial_csv};
use crate::spectrum::{check_res, Method};
use std::io::Write;
use std::path::PathBuf;

/// The 2D samplers shown in `xy`.
const GALLERY_2D: [&str; 11] = [
    "random", "jittered", "nrooks", "mj", "cmj", "pmj02", "poisson", "blue", "halton", "sobol",
    "lattice",
];
/// The 4D samplers shown in `xu` (padded sets show the N-rooks cross or white noise there).
const GALLERY_4D: [&str; 9] = [
    "random",
    "jittered",
    "padded-mj",
    "padded-sobol",
    "sobol",
    "halton",
    "oa",
    "lattice",
    "xuyv-mj",
];

/// The contact sheets: the dimension of the samplers they show, the file, and the title.
const SHEETS: [(usize, &str, &str); 2] = [
    (2, "sheet_2d_xy.png", "2D samplers, xy"),
    (4, "sheet_4d_xu.png", "4D samplers, xu"),
];

/// The gallery's index page and its first line, which mark a folder holding an earlier gallery.
const GALLERY_MARKER: ReportMarker = ReportMarker {
    file: "index.md",
    first_line: "# Expected power spectra of the classical samplers",
};

/// Spectra of every classical sampler in one folder.
#[derive(Debug, clap::Args)]
pub struct GalleryArgs {
    /// Output folder, made if missing (as compare's --out); the gallery goes in OUT/gallery, replacing
    /// an earlier gallery there (a gallery folder of other files is refused).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Points per set (N × D at most 2^28 coordinates); a sampler that cannot make this N uses its nearest valid N (the index says which).
    #[arg(
        short = 'n',
        long = "n",
        default_value_t = 256,
        value_parser = super::parse_count,
        allow_negative_numbers = true
    )]
    pub n: usize,
    /// Frequency grid side K (even, at least 4 and at most 8192: each spectrum's radial profile needs an
    /// annulus).
    #[arg(long, default_value_t = 128, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub res: usize,
    /// Realizations averaged per spectrum (at most 1000000).
    #[arg(long, default_value_t = 64, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub realizations: usize,
    /// NUFFT tolerance (relative error of P), from 1e-12 to 1e-1.
    #[arg(long, default_value = "1e-6", allow_negative_numbers = true)]
    pub eps: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
}

/// Runs `anisospec gallery`.
pub fn run(args: &GalleryArgs) -> Result<()> {
    // The gallery's own lower limit first, so that --res 0 to 3 are told what the gallery takes.
    if args.res < 4 {
        // Every spectrum gets a radial profile, of the annuli r = 1 … K/2 − 1: none below K = 4.
        return Err(Error::Usage(format!(
            "--res {} leaves the gallery's radial profiles empty (they hold the annuli r = 1 to K/2 - 1); give --res 4 or more, e.g. --res 128",
            args.res
        )));
    }
    check_res(args.res)?;
    crate::stats::check_realizations("--realizations", args.realizations)?;
    if args.realizations == 0 {
        return Err(Error::Usage(
            "--realizations 0 averages nothing; give at least 1 (2 or more for standard errors), e.g. --realizations 64".into(),
        ));
    }
    let method = Method::nufft(args.eps)?;
    // Every sampler's N is checked before the folder is made: bad input leaves nothing behind.
    crate::points::coordinate_count(1, args.n, 4).map_err(Error::Usage)?;
    let jobs: Vec<(&str, usize, Projection)> = GALLERY_2D
        .iter()
        .map(|&s| (s, 2, Projection::XY))
        .chain(GALLERY_4D.iter().map(|&s| (s, 4, Projection::XU)))
        .collect();
    let mut built = Vec::with_capacity(jobs.len());
    for (name, dims, proj) in jobs {
        let sampler = samplers::build(name, dims)?;
        let n = usable_n(sampler.as_ref(), args.n);
        samplers::validate_n(sampler.as_ref(), n)?;
        built.push((name, sampler, n, dims, proj));
    }
    crate::output::check_folder(&args.out, "--out", "gallery")?;
    let gallery = args.out.join("gallery");
    // The folder the gallery goes into is --out/gallery: a file there is named as that folder.
    crate::output::check_folder_fixed_by(
        &gallery,
        "the gallery folder",
        "gallery",
        "move that file, or give --out another folder",
    )?;
    crate::output::check_report_folder(&gallery, GALLERY_MARKER)?;
    // Every file the gallery writes, checked before any spectrum is computed: one of yours where it
    // goes stops the run now, not after the work.
    let stem_of =
        |name: &str, dims: usize, proj: Projection| format!("{dims}d_{name}_{}", proj.name());
    let places: Vec<(PathBuf, bool)> = built
        .iter()
        .flat_map(|(name, _, _, dims, proj)| {
            let stem = stem_of(name, *dims, *proj);
            ["png", "npy"]
                .map(|ext| format!("{stem}.{ext}"))
                .into_iter()
                .chain([format!("{stem}_radial.csv")])
        })
        .chain(SHEETS.map(|(_, file, _)| file.to_string()))
        .chain([GALLERY_MARKER.file.to_string()])
        .map(|file| (PathBuf::from(file), false))
        .collect();
    crate::output::check_report_places(&gallery, GALLERY_MARKER, &places)?;
    // The whole gallery or nothing: a failure leaves an earlier one as it was.
    write_folder(&gallery, GALLERY_MARKER, |dir| {
        let mut rows = Vec::new();
        let mut spectra = Vec::new();
        let mut dark_noted = false;
        for (name, sampler, n, dims, proj) in &built {
            let (n, dims, proj) = (*n, *dims, *proj);
            let started = std::time::Instant::now();
            let spec = of_sampler(
                sampler.as_ref(),
                n,
                proj,
                args.res,
                args.realizations,
                args.seed,
                method,
            )?;
            let stem = stem_of(name, dims, proj);
            let outputs = [
                dir.join(format!("{stem}.png")),
                dir.join(format!("{stem}.npy")),
            ];
            super::spectrum::write_spectrum(
                &spec,
                &super::spectrum::sampler_identity(sampler.as_ref(), proj, args.seed),
                &outputs,
                &[ImageKind::Png, ImageKind::Npy],
            )?;
            let profile = radial_profile(&spec, 8, method);
            write_radial_csv(&dir.join(format!("{stem}_radial.csv")), &profile)?;
            if !dark_noted {
                if let Some(note) = dark_withheld_note(&profile, method, n) {
                    crate::eprintln_best_effort!("{note} (said once for the gallery)");
                    dark_noted = true;
                }
            }
            crate::eprintln_best_effort!(
                "{stem}: N = {n}, {:.2} s",
                started.elapsed().as_secs_f64()
            );
            rows.push((sampler.name(), dims, proj.name(), n, stem));
            // Only the mean goes on the sheets: the rest is dropped now, not held for every sampler.
            spectra.push(spec.mean);
        }
        for (dims, file, title) in SHEETS {
            let panels: Vec<Panel> = rows
                .iter()
                .zip(&spectra)
                .filter(|(row, _)| row.1 == dims)
                .map(|(row, mean)| Panel {
                    label: format!("{} N={}", row.0, row.3),
                    values: mean,
                    res: args.res,
                })
                .collect();
            let title = format!(
                "Expected power spectra: {title}, K = {}, {} realizations",
                args.res, args.realizations
            );
            write_sheet(&dir.join(file), &title, &panels, 5)?;
        }
        write_atomic(&dir.join(GALLERY_MARKER.file), |w| {
            writeln!(w, "{}\n", GALLERY_MARKER.first_line)?;
            writeln!(
                w,
                "{} realizations each, K = {}, NUFFT eps = {}, seed {}. PNG: {}.\n",
                args.realizations,
                args.res,
                crate::error::number(args.eps),
                args.seed,
                crate::output::image::spectrum_png_key()
            )?;
            let sheets: Vec<String> = SHEETS
                .iter()
                .map(|(_, file, title)| format!("[{title}]({file})"))
                .collect();
            writeln!(w, "Contact sheets: {}.\n", sheets.join(", "))?;
            writeln!(
                w,
                "| sampler | D | projection | N | spectrum | radial profile |"
            )?;
            writeln!(w, "|---|---|---|---|---|---|")?;
            for (name, dims, proj, n, stem) in &rows {
                writeln!(
                    w,
                    "| {name} | {dims} | {proj} | {n} | ![{stem}]({stem}.png) | [{stem}_radial.csv]({stem}_radial.csv) |"
                )?;
            }
            Ok(())
        })
    })?;
    let index = gallery.join(GALLERY_MARKER.file);
    crate::eprintln_best_effort!("gallery written to {}", index.display());
    Ok(())
}
