//! Contact sheets: several spectra side by side in one labelled PNG, tone-mapped like
//! [`super::image::write_spectrum_png`] (log10 P over [`super::image::LOG_RANGE`], larger `k2` on top).

use super::image::{spectrum_image_rows, tone_map_log, write_png, LOG_RANGE};
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// One spectrum of a sheet.
#[derive(Clone, Debug)]
pub struct Panel<'a> {
    /// Caption under the spectrum, e.g. `padded-mj xu N=256`.
    pub label: String,
    /// `res × res` values, row `i` at `k2 = i − K/2` (the spectrum layout).
    pub values: &'a [f64],
    /// Grid side `K`.
    pub res: usize,
}

/// Side of one panel, pixels.
const PANEL: usize = 192;
/// Room for a caption under each panel, pixels.
const CAPTION: usize = 22;
/// Room for the title, pixels.
const TITLE: usize = 34;
/// Gap between panels, pixels.
const GAP: usize = 8;

/// Writes `panels` in rows of `columns` under `title` (its long numbers shortened, as in plots) as an
/// RGB PNG, with the tone map stated in a footer line.
pub fn write_sheet(path: &Path, title: &str, panels: &[Panel], columns: usize) -> Result<()> {
    if panels.is_empty() || columns == 0 {
        return Err(Error::Numerical(format!(
            "{}: a sheet needs at least one panel",
            path.display()
        )));
    }
    super::plot::register_font();
    let columns = columns.min(panels.len());
    let rows = panels.len().div_ceil(columns);
    let width = GAP + columns * (PANEL + GAP);
    let height = TITLE + rows * (PANEL + CAPTION + GAP) + CAPTION;
    let mut buffer = vec![255u8; width * height * 3];
    let fail = |e: &dyn std::fmt::Display| {
        Error::Numerical(format!("cannot draw {}: {e}", path.display()))
    };
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width as u32, height as u32))
            .into_drawing_area();
        let text = |s: &str, x: usize, y: usize, size: u32| {
            root.draw_text(
                s,
                &("sans-serif", size).into_font().color(&BLACK),
                (x as i32, y as i32),
            )
        };
        text(&super::plot::short_numbers(title), GAP, 6, 20).map_err(|e| fail(&e))?;
        for (p, panel) in panels.iter().enumerate() {
            let (col, row) = (p % columns, p / columns);
            let x0 = GAP + col * (PANEL + GAP);
            let y0 = TITLE + row * (PANEL + CAPTION + GAP);
            let img = spectrum_image_rows(panel.values, panel.res);
            for y in 0..PANEL {
                for x in 0..PANEL {
                    let v = img[(y * panel.res / PANEL) * panel.res + x * panel.res / PANEL];
                    let g = tone_map_log(v);
                    root.draw_pixel(((x0 + x) as i32, (y0 + y) as i32), &RGBColor(g, g, g))
                        .map_err(|e| fail(&e))?;
                }
            }
            text(&panel.label, x0, y0 + PANEL + 3, 14).map_err(|e| fail(&e))?;
        }
        let footer = format!(
            "log10 P from {} (black) to {} (white); P = 1 (white noise) mid-grey; k1 right, k2 up, k = 0 at the centre",
            LOG_RANGE.0, LOG_RANGE.1
        );
        text(&footer, GAP, height - CAPTION + 3, 12).map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    write_png(path, width, height, 3, &buffer)
}
