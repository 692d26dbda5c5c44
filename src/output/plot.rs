//! Line plots with a log vertical axis written as PNG (log-log, or linear-log for a signed horizontal
//! quantity): several series, each with a label and optional error bars, axis labels, a title and a
//! legend in a column right of the axes, where it covers no data (long labels wrap). Text is drawn
//! with DejaVu Sans embedded in the binary (plotters' `ab_glyph` backend), so no system font is needed.

use crate::error::{Error, Result};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;
use std::sync::Once;

/// One line of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text, e.g. `jittered: slope -1.51, 95% CI [-1.55, -1.47]`.
    pub label: String,
    /// `(x, y)` points: `y` positive, and `x` too on a log axis (points that are not are skipped,
    /// and the line is broken there).
    pub points: Vec<(f64, f64)>,
    /// Optional symmetric error bars (`y ± e`), one per point.
    pub errors: Option<Vec<f64>>,
    /// Draw dashed, without markers (for reference lines such as `N^-1`).
    pub dashed: bool,
    /// Index into [`PALETTE`] (`None`: the series' own position in the plot), so that two series can
    /// share a colour.
    pub colour: Option<usize>,
}

/// Twenty colours that stay apart from one another on white (Tableau 10, then black, navy, teal,
/// magenta, maroon, violet, lime, sky blue, dark olive and salmon), used in order and then again with
/// hollow markers. Each colour has its own marker shape in [`MARKERS`], chosen so that the colours
/// nearest one another (blue and navy or sky blue, cyan and teal, pink and magenta, brown and maroon,
/// purple and violet, green and lime) differ in shape too.
pub const PALETTE: [(u8, u8, u8); 20] = [
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
    (0, 0, 128),
    (0, 128, 128),
    (200, 0, 200),
    (128, 0, 0),
    (110, 50, 220),
    (90, 220, 60),
    (120, 170, 240),
    (85, 107, 47),
    (250, 128, 114),
];

/// A marker's shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A disc of radius 4 px.
    Circle,
    /// An 8 px square.
    Square,
    /// A triangle pointing up.
    TriangleUp,
    /// A square standing on a corner.
    Diamond,
    /// A triangle pointing down.
    TriangleDown,
}

/// The marker of each colour of [`PALETTE`].
pub const MARKERS: [Marker; 20] = {
    use Marker::*;
    [
        Circle,
        Square,
        TriangleUp,
        Diamond,
        TriangleDown,
        Circle,
        Square,
        TriangleUp,
        Diamond,
        TriangleDown,
        Square,
        TriangleUp,
        Circle,
        Diamond,
        TriangleDown,
        Circle,
        Square,
        Diamond,
        TriangleDown,
        TriangleUp,
    ]
};

impl Marker {
    /// The outline's corners around the point, pixels (`None` for the circle).
    fn corners(self) -> Option<Vec<(i32, i32)>> {
        match self {
            Marker::Circle => None,
            Marker::Square => Some(vec![(-4, -4), (4, -4), (4, 4), (-4, 4)]),
            Marker::TriangleUp => Some(vec![(0, -6), (5, 4), (-5, 4)]),
            Marker::Diamond => Some(vec![(0, -6), (6, 0), (0, 6), (-6, 0)]),
            Marker::TriangleDown => Some(vec![(0, 6), (5, -4), (-5, -4)]),
        }
    }
}

/// Draws `marker` at `at` on `area` in `style` (filled, or an outline).
fn draw_marker<DB: DrawingBackend, CT: plotters::coord::CoordTranslate>(
    area: &DrawingArea<DB, CT>,
    at: CT::From,
    marker: Marker,
    style: ShapeStyle,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    CT::From: Clone,
{
    match marker.corners() {
        None => area.draw(&Circle::new(at, 4, style)),
        Some(corners) if style.filled => {
            area.draw(&(EmptyElement::at(at) + Polygon::new(corners, style)))
        }
        Some(mut corners) => {
            corners.push(corners[0]);
            area.draw(&(EmptyElement::at(at) + PathElement::new(corners, style)))
        }
    }
}

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
    /// as its longest label line, at most [`LEGEND_TEXT`] of text), or columns when its entries do not
    /// fit the height.
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
/// Height of the title's band above the axes for a one-line title (22 px text and its padding),
/// pixels; each further line adds [`TITLE_LINE`].
const TITLE_BAND: u32 = 40;
/// Line pitch of a title that wraps, pixels.
const TITLE_LINE: u32 = 26;
/// Size of the title's text, pixels.
const TITLE_SIZE: u32 = 22;
/// Height of one legend entry (14 px text), pixels.
const LEGEND_ROW: u32 = 20;
/// Length of a legend entry's line sample, pixels; the text starts [`MARGIN`] after it.
const SWATCH: u32 = 24;

/// Widest line of a legend entry's label (14 px text), pixels: a longer label wraps at spaces, so that
/// one long label (a group of samplers with identical estimates) does not make the legend wider than
/// the axes.
const LEGEND_TEXT: u32 = 400;
/// Line pitch of a legend label that wraps, pixels.
const LEGEND_LINE: u32 = 16;

/// The legend's place right of the axes: entries top down from the axes' top edge, each label wrapped
/// to [`LEGEND_TEXT`], in as many columns as the plot's height needs.
struct LegendLayout {
    /// Each series' label, wrapped.
    lines: Vec<Vec<String>>,
    /// Each entry's column and the top of its first row below the legend's top edge, pixels.
    places: Vec<(u32, u32)>,
    /// Columns.
    columns: u32,
    /// Width of one column (sample, text and margins), pixels.
    column_width: u32,
}

impl LegendLayout {
    fn new(plot: &LogLogPlot, title_band: u32) -> std::result::Result<Self, String> {
        let font = ("sans-serif", 14).into_font();
        let lines: Vec<Vec<String>> = plot
            .series
            .iter()
            .map(|s| wrap(&s.label, 14, LEGEND_TEXT))
            .collect();
        let mut text = 0;
        for line in lines.iter().flatten() {
            let (w, _) = font.box_size(line).map_err(|e| format!("{e:?}"))?;
            text = text.max(w);
        }
        let room = plot
            .height
            .saturating_sub(title_band + 2 * MARGIN + X_LABEL_AREA);
        let (mut column, mut top) = (0, 0);
        let mut places = Vec::with_capacity(lines.len());
        for label in &lines {
            let height = LEGEND_ROW + LEGEND_LINE * (label.len() as u32 - 1);
            if top > 0 && top + height > room {
                (column, top) = (column + 1, 0);
            }
            places.push((column, top));
            top += height;
        }
        Ok(LegendLayout {
            lines,
            places,
            columns: if plot.series.is_empty() {
                0
            } else {
                column + 1
            },
            column_width: SWATCH + text + 2 * MARGIN,
        })
    }

    /// Width of all the columns, pixels.
    fn width(&self) -> u32 {
        self.columns * self.column_width
    }
}

/// A series' colour, its marker and the marker's style: the palette in order, each colour with its
/// own shape, then round again with hollow markers.
fn series_style(s: &Series, index: usize) -> (RGBAColor, Marker, ShapeStyle) {
    let slot = s.colour.unwrap_or(index);
    let (r, g, b) = PALETTE[slot % PALETTE.len()];
    let colour = RGBColor(r, g, b).to_rgba();
    let style = if (slot / PALETTE.len()).is_multiple_of(2) {
        colour.filled()
    } else {
        colour.stroke_width(2)
    };
    (colour, MARKERS[slot % PALETTE.len()], style)
}

/// The values a log axis shows: 1e-300 to 1e300.
const LOG_LIMITS: (f64, f64) = (1e-300, 1e300);

/// The axis range `[lo, hi]` padded by a fraction of a decade on each side, and widened to the
/// enclosing decades when it holds no power of ten: plotters puts the vertical axis's labels at the
/// powers of ten in range (and between them), and [`log_ticks`] falls back on them, so a range inside
/// one decade (N = 16 to 64) would otherwise get an axis with no label at all.
///
/// Values outside [`LOG_LIMITS`] are left out (and not drawn), and the padded range stays within a
/// decade of them, so that every decade of the axis is a normal `f64` and the tick search is finite.
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| (LOG_LIMITS.0..=LOG_LIMITS.1).contains(v))
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
    let (lo, hi) = (
        (lo / 10f64.powf(pad)).max(LOG_LIMITS.0 / 10.0),
        (hi * 10f64.powf(pad)).min(LOG_LIMITS.1 * 10.0),
    );
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

/// Which way an axis runs, for how much room its labels need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Direction {
    /// Labels side by side: each as wide as its text.
    Horizontal,
    /// Labels one above the other: each one line of 14 px text.
    Vertical,
}

/// Writes an axis's tick labels.
type Labels = dyn Fn(&f64) -> String;

/// A log axis with its own key (labelled) and light points: every vertical axis, and a log horizontal one.
type LogAxis = plotters::coord::combinators::WithKeyPoints<LogCoord<f64>>;

/// Where a log axis from `lo` to `hi` (`0 < lo < hi`) `pixels` long puts its labels: the first of
/// powers of two from 1 (with `powers_of_two`, for a horizontal axis of counts such as N), 1-2-5 in
/// each decade, 1 to 9 in each decade (for
/// a range too narrow to hold two of 1-2-5), every decade, and every k-th decade whose labels, as
/// [`tick_label`] writes them in 14 px text, do not run into one another along `direction`: at least
/// two labels, and every label distinct. Every axis that [`log_range`] makes holds at least one of
/// them.
fn log_ticks(lo: f64, hi: f64, pixels: f64, direction: Direction, powers_of_two: bool) -> Vec<f64> {
    let (llo, lhi) = (lo.log10(), hi.log10());
    let at = |v: f64| (v.log10() - llo) / (lhi - llo) * pixels;
    // About 8 px per character at 14 px and a gap of 16 px between labels side by side; 11 px of
    // text and a gap of 9 px one above the other.
    let width = |v: f64| 8.0 * tick_label(v).chars().count() as f64;
    let room = |a: f64, b: f64| match direction {
        Direction::Horizontal => (width(a) + width(b)) / 2.0 + 16.0,
        Direction::Vertical => 20.0,
    };
    let fits = |ticks: &[f64]| {
        ticks.windows(2).all(|w| {
            at(w[1]) - at(w[0]) >= room(w[0], w[1]) && tick_label(w[0]) != tick_label(w[1])
        })
    };
    let inside = |v: &f64| lo <= *v && *v <= hi;
    let decades = (llo.floor() as i32)..=(lhi.ceil() as i32);
    let mantissas = |ms: &[f64]| -> Vec<f64> {
        decades
            .clone()
            .flat_map(|d| ms.iter().map(move |m| m * 10f64.powi(d)))
            .filter(inside)
            .collect()
    };
    let mut candidates: Vec<Vec<f64>> = Vec::new();
    // An axis of counts starts at 1 or above, or less than a factor 2 below 1 where the padding of
    // [`log_range`] puts an axis from N = 1: its first power of two is then 1 or more.
    if powers_of_two && lo > 0.5 {
        let twos = (lo.log2().ceil() as i32)..=(hi.log2().floor() as i32);
        candidates.push(twos.map(|k| 2f64.powi(k)).collect());
    }
    candidates.push(mantissas(&[1.0, 2.0, 5.0]));
    candidates.push(mantissas(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]));
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

/// A log axis from `lo` to `hi`, `pixels` long: labelled at [`log_ticks`], with the grid lines of
/// [`minor_ticks`], and the writer of its labels ([`axis_labels`]).
fn log_axis(
    lo: f64,
    hi: f64,
    pixels: f64,
    direction: Direction,
    powers_of_two: bool,
) -> (LogAxis, Box<Labels>) {
    let ticks = log_ticks(lo, hi, pixels, direction, powers_of_two);
    let labels = axis_labels(&ticks);
    let axis = (lo..hi)
        .log_scale()
        .with_key_points(ticks)
        .with_light_points(minor_ticks(lo, hi, pixels));
    (axis, labels)
}

/// The unlabelled grid lines of a log axis from `lo` to `hi` `pixels` long: 1 to 9 in each decade
/// where a decade is at least 60 px long, else every decade (finer lines would merge into a smear).
fn minor_ticks(lo: f64, hi: f64, pixels: f64) -> Vec<f64> {
    let per_decade = pixels / (hi / lo).log10();
    let steps: &[f64] = if per_decade >= 60.0 {
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    } else {
        &[1.0]
    };
    ((lo.log10().floor() as i32)..=(hi.log10().ceil() as i32))
        .flat_map(|d| steps.iter().map(move |m| m * 10f64.powi(d)))
        .filter(|v| lo <= *v && *v <= hi)
        .collect()
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

/// `v` in scientific notation with at most 4 significant digits (`0.005` → `5e-3`).
fn scientific(v: f64) -> String {
    let text = format!("{v:.3e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    format!("{mantissa}e{exponent}")
}

/// The labels of an axis's `ticks`: by [`tick_label`], or all in scientific notation when one of
/// them is (so that `0.005` and `5e-4` do not share an axis).
fn axis_labels(ticks: &[f64]) -> Box<Labels> {
    if ticks.iter().any(|&t| tick_label(t).contains('e')) {
        Box::new(|v| scientific(*v))
    } else {
        Box::new(|v| tick_label(*v))
    }
}

/// The embedded font as `ab_glyph` (the crate plotters draws text with) reads it, for its left side
/// bearings: plotters' text drawing puts each glyph's ink, not its origin, at the pen, so a glyph
/// whose ink starts left of its origin (`j`) or well right of it (`i`, `l`) sits a pixel or two off,
/// and `mj` reads `m j`. [`draw_text`] puts each glyph back where the font places it.
static GLYPHS: std::sync::OnceLock<Option<ab_glyph::FontRef<'static>>> = std::sync::OnceLock::new();

/// The left side bearing of `c` at `size` px, rounded down to whole pixels as `ab_glyph` places its
/// ink (a font of size `s` px is scaled by `s / (ascent − descent)`).
fn bearing(font: &ab_glyph::FontRef<'static>, c: char, size: f64) -> i32 {
    use ab_glyph::Font as _;
    let lsb = font.h_side_bearing_unscaled(font.glyph_id(c));
    (f64::from(lsb) * size / f64::from(font.height_unscaled())).floor() as i32
}

/// Width of `text` at `size` px in the embedded font, pixels (plotters' own measure).
pub fn text_width(text: &str, size: u32) -> u32 {
    register_font();
    ("sans-serif", size)
        .into_font()
        .box_size(text)
        .map_or(0, |(w, _)| w)
}

/// `text` broken at spaces into lines no wider than `width` px at `size` px (a word wider than that
/// gets a line of its own).
pub fn wrap(text: &str, size: u32, width: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), size) <= width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Draws `text` at `size` px in `colour` on `area`, its top left (or top centre, with `centred`) at
/// `(x, y)`, each glyph where the font places it (its left side bearing, as `ab_glyph` reads it).
pub fn draw_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    (x, y): (i32, i32),
    size: u32,
    colour: &RGBColor,
    centred: bool,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    register_font();
    let style = ("sans-serif", size)
        .into_font()
        .color(colour)
        .pos(Pos::new(HPos::Left, VPos::Top));
    let x = if centred {
        x - text_width(text, size) as i32 / 2
    } else {
        x
    };
    let Some(font) = GLYPHS
        .get_or_init(|| ab_glyph::FontRef::try_from_slice(dejavu::sans::regular()).ok())
        .as_ref()
    else {
        return area.draw_text(text, &style, (x, y));
    };
    for (i, c) in text.char_indices() {
        if c.is_whitespace() {
            continue;
        }
        let pen = text_width(&text[..i], size) as i32;
        let at = (x + pen + bearing(font, c, f64::from(size)), y);
        area.draw_text(&text[i..i + c.len_utf8()], &style, at)?;
    }
    Ok(())
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
    // The title spans the axes and the legend, wrapped to the image's width; a legend of one column
    // is measured for a one-line title, which covers every title as wide as the axes.
    let title = short_numbers(&plot.title);
    let first = LegendLayout::new(plot, TITLE_BAND).map_err(|e| plot_error(path, e))?;
    let lines = wrap(&title, TITLE_SIZE, plot.width + first.width() - 2 * MARGIN);
    let title_band = TITLE_BAND + TITLE_LINE * (lines.len() as u32 - 1);
    let legend = LegendLayout::new(plot, title_band).map_err(|e| plot_error(path, e))?;
    let image_width = plot.width + legend.width();
    let (w, h) = (image_width as usize, plot.height as usize);
    let mut buffer = vec![0u8; w * h * 3];
    {
        let root =
            BitMapBackend::with_buffer(&mut buffer, (image_width, plot.height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error(path, e))?;
        // The title's lines, centred, from 10 px below the top edge; the rest (below 32 px for one
        // line, as plotters' own title leaves) is split between the axes and the legend.
        for (i, line) in lines.iter().enumerate() {
            let y = 10 + (TITLE_LINE * i as u32) as i32;
            draw_text(
                &root,
                line,
                (image_width as i32 / 2, y),
                TITLE_SIZE,
                &BLACK,
                true,
            )
            .map_err(|e| plot_error(path, e))?;
        }
        let body = root.margin(title_band - 8, 0, 0, 0);
        let (axes, key) = body.split_horizontally(plot.width);
        let mut builder = ChartBuilder::on(&axes);
        builder
            .margin(MARGIN)
            .x_label_area_size(X_LABEL_AREA)
            .y_label_area_size(Y_LABEL_AREA);
        // The axes' own height less the title, the margins and the horizontal axis's label area.
        let y_pixels =
            f64::from(plot.height) - f64::from(title_band - 8 + 2 * MARGIN + X_LABEL_AREA);
        let (y_axis, y_label) = log_axis(y0, y1, y_pixels, Direction::Vertical, false);
        if x_log {
            // The axes' own width less the margins and the vertical axis's label area.
            let x_pixels = f64::from(plot.width) - f64::from(2 * MARGIN + Y_LABEL_AREA);
            let (x_axis, x_label) = log_axis(x0, x1, x_pixels, Direction::Horizontal, true);
            let chart = builder
                .build_cartesian_2d(x_axis, y_axis)
                .map_err(|e| plot_error(path, e))?;
            draw(chart, plot, path, y0, keep, (&*x_label, &*y_label))?;
        } else {
            let chart = builder
                .build_cartesian_2d(x0..x1, y_axis)
                .map_err(|e| plot_error(path, e))?;
            draw(
                chart,
                plot,
                path,
                y0,
                keep,
                (&|v| short_number(*v), &*y_label),
            )?;
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
    let (row, swatch) = (LEGEND_ROW as i32, SWATCH as i32);
    for (i, s) in plot.series.iter().enumerate() {
        let (colour, marker, style) = series_style(s, i);
        let (column, top) = layout.places[i];
        let x = column as i32 * layout.column_width as i32 + MARGIN as i32 / 2;
        let y = MARGIN as i32 + top as i32 + row / 2;
        let line = colour.stroke_width(2);
        if s.dashed {
            // The plot's dashes: 8 px drawn, 6 px left out.
            for a in (0..swatch).step_by(14) {
                area.draw(&PathElement::new(vec![(x + a, y), (x + a + 8, y)], line))?;
            }
        } else {
            area.draw(&PathElement::new(vec![(x, y), (x + swatch, y)], line))?;
            draw_marker(area, (x + swatch / 2, y), marker, style)?;
        }
        // 14 px text is 11 px high in plotters' layout: its top 6 px above the row's middle.
        for (j, text) in layout.lines[i].iter().enumerate() {
            draw_text(
                area,
                text,
                (
                    x + swatch + MARGIN as i32 / 2,
                    y - 6 + j as i32 * LEGEND_LINE as i32,
                ),
                14,
                &BLACK,
                false,
            )?;
        }
    }
    Ok(())
}

/// Draws the mesh and the series of `plot` on `chart`, whatever its horizontal scale, with
/// `x_label` and `y_label` writing the axes' labels; `y0` is the bottom of the vertical axis (where an
/// error bar that would cross 0 ends).
fn draw<'a, X>(
    mut chart: ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, LogAxis>>,
    plot: &LogLogPlot,
    path: &Path,
    y0: f64,
    keep: impl Fn(&(f64, f64)) -> bool,
    (x_label, y_label): (&Labels, &Labels),
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
        .y_label_formatter(y_label)
        .draw()
        .map_err(|e| plot_error(path, e))?;
    for (i, s) in plot.series.iter().enumerate() {
        let (colour, marker, marker_style) = series_style(s, i);
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| keep(p)).collect();
        // A point the axes cannot show (an MSE of 0) breaks the line: no segment passes over it as
        // if the values between its neighbours had been measured.
        let runs = s.points.split(|p| !keep(p)).filter(|run| !run.is_empty());
        let style = colour.stroke_width(2);
        if s.dashed {
            for run in runs {
                chart
                    .draw_series(DashedLineSeries::new(run.to_vec(), 8, 6, style))
                    .map_err(|e| plot_error(path, e))?;
            }
        } else {
            for run in runs {
                chart
                    .draw_series(LineSeries::new(run.to_vec(), style))
                    .map_err(|e| plot_error(path, e))?;
            }
            let area = chart.plotting_area();
            for &p in &pts {
                draw_marker(area, p, marker, marker_style).map_err(|e| plot_error(path, e))?;
            }
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
        let legend = LegendLayout::new(&plot, TITLE_BAND).unwrap();
        assert_eq!(legend.columns, 1);
        assert_eq!(legend.places, [(0, 0), (0, LEGEND_ROW)]);
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
        let layout = LegendLayout::new(&tall, TITLE_BAND).unwrap();
        assert_eq!(layout.columns, 2);
        assert_eq!(layout.places[17], (0, 17 * LEGEND_ROW));
        assert_eq!(layout.places[18], (1, 0));
        let c = dir.path().join("c.png");
        write_loglog_png(&c, &tall).unwrap();
        assert_eq!(read_rgb(&c).0, 640 + 2 * layout.column_width);
        // A label wider than LEGEND_TEXT wraps at its spaces: the column stays that narrow and the
        // entry takes a line more per wrap, so the next entry starts below all of it.
        let group = (0..8)
            .map(|i| format!("optimized table number {i}"))
            .collect::<Vec<_>>()
            .join(", ");
        let wide = plot(series(
            &|i| {
                if i == 0 {
                    group.clone()
                } else {
                    format!("s{i}")
                }
            },
            2,
        ));
        let layout = LegendLayout::new(&wide, TITLE_BAND).unwrap();
        let lines = layout.lines[0].len() as u32;
        assert!(lines >= 3, "{:?}", layout.lines[0]);
        assert_eq!(layout.lines[0].join(" "), group);
        assert!(layout.column_width <= SWATCH + LEGEND_TEXT + 2 * MARGIN);
        assert_eq!(
            layout.places[1],
            (0, LEGEND_ROW + (lines - 1) * LEGEND_LINE)
        );
        let d = dir.path().join("d.png");
        write_loglog_png(&d, &wide).unwrap();
        assert_eq!(read_rgb(&d).0, 640 + layout.column_width);
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
        let ticks = log_ticks(lo, hi, width, Direction::Horizontal, true);
        assert_eq!(ticks, [16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0]);
        let labels: Vec<String> = ticks.iter().map(|&v| tick_label(v)).collect();
        assert_eq!(labels.join(" "), "16 32 64 128 256 512 1024");
        // Counts from 1: the padding puts the axis's start below 1, and the powers of two still
        // label it (only 1 and 2, of 1-2-5, were labelled over N = 1 to 4).
        let (lo, hi) = log_range([1.0, 4.0].into_iter()).unwrap();
        assert!(lo < 1.0, "{lo}");
        assert_eq!(
            log_ticks(lo, hi, width, Direction::Horizontal, true),
            [1.0, 2.0, 4.0]
        );
        // Times from 0.002 ms are no counts: no powers of two from 1, which would leave the axis
        // below 1 unlabelled.
        let (lo, hi) = log_range([0.002, 100.0].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, width, Direction::Horizontal, true);
        assert!(ticks[0] <= 0.002 * 10.0, "{ticks:?}");
        let (lo, hi) = log_range([2e-6, 3e-3].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, width, Direction::Horizontal, true);
        assert!(ticks.contains(&2e-6) && ticks.contains(&5e-5), "{ticks:?}");
        assert_eq!(tick_label(5e-5), "5e-5");
        let (lo, hi) = log_range([1.0, 1e6].into_iter()).unwrap();
        let ticks = log_ticks(lo, hi, 400.0, Direction::Horizontal, true);
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
            let ticks = log_ticks(lo, hi, pixels, Direction::Horizontal, true);
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

    /// A vertical log axis: at least two distinct labels whatever the range (the robustness plots'
    /// 1.4e-7 to 3e-6 gets 1-2-5, a range of one decade's part 1 to 9), one line of text apart, the
    /// lowest within a factor 10 of the data's bottom; labels of one axis in one notation.
    #[test]
    fn vertical_log_axes_label_their_whole_range() {
        for (values, pixels) in [
            (vec![1.4e-7, 3e-6], 600.0),
            (vec![9e-7, 5.5e-5], 600.0),
            (vec![8.5e-7, 1.3e-6], 600.0),
            (vec![1e-7, 5e-3], 600.0),
            (vec![1e-12, 1e2], 300.0),
            (vec![2e-6, 2.2e-6], 200.0),
        ] {
            let (lo, hi) = log_range(values.iter().copied()).unwrap();
            let ticks = log_ticks(lo, hi, pixels, Direction::Vertical, false);
            assert!(ticks.len() >= 2, "{values:?}: {ticks:?}");
            assert!(ticks[0] <= values[0] * 10.0, "{values:?}: {ticks:?}");
            let at = |v: f64| (v / lo).log10() / (hi / lo).log10() * pixels;
            for w in ticks.windows(2) {
                assert!(at(w[1]) - at(w[0]) >= 20.0, "{values:?}: {ticks:?}");
                assert_ne!(tick_label(w[0]), tick_label(w[1]), "{values:?}");
            }
        }
        let (lo, hi) = log_range([1.4e-7, 3e-6].into_iter()).unwrap();
        assert_eq!(
            log_ticks(lo, hi, 600.0, Direction::Vertical, false),
            [2e-7, 5e-7, 1e-6, 2e-6]
        );
        let label = axis_labels(&[5e-4, 1e-3, 5e-3]);
        assert_eq!([label(&5e-4), label(&5e-3)], ["5e-4", "5e-3"]);
        let label = axis_labels(&[16.0, 1024.0]);
        assert_eq!(label(&1024.0), "1024");
    }

    /// The embedded font's side bearings are read (`j` starts left of its origin, `m` right of it),
    /// and titles wrap at spaces to the width asked.
    #[test]
    fn text_keeps_the_fonts_spacing_and_wraps() {
        let font = ab_glyph::FontRef::try_from_slice(dejavu::sans::regular()).unwrap();
        assert!(bearing(&font, 'j', 100.0) < 0, "j");
        assert!(bearing(&font, 'm', 100.0) > 0, "m");
        let title =
            "padded-mj sheared (transported), at shear 0.5: expected power spectra, K = 64, \
                     32 realizations";
        let lines = wrap(title, 20, 792);
        assert!(lines.len() >= 2, "{lines:?}");
        assert_eq!(lines.join(" "), title);
        assert!(lines.iter().all(|l| text_width(l, 20) <= 792), "{lines:?}");
        // Twenty series get twenty different colours; colours that look alike have different markers.
        let mut colours = PALETTE.to_vec();
        colours.sort_unstable();
        colours.dedup();
        assert_eq!(colours.len(), PALETTE.len());
        for (a, b) in [
            (0, 11),
            (0, 17),
            (9, 12),
            (6, 13),
            (5, 14),
            (4, 15),
            (2, 16),
            (8, 18),
        ] {
            assert_ne!(MARKERS[a], MARKERS[b], "{a} {b}");
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

    /// Values at the ends of the floating-point range: those beyond [`LOG_LIMITS`] are left out, the
    /// range stays finite and normal, and the ticks are found (an infinite range used to make the
    /// tick search run over every `i32` decade).
    #[test]
    fn extreme_values_keep_a_finite_axis() {
        assert_eq!(log_range([1.7e308, 1e-310, 0.0].into_iter()), None);
        for values in [
            vec![1e-300, 1e300],
            vec![16.0, 1.7e308],
            vec![1e-310, 1e-299],
        ] {
            let (lo, hi) = log_range(values.iter().copied()).unwrap();
            assert!(
                lo >= f64::MIN_POSITIVE && hi < f64::INFINITY,
                "{values:?}: [{lo}, {hi}]"
            );
            for (direction, twos) in [(Direction::Vertical, false), (Direction::Horizontal, true)] {
                let ticks = log_ticks(lo, hi, 600.0, direction, twos);
                assert!(!ticks.is_empty(), "{values:?}: no ticks");
            }
        }
    }
}
