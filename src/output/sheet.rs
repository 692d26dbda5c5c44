//! Contact sheets: several spectra side by side in one labelled PNG, tone-mapped like
//! [`super::image::write_spectrum_png`] (log10 P over [`super::image::LOG_RANGE`], larger `k2` on top),
//! each panel with its frequency axes and the sheet with a colour bar of the tone map.

use super::image::{spectrum_image_rows, tone_map_log, write_png, LOG_RANGE};
use super::plot::{draw_text, short_numbers, text_width, wrap};
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

/// Side of one panel's picture, pixels.
const PANEL: usize = 192;
/// Room left of each picture for the `k2` tick labels, pixels.
const AXIS_LEFT: usize = 30;
/// Room under each picture for the `k1` tick marks and labels, pixels.
const AXIS_BOTTOM: usize = 19;
/// Length of a tick mark, pixels.
const TICK: usize = 3;
/// Size of the tick labels' text, pixels.
const TICK_TEXT: u32 = 11;
/// Room for a caption under each panel, pixels.
const CAPTION: usize = 22;
/// Room for a one-line title, pixels; each further line adds [`TITLE_LINE`].
const TITLE: usize = 34;
/// Line pitch of a title that wraps (20 px text), pixels.
const TITLE_LINE: usize = 24;
/// Height of the colour bar, pixels.
const BAR: usize = 10;
/// Room for the colour bar with its labels, pixels.
const BAR_ROW: usize = BAR + 28;
/// Line pitch of a footer that wraps (12 px text), pixels.
const FOOTER_LINE: usize = 16;
/// Gap between panels, pixels.
const GAP: usize = 8;

/// What the sheet's colour bar and axes mean (ASCII, the footer's text).
fn footer_text() -> String {
    "Each picture: P(k) at integer frequencies k = (k1, k2) of the projection named under it, k1 \
     along its first axis (right), k2 along its second (up), k = 0 at the centre."
        .to_string()
}

/// The frequencies that get a tick on an axis of `res` frequencies `−K/2 … K/2 − 1`: both ends,
/// `±K/4` and 0.
fn ticks(res: usize) -> Vec<i64> {
    let half = (res / 2) as i64;
    let mut t = vec![-half, -half / 2, 0, half / 2, half - 1];
    t.dedup();
    t
}

/// The image index (row from the top, or column from the left, `0 … K − 1`) a pixel `offset` of a
/// picture shows, for `res` frequencies over [`PANEL`] pixels: anchored at the centre, so that the
/// pixels either side of it show the indices `K/2 − 1` and `K/2` (the rows `k2 = 0` and `−1`, the
/// columns `k1 = −1` and `0`) at any `K`, also when a pixel spans several frequencies.
fn index_at(offset: usize, res: usize) -> usize {
    let (half_panel, half) = (PANEL / 2, res / 2);
    if offset >= half_panel {
        (half + (offset - half_panel) * res / PANEL).min(res - 1)
    } else {
        half.saturating_sub(1 + (half_panel - 1 - offset) * res / PANEL)
    }
}

/// The image index of frequency `k` along an axis of `res` frequencies: the column `k + K/2` for
/// `k1`, or with `up` the row `K/2 − 1 − k` for `k2` (larger `k2` on top).
fn index_of(k: i64, res: usize, up: bool) -> usize {
    let half = (res / 2) as i64;
    (if up { half - 1 - k } else { k + half }) as usize
}

/// Pixel offset (from the picture's left or top edge) of the tick of frequency `k`: the middle of
/// the pixels that show it, or, when no pixel does (more frequencies than pixels), the pixel showing
/// the nearest index.
fn tick_offset(k: i64, res: usize, up: bool) -> usize {
    let want = index_of(k, res, up);
    let showing: Vec<usize> = (0..PANEL).filter(|&o| index_at(o, res) == want).collect();
    if let (Some(first), Some(last)) = (showing.first(), showing.last()) {
        return (first + last) / 2;
    }
    (0..PANEL)
        .min_by_key(|&o| index_at(o, res).abs_diff(want))
        .unwrap_or(0)
}

/// A tick label: the frequency with a proper minus sign.
fn tick_label(k: i64) -> String {
    if k < 0 {
        format!("\u{2212}{}", -k)
    } else {
        k.to_string()
    }
}

/// Writes `panels` in rows of `columns` under `title` (its long numbers shortened, as in plots, and
/// wrapped at spaces to the sheet's width) as an RGB PNG. Each panel has tick marks and labels at
/// frequencies `−K/2, −K/4, 0, K/4, K/2 − 1` on both axes; under the panels a colour bar gives the tone map
/// (P from 10^LOG_RANGE.0 to 10^LOG_RANGE.1, log scale) and a footer says how to read the axes.
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
    let cell_width = AXIS_LEFT + PANEL;
    let cell_height = PANEL + AXIS_BOTTOM + CAPTION;
    let width = GAP + columns * (cell_width + GAP);
    let text_width_px = (width - 2 * GAP) as u32;
    let title = wrap(&short_numbers(title), 20, text_width_px);
    let footer = wrap(&footer_text(), 12, text_width_px);
    let top = TITLE + TITLE_LINE * (title.len() - 1);
    let footer_height = BAR_ROW + FOOTER_LINE * footer.len() + GAP;
    let height = top + rows * (cell_height + GAP) + footer_height;
    let mut buffer = vec![255u8; width * height * 3];
    let fail = |e: &dyn std::fmt::Display| {
        Error::Numerical(format!("cannot draw {}: {e}", path.display()))
    };
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width as u32, height as u32))
            .into_drawing_area();
        let text = |s: &str, x: usize, y: usize, size: u32, centred: bool| {
            draw_text(&root, s, (x as i32, y as i32), size, &BLACK, centred)
        };
        let pixel =
            |x: usize, y: usize, g: u8| root.draw_pixel((x as i32, y as i32), &RGBColor(g, g, g));
        for (i, line) in title.iter().enumerate() {
            text(line, GAP, 6 + i * TITLE_LINE, 20, false).map_err(|e| fail(&e))?;
        }
        for (p, panel) in panels.iter().enumerate() {
            let (col, row) = (p % columns, p / columns);
            let x0 = GAP + col * (cell_width + GAP) + AXIS_LEFT;
            let y0 = top + row * (cell_height + GAP);
            let img = spectrum_image_rows(panel.values, panel.res);
            for y in 0..PANEL {
                for x in 0..PANEL {
                    let v = img[index_at(y, panel.res) * panel.res + index_at(x, panel.res)];
                    pixel(x0 + x, y0 + y, tone_map_log(v)).map_err(|e| fail(&e))?;
                }
            }
            for k in ticks(panel.res) {
                let label = tick_label(k);
                // k1: a mark under the picture, its label under the mark.
                let x = x0 + tick_offset(k, panel.res, false);
                for d in 0..TICK {
                    pixel(x, y0 + PANEL + 1 + d, 0).map_err(|e| fail(&e))?;
                }
                text(&label, x, y0 + PANEL + TICK + 4, TICK_TEXT, true).map_err(|e| fail(&e))?;
                // k2: a mark left of the picture, its label left of the mark.
                let y = y0 + tick_offset(k, panel.res, true);
                for d in 1..=TICK {
                    pixel(x0 - d, y, 0).map_err(|e| fail(&e))?;
                }
                let label_x = x0 - TICK - 2 - text_width(&label, TICK_TEXT) as usize;
                let label_y = (y + 1).saturating_sub(TICK_TEXT as usize / 2 + 1);
                text(&label, label_x, label_y, TICK_TEXT, false).map_err(|e| fail(&e))?;
            }
            text(&panel.label, x0, y0 + PANEL + AXIS_BOTTOM + 3, 14, false)
                .map_err(|e| fail(&e))?;
        }
        // The colour bar: the tone map itself, drawn pixel column by pixel column.
        let bar_x = GAP + AXIS_LEFT;
        let bar_y = height - footer_height + 4;
        let (lo, hi) = LOG_RANGE;
        let at = |log_p: f64| bar_x + ((log_p - lo) / (hi - lo) * (PANEL - 1) as f64) as usize;
        for x in 0..PANEL {
            let log_p = lo + (x as f64 + 0.5) / PANEL as f64 * (hi - lo);
            let g = tone_map_log(10f64.powf(log_p));
            for y in 0..BAR {
                pixel(bar_x + x, bar_y + y, g).map_err(|e| fail(&e))?;
            }
        }
        for decade in (lo.ceil() as i32)..=(hi.floor() as i32) {
            let x = at(f64::from(decade));
            for d in 0..TICK {
                pixel(x, bar_y + BAR + d, 0).map_err(|e| fail(&e))?;
            }
            let places = usize::try_from(-decade).unwrap_or(0);
            let label = format!("{:.places$}", 10f64.powi(decade));
            text(&label, x, bar_y + BAR + TICK + 4, TICK_TEXT, true).map_err(|e| fail(&e))?;
        }
        text(
            "P, log scale, clamped outside this range (white noise: P = 1)",
            bar_x + PANEL + 2 * GAP,
            bar_y - 1,
            12,
            false,
        )
        .map_err(|e| fail(&e))?;
        for (i, line) in footer.iter().enumerate() {
            let y = height - footer_height + BAR_ROW + i * FOOTER_LINE;
            text(line, GAP, y, 12, false).map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    write_png(path, width, height, 3, &buffer)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_tick_sits_on_the_pixels_of_its_frequency_and_zero_is_always_drawn() {
        for res in [2, 4, 6, 32, 64, 100, 128, 256, 1000, 8192] {
            for up in [false, true] {
                // k = 0 and its neighbour −1 are drawn whatever K (before, K = 1000 skipped the
                // row k2 = 0).
                let shown: Vec<usize> = (0..PANEL).map(|o| index_at(o, res)).collect();
                for k in [0, -1] {
                    assert!(
                        shown.contains(&index_of(k, res, up)),
                        "K={res} up={up} k={k}"
                    );
                }
                for k in ticks(res) {
                    let at = index_at(tick_offset(k, res, up), res);
                    if shown.contains(&index_of(k, res, up)) {
                        assert_eq!(at, index_of(k, res, up), "K={res} k={k} up={up}");
                    } else {
                        // Not drawn (a pixel spans several frequencies): the nearest drawn one,
                        // within a pixel's span.
                        let off = at.abs_diff(index_of(k, res, up));
                        assert!(
                            off <= res.div_ceil(PANEL),
                            "K={res} k={k} up={up}: off by {off}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_sheet_draws_its_pictures_and_tick_marks_where_the_layout_puts_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sheet.png");
        let values = vec![1.0; 64 * 64];
        let panel = |label: &str| Panel {
            label: label.to_string(),
            values: &values,
            res: 64,
        };
        write_sheet(&path, "two panels", &[panel("a"), panel("b")], 2).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut rgb).unwrap();
        let width = frame.width as usize;
        assert_eq!(width, GAP + 2 * (AXIS_LEFT + PANEL + GAP));
        let grey = |x: usize, y: usize| rgb[(y * width + x) * 3];
        // The second panel: P = 1 is light grey inside the picture, the k1 = 0 and k2 = 0 tick
        // marks are black just outside it.
        let (x0, y0) = (GAP + (AXIS_LEFT + PANEL + GAP) + AXIS_LEFT, TITLE);
        assert_eq!(grey(x0 + PANEL / 2, y0 + PANEL / 2), tone_map_log(1.0));
        assert_eq!(grey(x0 + tick_offset(0, 64, false), y0 + PANEL + 1), 0);
        assert_eq!(grey(x0 - 1, y0 + tick_offset(0, 64, true)), 0);
    }
}
