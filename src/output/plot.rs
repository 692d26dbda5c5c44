//! Line plots with a log vertical axis written as PNG (log-log, or linear-log for a signed horizontal
//! quantity): several series, each with a label and optional error bars, axis labels, a title and a
//! legend in a column right of the axes, where it covers no data. Text is drawn with DejaVu Sans embedded in the binary (plotters'
//! `ab_glyph` backend), so no system font is needed.

use crate::error::{Error, Result};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;
use std::sync::Once;

/// One line of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text, e.g. `jittered: slope -1.51 [-1.55, -1.47]`.
    pub label: String,
    /// `(x, y)` points: `y` positive, and `x` too on a log axis (points that are not are skipped).
    pub points: Vec<(f64, f64)>,
    /// Optional symmetric error bars (`y ± e`), one per point.
    pub errors: Option<Vec<f64>>,
    /// Draw dashed, without markers (for reference lines such as `N^-1`).
    pub dashed: bool,
    /// Index into [`PALETTE`] (`None`: the series' own position in the plot), so that two series can
    /// share a colour.
    pub colour: Option<usize>,
}

/// Twelve colours that stay apart from one another (Tableau 10, then black and dark gold), used in
/// order and then again with hollow markers.
pub const PALETTE: [(u8, u8, u8); 12] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
    (0, 0, 0),
    (184, 134, 11),
];

/// How the horizontal axis is scaled (the vertical one is always logarithmic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XScale {
    /// Logarithmic, for positive values such as N or a time.
    Log,
    /// Linear, for values of either sign such as a relative error.
    Linear,
}

/// A plot with a log vertical axis.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLogPlot {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// The lines, drawn in order, coloured from a fixed palette.
    pub series: Vec<Series>,
    /// Width of the axes with their labels, pixels: the image is wider by the legend's column (as wide
    /// as its longest label), or columns when its entries do not fit the height.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// How the horizontal axis is scaled.
    pub x_scale: XScale,
}

static FONT: Once = Once::new();

/// Registers the embedded DejaVu Sans as the "sans-serif" font (once per process).
pub fn register_font() {
    FONT.call_once(|| {
        // The embedded font is valid; a failure here would only lose text, never the plot.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Numerical(format!("cannot draw the plot {}: {e}", path.display()))
}

/// Margin around the axes, pixels.
const MARGIN: u32 = 12;
/// Height of the horizontal axis's label area, pixels.
const X_LABEL_AREA: u32 = 45;
/// Width of the vertical axis's label area, pixels.
const Y_LABEL_AREA: u32 = 80;
/// Height of the title's band above the axes (22 px text and its padding), pixels.
const TITLE_BAND: u32 = 40;
/// Height of one legend entry (14 px text), pixels.
const LEGEND_ROW: u32 = 20;
/// Length of a legend entry's line sample, pixels; the text starts [`MARGIN`] after it.
const SWATCH: u32 = 24;

/// The legend's place right of the axes: entries top down from the axes' top edge, in as many columns
/// as the plot's height needs.
struct LegendLayout {
    /// Entries per column.
    rows: usize,
    /// Columns.
    columns: u32,
    /// Width of one column (sample, text and margins), pixels.
    column_width: u32,
}

impl LegendLayout {
    fn new(plot: &LogLogPlot) -> std::result::Result<Self, String> {
        let font = ("sans-serif", 14).into_font();
        let mut text = 0;
        for s in &plot.series {
            let (w, _) = font.box_size(&s.label).map_err(|e| format!("{e:?}"))?;
            text = text.max(w);
        }
        let room = plot
            .height
            .saturating_sub(TITLE_BAND + 2 * MARGIN + X_LABEL_AREA);
        let rows = (room / LEGEND_ROW).max(1) as usize;
        Ok(LegendLayout {
            rows,
            columns: plot.series.len().div_ceil(rows) as u32,
            column_width: SWATCH + text + 2 * MARGIN,
        })
    }

    /// Width of all the columns, pixels.
    fn width(&self) -> u32 {
        self.columns * self.column_width
    }
}

/// A series' colour, and the style of its markers: the palette in order, then round again with hollow
/// markers.
fn series_style(s: &Series, index: usize) -> (RGBAColor, ShapeStyle) {
    let slot = s.colour.unwrap_or(index);
    let (r, g, b) = PALETTE[slot % PALETTE.len()];
    let colour = RGBColor(r, g, b).to_rgba();
    let marker = if (slot / PALETTE.len()).is_multiple_of(2) {
        colour.filled()
    } else {
        colour.stroke_width(2)
    };
    (colour, marker)
}

/// The axis range `[lo, hi]` padded by a fraction of a decade on each side, and widened to the
/// enclosing decades when it holds no power of ten: plotters puts the vertical axis's labels at the
/// powers of ten in range (and between them), and [`log_ticks`] falls back on them, so a range inside
/// one decade (N = 16 to 64) would otherwise get an axis with no label at all.
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return None;
    }
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo / 2.0, hi * 2.0)
    };
    let pad = ((hi / lo).log10() * 0.05).max(0.05);
    let (lo, hi) = (lo / 10f64.powf(pad), hi * 10f64.powf(pad));
    if 10f64.powf(lo.log10().ceil()) <= hi {
        Some((lo, hi))
    } else {
        Some((
            10f64.powf(lo.log10().floor()),
            10f64.powf(hi.log10().ceil()),
        ))
    }
}

/// `v` with at most 4 significant digits, trailing zeros dropped: plain from 0.001 to 99999
/// (`0.6830127018922193` → `0.683`, `1234.5` → `1235`), else in scientific notation (`1.235e-5`).
pub fn short_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let trim = |t: String| -> String {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    };
    // Round first, so that 99999.5 becomes 1e5 before the notation is chosen.
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    let magnitude = rounded.abs().log10().floor();
    if (-3.0..5.0).contains(&magnitude) {
        let decimals = (3.0 - magnitude).max(0.0) as usize;
        trim(format!("{rounded:.decimals$}"))
    } else {
        let text = format!("{rounded:.3e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        format!("{}e{exponent}", trim(mantissa.to_string()))
    }
}

/// `text` with every decimal number of more than 4 significant digits (one with a point, as a float
/// prints: `c=0.6830127018922193`) written by [`short_number`]; integers and short numbers are kept as
/// they are. For titles built from names that hold computed parameters.
pub fn short_numbers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let starts_number = chars[i].is_ascii_digit()
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '.'));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let start = i;
        let digits = |mut j: usize| {
            while j < chars.len() && chars[j].is_ascii_digit() {
                j += 1;
            }
            j
        };
        i = digits(i);
        let mut has_point = false;
        if i + 1 < chars.len() && chars[i] == '.' && chars[i + 1].is_ascii_digit() {
            has_point = true;
            i = digits(i + 1);
            let sign = usize::from(i + 1 < chars.len() && matches!(chars[i + 1], '+' | '-'));
            if i + 1 + sign < chars.len()
                && matches!(chars[i], 'e' | 'E')
                && chars[i + 1 + sign].is_ascii_digit()
            {
                i = digits(i + 1 + sign);
            }
        }
        let token: String = chars[start..i].iter().collect();
        let significant = token
            .split(['e', 'E'])
            .next()
            .unwrap_or_default()
            .chars()
            .filter(char::is_ascii_digit)
            .skip_while(|&c| c == '0')
            .count();
        match token.parse::<f64>() {
            Ok(v) if has_point && significant > 4 => out.push_str(&short_number(v)),
            _ => out.push_str(&token),
        }
    }
    out
}

/// Where a log axis from `lo` to `hi` (`0 < lo < hi`) `pixels` long puts its labels: the first of
/// powers of two (for ranges of counts, `lo ≥ 1`), 1-2-5 in each decade, every decade, and every k-th
/// decade whose labels, as [`tick_label`] writes them in 14 px text, do not run into one another.
/// Every axis that [`log_range`] makes holds at least one of them.
fn log_ticks(lo: f64, hi: f64, pixels: f64) -> Vec<f64> {
    let (llo, lhi) = (lo.log10(), hi.log10());
    let at = |v: f64| (v.log10() - llo) / (lhi - llo) * pixels;
    // About 8 px per character at 14 px, and a gap of 16 px between labels.
    let width = |v: f64| 8.0 * tick_label(v).chars().count() as f64;
    let fits = |ticks: &[f64]| {
        ticks
            .windows(2)
            .all(|w| at(w[1]) - at(w[0]) >= (width(w[0]) + width(w[1])) / 2.0 + 16.0)
    };
    let inside = |v: &f64| lo <= *v && *v <= hi;
    let decades = (llo.floor() as i32)..=(lhi.ceil() as i32);
    let mut candidates: Vec<Vec<f64>> = Vec::new();
    if lo >= 1.0 {
        let twos = (lo.log2().ceil() as i32)..=(hi.log2().floor() as i32);
        candidates.push(twos.map(|k| 2f64.powi(k)).collect());
    }
    candidates.push(
        decades
            .clone()
            .flat_map(|d| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(d)))
            .filter(inside)
            .collect(),
    );
    for step in 1..=(lhi - llo).ceil().max(1.0) as i32 {
        candidates.push(
            decades
                .clone()
                .filter(|d| d.rem_euclid(step) == 0)
                .map(|d| 10f64.powi(d))
                .filter(inside)
                .collect(),
        );
    }
    candidates
        .iter()
        .find(|t| t.len() >= 2 && fits(t))
        .or_else(|| candidates.iter().rev().find(|t| !t.is_empty()))
        .cloned()
        .unwrap_or_default()
}

/// The label of a tick at `v`: a whole number as it is (up to 9999999), anything else by
/// [`short_number`].
fn tick_label(v: f64) -> String {
    if (1.0..1e7).contains(&v) && v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        short_number(v)
    }
}

/// The range `[lo, hi]` of a linear axis, padded by 4 % of its width on each side.
fn linear_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return None;
    }
    let pad = if hi > lo { 0.04 * (hi - lo) } else { 1.0 };
    Some((lo - pad, hi + pad))
}

/// Draws `plot` and writes it to `path` as an RGB PNG (atomically).
pub fn write_loglog_png(path: &Path, plot: &LogLogPlot) -> Result<()> {
    register_font();
    let x_log = plot.x_scale == XScale::Log;
    let keep = move |&(x, y): &(f64, f64)| {
        (x > 0.0 || !x_log) && y > 0.0 && x.is_finite() && y.is_finite()
    };
    let xs = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter().filter(|p| keep(p)).map(|p| p.0));
    let x_range = if x_log {
        log_range(xs)
    } else {
        linear_range(xs)
    };
    let ys = plot.series.iter().flat_map(|s| {
        let errs = s.errors.clone().unwrap_or_default();
        s.points
            .iter()
            .enumerate()
            .filter(|(_, p)| keep(p))
            .flat_map(move |(i, p)| {
                let e = errs.get(i).copied().unwrap_or(0.0);
                [p.1, p.1 + e, if p.1 - e > 0.0 { p.1 - e } else { p.1 }]
            })
    });
    let (Some((x0, x1)), Some((y0, y1))) = (x_range, log_range(ys)) else {
        return Err(Error::Numerical(format!(
            "nothing to plot in {}: no series has a point to draw",
            path.display()
        )));
    };
    let legend = LegendLayout::new(plot).map_err(|e| plot_error(path, e))?;
    let image_width = plot.width + legend.width();
    let (w, h) = (image_width as usize, plot.height as usize);
    let mut buffer = vec![0u8; w * h * 3];
    {
        let root =
            BitMapBackend::with_buffer(&mut buffer, (image_width, plot.height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error(path, e))?;
        // The title spans the axes and the legend, 5 px below the top edge (with plotters' 5 px of
        // padding either side of the 22 px text, a band of about TITLE_BAND); the rest is split
        // between the axes and the legend.
        let body = root
            .margin(5, 0, 0, 0)
            .titled(&short_numbers(&plot.title), ("sans-serif", 22))
            .map_err(|e| plot_error(path, e))?;
        let (axes, key) = body.split_horizontally(plot.width);
        let mut builder = ChartBuilder::on(&axes);
        builder
            .margin(MARGIN)
            .x_label_area_size(X_LABEL_AREA)
            .y_label_area_size(Y_LABEL_AREA);
        let y_axis = (y0..y1).log_scale();
        if x_log {
            // The axes' own width less the margins and the vertical axis's label area.
            let ticks = log_ticks(
                x0,
                x1,
                f64::from(plot.width) - f64::from(2 * MARGIN + Y_LABEL_AREA),
            );
            let minor: Vec<f64> = ((x0.log10().floor() as i32)..=(x1.log10().ceil() as i32))
                .flat_map(|d| (1..10).map(move |m| m as f64 * 10f64.powi(d)))
                .filter(|v| x0 <= *v && *v <= x1)
                .collect();
            let x_axis = (x0..x1)
                .log_scale()
                .with_key_points(ticks)
                .with_light_points(minor);
            let chart = builder
                .build_cartesian_2d(x_axis, y_axis)
                .map_err(|e| plot_error(path, e))?;
            draw(chart, plot, path, y0, keep, &|v| tick_label(*v))?;
        } else {
            let chart = builder
                .build_cartesian_2d(x0..x1, y_axis)
                .map_err(|e| plot_error(path, e))?;
            draw(chart, plot, path, y0, keep, &|v| format!("{v}"))?;
        }
        draw_legend(&key, plot, &legend).map_err(|e| plot_error(path, e))?;
        root.present().map_err(|e| plot_error(path, e))?;
    }
    super::image::write_png(path, w, h, 3, &buffer)
}

/// Draws the legend of `plot` on `area`, the band right of the axes: one entry per series, its line
/// sample (dashed, or solid with its marker) and its label, from the axes' top edge down.
fn draw_legend<'a>(
    area: &DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>,
    plot: &LogLogPlot,
    layout: &LegendLayout,
) -> std::result::Result<(), DrawingAreaErrorKind<<BitMapBackend<'a> as DrawingBackend>::ErrorType>>
{
    let text = ("sans-serif", 14)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let (row, swatch) = (LEGEND_ROW as i32, SWATCH as i32);
    for (i, s) in plot.series.iter().enumerate() {
        let (colour, marker) = series_style(s, i);
        let x = (i / layout.rows) as i32 * layout.column_width as i32 + MARGIN as i32 / 2;
        let y = MARGIN as i32 + (i % layout.rows) as i32 * row + row / 2;
        let line = colour.stroke_width(2);
        if s.dashed {
            // The plot's dashes: 8 px drawn, 6 px left out.
            for a in (0..swatch).step_by(14) {
                area.draw(&PathElement::new(vec![(x + a, y), (x + a + 8, y)], line))?;
            }
        } else {
            area.draw(&PathElement::new(vec![(x, y), (x + swatch, y)], line))?;
            area.draw(&Circle::new((x + swatch / 2, y), 4, marker))?;
        }
        area.draw(&Text::new(
            s.label.clone(),
            (x + swatch + MARGIN as i32 / 2, y),
            text.clone(),
        ))?;
    }
    Ok(())
}

/// Draws the mesh and the series of `plot` on `chart`, whatever its horizontal scale, with
/// `x_label` writing the horizontal axis's labels; `y0` is the bottom of the vertical axis (where an
/// error bar that would cross 0 ends).
fn draw<'a, X>(
    mut chart: ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, LogCoord<f64>>>,
    plot: &LogLogPlot,
    path: &Path,
    y0: f64,
    keep: impl Fn(&(f64, f64)) -> bool,
    x_label: &dyn Fn(&f64) -> String,
) -> Result<()>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_label_formatter(x_label)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| plot_error(path, e))?;
    for (i, s) in plot.series.iter().enumerate() {
        let (colour, marker) = series_style(s, i);
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| keep(p)).collect();
        let style = colour.stroke_width(2);
        if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(pts.clone(), 8, 6, style))
                .map_err(|e| plot_error(path, e))?;
        } else {
            chart
                .draw_series(LineSeries::new(pts.clone(), style))
                .map_err(|e| plot_error(path, e))?;
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, marker)))
                .map_err(|e| plot_error(path, e))?;
        }
        if let Some(errs) = &s.errors {
            let bars = s
                .points
                .iter()
                .zip(errs)
                .filter(|(p, _)| keep(p))
                .map(|(&(x, y), &e)| {
                    let lo = if y - e > 0.0 { y - e } else { y0 };
                    PathElement::new(vec![(x, lo), (x, y + e)], colour.stroke_width(1))
                });
            chart.draw_series(bars).map_err(|e| plot_error(path, e))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_lines_text_and_error_bars() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let plot = LogLogPlot {
            title: "test".into(),
            x_label: "N".into(),
            y_label: "MSE".into(),
            series: vec![
                Series {
                    label: "a: slope -1".into(),
                    points: vec![(16.0, 1e-2), (64.0, 2.5e-3), (256.0, 6e-4)],
                    errors: Some(vec![1e-3, 2e-4, 1e-4]),
                    dashed: false,
                    colour: None,
                },
                Series {
                    label: "N^-2".into(),
                    points: vec![(16.0, 1e-3), (256.0, 4e-6)],
                    errors: None,
                    dashed: true,
                    colour: None,
                },
            ],
            width: 640,
            height: 480,
            x_scale: XScale::Log,
        };
        write_loglog_png(&path, &plot).unwrap();
        let (width, height, buf) = read_rgb(&path);
        // The axes' 640 px and the legend's column right of them, with room for
        // (480 − 40 title − 2·12 margins − 45 axis labels) / 20 = 18 entries.
        let legend = LegendLayout::new(&plot).unwrap();
        assert_eq!((legend.rows, legend.columns), (18, 1));
        assert_eq!((width, height), (640 + legend.width(), 480));
        // Not blank: many non-white pixels, and several colours (lines, text).
        let non_white = buf.chunks(3).filter(|p| p != &[255, 255, 255]).count();
        assert!(non_white > 5000, "{non_white}");
        // The title row area holds dark text pixels (the embedded font renders).
        let dark_in_title = buf[..width as usize * 3 * 30]
            .chunks(3)
            .filter(|p| p[0] < 100 && p[1] < 100 && p[2] < 100)
            .count();
        assert!(dark_in_title > 20, "{dark_in_title}");
        assert!(write_loglog_png(
            &path,
            &LogLogPlot {
                series: vec![],
                ..plot
            }
        )
        .is_err());
    }

    /// The PNG at `path` as `(width, height, RGB bytes)`.
    fn read_rgb(path: &Path) -> (u32, u32, Vec<u8>) {
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        (info.width, info.height, buf)
    }

    /// The legend covers no data: below the title, the axes' pixels are the same whatever the labels
    /// (long ones widen only the legend's column), every series' colour is in that column, and a legend
    /// taller than the plot takes a second column.
    #[test]
    fn the_legend_sits_right_of_the_axes() {
        let dir = tempfile::tempdir().unwrap();
        let series = |label: &dyn Fn(usize) -> String, count: usize| -> Vec<Series> {
            (0..count)
                .map(|i| Series {
                    label: label(i),
                    // Falling lines through the lower left, where a legend inside the axes would sit.
                    points: vec![
                        (16.0, 1e-2 / (i + 1) as f64),
                        (1024.0, 1e-7 * (i + 1) as f64),
                    ],
                    errors: None,
                    dashed: i % 2 == 1,
                    colour: None,
                })
                .collect()
        };
        let plot = |series: Vec<Series>| LogLogPlot {
            title: "legend".into(),
            x_label: "N".into(),
            y_label: "MSE".into(),
            series,
            width: 640,
            height: 480,
            x_scale: XScale::Log,
        };
        let short = plot(series(&|i| format!("s{i}"), 6));
        let long = plot(series(
            &|i| format!("sampler number {i}: slope -1.98 [-2.07, -1.89]"),
            6,
        ));
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        write_loglog_png(&a, &short).unwrap();
        write_loglog_png(&b, &long).unwrap();
        let ((wa, ha, pa), (wb, hb, pb)) = (read_rgb(&a), read_rgb(&b));
        assert_eq!((ha, hb), (480, 480));
        assert!(wb > wa && wa > 640, "{wa} {wb}");
        let axes = |w: u32, px: &[u8]| -> Vec<u8> {
            (TITLE_BAND as usize..480)
                .flat_map(|y| px[y * w as usize * 3..(y * w as usize + 640) * 3].to_vec())
                .collect()
        };
        assert!(
            axes(wa, &pa) == axes(wb, &pb),
            "the labels changed the axes"
        );
        for (i, s) in long.series.iter().enumerate() {
            let (r, g, b) = PALETTE[s.colour.unwrap_or(i)];
            let in_legend = (0..480usize)
                .flat_map(|y| (640..wb as usize).map(move |x| (y * wb as usize + x) * 3))
                .filter(|&o| pb[o..o + 3] == [r, g, b])
                .count();
            assert!(in_legend >= 8, "series {i}: {in_legend} px of its colour");
        }
        let tall = plot(series(&|i| format!("s{i}"), 30));
        let layout = LegendLayout::new(&tall).unwrap();
        assert_eq!((layout.rows, layout.columns), (18, 2));
        let c = dir.path().join("c.png");
        write_loglog_png(&c, &tall).unwrap();
        assert_eq!(read_rgb(&c).0, 640 + 2 * layout.column_width);
    }

    /// A linear horizontal axis takes values of either sign (a log one would drop them all here).
    #[test]
    fn a_linear_axis_draws_signed_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let mut plot = LogLogPlot {
            title: "signed".into(),
            x_label: "error, %".into(),
            y_label: "MSE".into(),
            series: vec![Series {
                label: "v".into(),
                points: vec![(-25.0, 1e-5), (-10.0, 2e-6), (0.0, 1e-7)],
                errors: None,
                dashed: false,
                colour: None,
            }],
            width: 320,
            height: 240,
            x_scale: XScale::Linear,
        };
        write_loglog_png(&path, &plot).unwrap();
        plot.x_scale = XScale::Log;
        assert!(write_loglog_png(&path, &plot).is_err());
        assert_eq!(linear_range([-25.0, 25.0].into_iter()), Some((-27.0, 27.0)));
        assert_eq!(linear_range([3.0].into_iter()), Some((2.0, 4.0)));
    }

    /// Numbers in titles keep at most 4 significant digits; integers, short decimals and numbers inside
    /// words are left alone.
    #[test]
    fn titles_shorten_long_numbers_only() {
        for (v, want) in [
            (0.6830127018922193, "0.683"),
            (0.8415063509461096, "0.8415"),
            (1234.5678, "1235"),
            (99999.7, "1e5"),
            (1.234567e-5, "1.235e-5"),
            (-0.7111111, "-0.7111"),
            (2.5e7, "2.5e7"),
        ] {
            assert_eq!(short_number(v), want, "{v}");
        }
        for (title, want) in [
            (
                "Convergence on step:theta=30,c=0.6830127018922193",
                "Convergence on step:theta=30,c=0.683",
            ),
            (
                "sheared:s=-0.711,c=0.5@xu, N = 1024",
                "sheared:s=-0.711,c=0.5@xu, N = 1024",
            ),
            ("MSE 1.23456789e-5 at 65536", "MSE 1.235e-5 at 65536"),
            ("table v2.12345 and 3.14159265", "table v2.12345 and 3.142"),
        ] {
            assert_eq!(short_numbers(title), want);
        }
    }

    /// Log-axis labels: powers of two on a count axis that has room for them (the convergence plot's
    /// 16 to 1024, labelled from its first point), 1-2-5 on a time axis, decades where those would
    /// crowd; every label inside the axis, and no two closer than their half-widths and a gap.
    #[test]
    fn log_axis_labels_do_not_run_together() {
        let width = 1000.0 - 24.0 - 80.0;
        let (lo, hi) = log_range([16.0, 1024.0].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, width);
        assert_eq!(ticks, [16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0]);
        let labels: Vec<String> = ticks.iter().map(|&v| tick_label(v)).collect();
        assert_eq!(labels.join(" "), "16 32 64 128 256 512 1024");
        let (lo, hi) = log_range([2e-6, 3e-3].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, width);
        assert!(ticks.contains(&2e-6) && ticks.contains(&5e-5), "{ticks:?}");
        assert_eq!(tick_label(5e-5), "5e-5");
        let (lo, hi) = log_range([1.0, 1e6].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, 400.0);
        assert!(ticks.iter().all(|v| v.log10().fract() == 0.0), "{ticks:?}");
        for (values, pixels) in [
            (vec![16.0, 64.0], width),
            (vec![16.0, 1024.0], 300.0),
            (vec![4.0, 65536.0], width),
            (vec![1e-7, 10.0], width),
            (vec![1e-7, 10.0], 200.0),
            (vec![0.011, 0.09], width),
        ] {
            let (lo, hi) = log_range(values.iter().copied()).unwrap();
            let ticks = log_ticks(lo, hi, pixels);
            assert!(!ticks.is_empty(), "{values:?}");
            assert!(
                ticks.iter().all(|t| lo <= *t && *t <= hi),
                "{values:?}: {ticks:?}"
            );
            let at = |v: f64| (v / lo).log10() / (hi / lo).log10() * pixels;
            for w in ticks.windows(2) {
                let room = (tick_label(w[0]).len() + tick_label(w[1]).len()) as f64 * 4.0;
                assert!(
                    at(w[1]) - at(w[0]) > room,
                    "{values:?} at {pixels} px: {ticks:?}"
                );
            }
        }
    }

    /// Every axis range holds a power of ten (where plotters puts its labels) and all the values.
    #[test]
    fn log_ranges_hold_a_power_of_ten() {
        for values in [
            vec![16.0, 64.0],
            vec![2e-4, 8e-4],
            vec![3.0],
            vec![0.011, 0.09],
            vec![16.0, 1024.0],
            vec![1e-6, 1e-6],
        ] {
            let (lo, hi) = log_range(values.iter().copied()).unwrap();
            assert!(
                values.iter().all(|&v| lo < v && v < hi),
                "{values:?}: [{lo}, {hi}]"
            );
            let decade = 10f64.powf(lo.log10().ceil());
            assert!(
                decade <= hi,
                "{values:?}: [{lo}, {hi}] holds no power of ten"
            );
        }
        // Within a decade: the enclosing one, not more.
        assert_eq!(log_range([16.0, 64.0].into_iter()), Some((10.0, 100.0)));
    }
}
