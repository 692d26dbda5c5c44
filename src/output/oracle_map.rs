//! The depth oracle as a picture (DESIGN §5): each pixel's class beside its shear, with a legend
//! and a colour bar (the `oracle` command's `FILE.png`).

use super::image::write_png_described;
use super::plot::{draw_text, register_font, short_number, text_width, wrap};
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// Colours of the classes, in class order (in focus, hairline, double wedge), with their names.
pub const CLASS_COLOURS: [(&str, (u8, u8, u8)); 3] = [
    ("grey", (200, 200, 200)),
    ("blue", (31, 119, 180)),
    ("orange", (255, 127, 14)),
];
/// Colour of the most negative shear of the map (blue); 0 is white.
const NEGATIVE: (u8, u8, u8) = (33, 102, 172);
/// Colour of the most positive shear of the map (red).
const POSITIVE: (u8, u8, u8) = (178, 24, 43);
/// A scene smaller than this on its longer side is scaled up by an integer factor to reach it, pixels.
const MIN_SIDE: usize = 256;
/// A scene larger than this on its longer side is scaled down to it, pixels.
const MAX_SIDE: usize = 512;
/// Gap around and between the panels, pixels.
const GAP: usize = 8;
/// Smallest width of each panel's column, pixels: its caption, legend or colour bar fit in it
/// however narrow the scene (a 16 x 256 scene's panel is 16 px wide).
const MIN_COLUMN: usize = 250;
/// Room for one line of the title (18 px text), pixels.
const TITLE_LINE: usize = 24;
/// Room for a panel's caption above it, pixels.
const CAPTION: usize = 22;
/// Room for one legend row under the class panel, pixels.
const LEGEND_ROW: usize = 18;
/// Height of the shear's colour bar, pixels.
const BAR: usize = 10;

/// The oracle of a `width × height` scene, per pixel in rows from the top.
pub struct OracleMaps<'a> {
    /// Scene size `[width, height]`, pixels.
    pub size: [usize; 2],
    /// Each pixel's class, an index into `class_names` (and [`CLASS_COLOURS`]).
    pub classes: &'a [usize],
    /// The classes' names, at most [`CLASS_COLOURS`]`.len()`.
    pub class_names: &'a [&'a str],
    /// Each pixel's shear `sx`, pixels per lens width.
    pub shear: &'a [f64],
}

/// The side of a panel showing `side` scene pixels, and the scale from scene to panel pixels.
fn panel_scale(width: usize, height: usize) -> f64 {
    let longer = width.max(height).max(1);
    if longer < MIN_SIDE {
        MIN_SIDE.div_ceil(longer) as f64
    } else if longer > MAX_SIDE {
        MAX_SIDE as f64 / longer as f64
    } else {
        1.0
    }
}

/// The colour of `shear` on a blue (negative), white (0), red (positive) scale reaching full colour
/// at `±limit`; black for a shear that is not finite.
fn shear_colour(shear: f64, limit: f64) -> RGBColor {
    if !shear.is_finite() {
        return BLACK;
    }
    let t = (shear / limit).clamp(-1.0, 1.0);
    let end = if t < 0.0 { NEGATIVE } else { POSITIVE };
    let mix = |c: u8| (255.0 + t.abs() * (f64::from(c) - 255.0)).round() as u8;
    RGBColor(mix(end.0), mix(end.1), mix(end.2))
}

/// Writes the class map (legend with each class's pixel count under it) beside the shear map
/// (colour bar from `−max |sx|` to `+max |sx|` under it) as an RGB PNG under `title`, with a text
/// description of the colours stored in the file.
pub fn write_oracle_png(path: &Path, title: &str, maps: &OracleMaps) -> Result<()> {
    let [w, h] = maps.size;
    let pixels = w * h;
    if pixels == 0
        || maps.classes.len() != pixels
        || maps.shear.len() != pixels
        || maps.class_names.len() > CLASS_COLOURS.len()
        || maps.classes.iter().any(|&c| c >= maps.class_names.len())
    {
        return Err(Error::Numerical(format!(
            "{}: an oracle map needs one class (of at most {}) and one shear per pixel of a non-empty scene",
            path.display(),
            CLASS_COLOURS.len()
        )));
    }
    register_font();
    let scale = panel_scale(w, h);
    let (pw, ph) = (
        ((w as f64 * scale).round() as usize).max(1),
        ((h as f64 * scale).round() as usize).max(1),
    );
    let scene_at = |x: usize, y: usize| {
        let sx = (((x as f64 + 0.5) / scale) as usize).min(w - 1);
        let sy = (((y as f64 + 0.5) / scale) as usize).min(h - 1);
        sy * w + sx
    };
    let limit = maps
        .shear
        .iter()
        .filter(|s| s.is_finite())
        .fold(0.0f64, |m, s| m.max(s.abs()));
    let limit = if limit > 0.0 { limit } else { 1.0 };
    let column = pw.max(MIN_COLUMN);
    let width = 3 * GAP + 2 * column;
    let title_lines = wrap(title, 18, (width - 2 * GAP) as u32);
    let top = GAP + TITLE_LINE * title_lines.len() + CAPTION;
    let under = (LEGEND_ROW * maps.class_names.len()).max(BAR + 40);
    let height = top + ph + GAP + under + GAP;
    let mut buffer = vec![255u8; width * height * 3];
    let fail = |e: &dyn std::fmt::Display| {
        Error::Numerical(format!("cannot draw {}: {e}", path.display()))
    };
    let counts: Vec<usize> = (0..maps.class_names.len())
        .map(|c| maps.classes.iter().filter(|&&k| k == c).count())
        .collect();
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width as u32, height as u32))
            .into_drawing_area();
        let text = |s: &str, x: usize, y: usize, size: u32| {
            draw_text(&root, s, (x as i32, y as i32), size, &BLACK, false)
        };
        let pixel = |x: usize, y: usize, c: RGBColor| root.draw_pixel((x as i32, y as i32), &c);
        for (i, line) in title_lines.iter().enumerate() {
            text(line, GAP, GAP + i * TITLE_LINE, 18).map_err(|e| fail(&e))?;
        }
        let (left, right) = (GAP, 2 * GAP + column);
        text("class", left, top - CAPTION + 4, 14).map_err(|e| fail(&e))?;
        text(
            "shear sx (pixels per lens width)",
            right,
            top - CAPTION + 4,
            14,
        )
        .map_err(|e| fail(&e))?;
        for y in 0..ph {
            for x in 0..pw {
                let i = scene_at(x, y);
                let (r, g, b) = CLASS_COLOURS[maps.classes[i]].1;
                pixel(left + x, top + y, RGBColor(r, g, b)).map_err(|e| fail(&e))?;
                pixel(right + x, top + y, shear_colour(maps.shear[i], limit))
                    .map_err(|e| fail(&e))?;
            }
        }
        // The legend: a swatch per class with its name and pixel count.
        for (c, name) in maps.class_names.iter().enumerate() {
            let y = top + ph + GAP + c * LEGEND_ROW;
            let (r, g, b) = CLASS_COLOURS[c].1;
            for dy in 0..12 {
                for dx in 0..12 {
                    pixel(left + dx, y + dy, RGBColor(r, g, b)).map_err(|e| fail(&e))?;
                }
            }
            text(&format!("{name}: {} px", counts[c]), left + 18, y - 1, 13)
                .map_err(|e| fail(&e))?;
        }
        // The colour bar, the width of its column: the shear map's own colours from −limit to
        // +limit, with both ends and 0.
        let bar_y = top + ph + GAP;
        let bar = column;
        for x in 0..bar {
            let s = -limit + (x as f64 + 0.5) / bar as f64 * 2.0 * limit;
            for dy in 0..BAR {
                pixel(right + x, bar_y + dy, shear_colour(s, limit)).map_err(|e| fail(&e))?;
            }
        }
        for (at, value) in [(0, -limit), (bar / 2, 0.0), (bar - 1, limit)] {
            for dy in 0..3 {
                pixel(right + at, bar_y + BAR + dy, BLACK).map_err(|e| fail(&e))?;
            }
            let label = if value == 0.0 {
                "0".to_string()
            } else {
                short_number(value)
            };
            // The end labels stay within the bar: the left one starts at it, the right one ends at it.
            let centred = at == bar / 2;
            let x = match at {
                0 => right,
                a if a == bar - 1 => (right + bar).saturating_sub(text_width(&label, 12) as usize),
                a => right + a,
            };
            draw_text(
                &root,
                &label,
                (x as i32, (bar_y + BAR + 5) as i32),
                12,
                &BLACK,
                centred,
            )
            .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    let key = format!(
        "Depth oracle of a {w} x {h} scene. Left: class per pixel ({}). Right: shear sx in pixels per lens width, blue {} to white 0 to red {}.",
        maps.class_names
            .iter()
            .zip(&counts)
            .zip(CLASS_COLOURS)
            .map(|((name, n), (colour, _))| format!("{name} {colour}, {n} px"))
            .collect::<Vec<_>>()
            .join("; "),
        short_number(-limit),
        short_number(limit)
    );
    write_png_described(path, [width, height], 3, &buffer, Some(key))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The oracle PNG of `maps`, titled "oracle", read back.
    fn drawn(maps: &OracleMaps) -> crate::output::image::DecodedPng {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("o.png");
        write_oracle_png(&path, "oracle", maps).unwrap();
        crate::output::image::decode_png(&path)
    }

    fn rgb(data: &[u8], width: usize, x: usize, y: usize) -> (u8, u8, u8) {
        let i = 3 * (y * width + x);
        (data[i], data[i + 1], data[i + 2])
    }

    #[test]
    fn each_pixel_shows_its_class_and_shear() {
        // A 4 x 2 scene: classes 0 1 2 0 / 2 2 1 0, shears from −1 to 0.5.
        let classes = [0, 1, 2, 0, 2, 2, 1, 0];
        let shear = [-1.0, -0.5, 0.0, 0.5, 0.25, f64::NAN, -0.25, 0.0];
        let maps = OracleMaps {
            size: [4, 2],
            classes: &classes,
            class_names: &["in-focus", "hairline", "double-wedge"],
            shear: &shear,
        };
        let png = drawn(&maps);
        let (width, data) = (png.width, &png.data);
        // Scaled up by 64: scene pixel (x, y) is the 64-pixel block at (GAP + 64x, top + 64y).
        let scale = 64;
        assert_eq!(panel_scale(4, 2), scale as f64);
        let top = GAP + TITLE_LINE + CAPTION;
        let right = 2 * GAP + 4 * scale;
        for y in 0..2 {
            for x in 0..4 {
                let i = y * 4 + x;
                let (px, py) = (x * scale + scale / 2, top + y * scale + scale / 2);
                assert_eq!(
                    rgb(data, width, GAP + px, py),
                    CLASS_COLOURS[classes[i]].1,
                    "class of ({x}, {y})"
                );
                let c = shear_colour(shear[i], 1.0);
                assert_eq!(
                    rgb(data, width, right + px, py),
                    (c.0, c.1, c.2),
                    "shear of ({x}, {y})"
                );
            }
        }
        // The ends of the scale: full blue at −1 (the largest |sx|), white at 0, black for NaN.
        assert_eq!(shear_colour(-1.0, 1.0), RGBColor(33, 102, 172));
        assert_eq!(shear_colour(0.0, 1.0), WHITE);
        assert_eq!(shear_colour(f64::NAN, 1.0), BLACK);
        let text = png.description.unwrap_or_default();
        assert!(text.contains("hairline blue, 2 px"), "{text}");
    }

    /// A narrow scene's panels stand in columns wide enough for their captions, legend and colour
    /// bar: the bar starts at the right column and spans it, clear of the legend.
    #[test]
    fn a_narrow_scene_keeps_its_legend_and_colour_bar_apart() {
        let (w, h) = (1, 8);
        let classes = [0, 1, 2, 0, 1, 2, 0, 1];
        let shear = [-2.0, -1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0];
        let maps = OracleMaps {
            size: [w, h],
            classes: &classes,
            class_names: &["in-focus", "hairline", "double-wedge"],
            shear: &shear,
        };
        let png = drawn(&maps);
        let (width, data) = (png.width, &png.data);
        assert_eq!(width, 3 * GAP + 2 * MIN_COLUMN);
        // Scaled by 32: a 32 x 256 panel; the bar's row lies under it, in the right column.
        let top = GAP + TITLE_LINE + CAPTION;
        let (right, bar_y) = (2 * GAP + MIN_COLUMN, top + 256 + GAP + BAR / 2);
        let c = shear_colour(-2.0 + 0.5 / MIN_COLUMN as f64 * 4.0, 2.0);
        assert_eq!(rgb(data, width, right, bar_y), (c.0, c.1, c.2));
        let last = -2.0 + (MIN_COLUMN as f64 - 0.5) / MIN_COLUMN as f64 * 4.0;
        let c = shear_colour(last, 2.0);
        assert_eq!(
            rgb(data, width, right + MIN_COLUMN - 1, bar_y),
            (c.0, c.1, c.2)
        );
        // Between the columns (the gap after the left column's legend) nothing is drawn.
        assert_eq!(
            rgb(data, width, GAP + MIN_COLUMN + GAP / 2, bar_y),
            (255, 255, 255)
        );
    }

    #[test]
    fn large_scenes_are_scaled_down_and_small_ones_up() {
        assert_eq!(panel_scale(64, 64), 4.0);
        assert_eq!(panel_scale(300, 200), 1.0);
        assert_eq!(panel_scale(1024, 512), 0.5);
        assert_eq!(panel_scale(1, 1), 256.0);
    }
}
