//! Contact sheets: several spectra side by side in one labelled PNG, tone-mapped like
//! [`super::image::write_spectrum_png`] (log10 P over [`super::image::LOG_RANGE`], larger `k2` on top).

use super::image::{spectrum_image_rows, tone_map_log, write_png};
use super::plot::{draw_text, short_numbers, wrap};
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
/// Room for a one-line title, pixels; each further line adds [`TITLE_LINE`].
const TITLE: usize = 34;
/// Line pitch of a title that wraps (20 px text), pixels.
const TITLE_LINE: usize = 24;
/// Line pitch of a footer that wraps (12 px text), pixels.
const FOOTER_LINE: usize = 16;
/// Gap between panels, pixels.
const GAP: usize = 8;

/// Writes `panels` in rows of `columns` under `title` (its long numbers shortened, as in plots, and
/// wrapped at spaces to the sheet's width) as an RGB PNG, with the tone map stated in a footer (also
/// wrapped).
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
    let text_width = (width - 2 * GAP) as u32;
    let title = wrap(&short_numbers(title), 20, text_width);
    let footer = wrap(&super::image::spectrum_png_key(), 12, text_width);
    let top = TITLE + TITLE_LINE * (title.len() - 1);
    let footer_height = CAPTION + FOOTER_LINE * (footer.len() - 1);
    let height = top + rows * (PANEL + CAPTION + GAP) + footer_height;
    let mut buffer = vec![255u8; width * height * 3];
    let fail = |e: &dyn std::fmt::Display| {
        Error::Numerical(format!("cannot draw {}: {e}", path.display()))
    };
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width as u32, height as u32))
            .into_drawing_area();
        let text = |s: &str, x: usize, y: usize, size: u32| {
            draw_text(&root, s, (x as i32, y as i32), size, &BLACK, false)
        };
        for (i, line) in title.iter().enumerate() {
            text(line, GAP, 6 + i * TITLE_LINE, 20).map_err(|e| fail(&e))?;
        }
        for (p, panel) in panels.iter().enumerate() {
            let (col, row) = (p % columns, p / columns);
            let x0 = GAP + col * (PANEL + GAP);
            let y0 = top + row * (PANEL + CAPTION + GAP);
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
        for (i, line) in footer.iter().enumerate() {
            let y = height - footer_height + 3 + i * FOOTER_LINE;
            text(line, GAP, y, 12).map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    write_png(path, width, height, 3, &buffer)
}
