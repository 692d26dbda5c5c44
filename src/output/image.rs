//! Images: EXR for float values, PNG (8-bit) for looking. Both take pixels with the top row first.
//!
//! Spectra are stored with `k2` increasing with the row index ([`crate::spectrum`]); images put larger
//! `k2` higher up, like a plot, so [`spectrum_image_rows`] flips them.

use super::write_atomic;
use crate::error::Result;
use std::path::Path;

/// Writes float channels (each `width * height` values, top row first) as an EXR image.
/// Channel names follow EXR custom: `Y` for one value per pixel, `R`, `G`, `B` for colour.
pub fn write_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, Vec<f32>)],
) -> Result<()> {
    use exr::prelude::*;
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .iter()
        .map(|(name, values)| AnyChannel::new(*name, FlatSamples::F32(values.clone())))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::named("anisospec"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    write_atomic(path, |w| {
        image
            .write()
            .to_buffered(w)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })
}

/// Reads one channel of the first layer of an EXR image: `Y` if there is one, else `R`, else its only
/// channel, as `f64` values top row first, with `[height, width]`. Several channels none of which is
/// `Y` or `R` are refused, naming them. Errors are the decoder's words or name the channels.
pub fn read_exr_channel(path: &Path) -> std::result::Result<(Vec<f64>, [usize; 2]), String> {
    let image = exr::prelude::read_first_flat_layer_from_file(path).map_err(|e| e.to_string())?;
    let layer = image.layer_data;
    let channels = &layer.channel_data.list;
    let pick = ["Y", "R"]
        .iter()
        .find_map(|want| channels.iter().find(|c| c.name.to_string() == *want))
        .or_else(|| (channels.len() == 1).then(|| &channels[0]))
        .ok_or_else(|| {
            let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
            if names.is_empty() {
                "the image has no channel".to_string()
            } else {
                format!(
                    "channels {} and none named Y or R, so which one is meant is unclear",
                    names.join(", ")
                )
            }
        })?;
    let values = pick
        .sample_data
        .values_as_f32()
        .map(f64::from)
        .collect::<Vec<_>>();
    Ok((values, [layer.size.height(), layer.size.width()]))
}

/// Writes an 8-bit PNG, grey (`channels = 1`) or RGB (`channels = 3`), top row first.
pub fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    pixels: &[u8],
) -> Result<()> {
    write_png_described(path, [width, height], channels, pixels, None)
}

/// [`write_png`] with a `description` stored in the file (a `tEXt` chunk, keyword `Description`,
/// which image viewers show among the file's properties). A text chunk holds Latin-1, so every
/// character outside ASCII (e.g. of a file name) is stored as `?`.
pub fn write_png_described(
    path: &Path,
    [width, height]: [usize; 2],
    channels: usize,
    pixels: &[u8],
    description: Option<String>,
) -> Result<()> {
    let colour = if channels == 3 {
        png::ColorType::Rgb
    } else {
        png::ColorType::Grayscale
    };
    write_atomic(path, |w| {
        let mut enc = png::Encoder::new(w, width as u32, height as u32);
        enc.set_color(colour);
        enc.set_depth(png::BitDepth::Eight);
        if let Some(text) = &description {
            let ascii = text
                .chars()
                .map(|c| if c.is_ascii() { c } else { '?' })
                .collect();
            enc.add_text_chunk("Description".into(), ascii)
                .map_err(std::io::Error::other)?;
        }
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(pixels)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
}

/// A `res × res` spectrum (row `i` at `k2 = i − K/2`) as image rows with the largest `k2` on top.
pub fn spectrum_image_rows(values: &[f64], res: usize) -> Vec<f64> {
    values
        .chunks_exact(res)
        .rev()
        .flat_map(|row| row.iter().copied())
        .collect()
}

/// The fixed `log10 P` range PNG spectra are tone-mapped over: `[-2, 1]` (P from 0.01 to 10).
pub const LOG_RANGE: (f64, f64) = (-2.0, 1.0);

/// Grey level of a power value: `log10 P` mapped linearly from [`LOG_RANGE`] to 0..255, clamped.
/// `P = 1` (white noise) is light grey, 170 of 255 (2/3 of the range).
pub fn tone_map_log(p: f64) -> u8 {
    let (lo, hi) = LOG_RANGE;
    let l = if p > 0.0 { p.log10() } else { lo };
    (((l - lo) / (hi - lo)).clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Smallest side of a point set's spectrum PNG; smaller grids are scaled up by an integer factor.
pub const SPECTRUM_PNG_MIN_SIDE: usize = 256;

/// How a spectrum PNG reads: the tone map of [`tone_map_log`] and the frequency layout (ASCII).
pub fn spectrum_png_key() -> String {
    format!(
        "log10 P from {} (black) to {} (white); P = 1 (white noise) light grey ({} of 255); k1 right, k2 up, k = 0 at the centre",
        LOG_RANGE.0,
        LOG_RANGE.1,
        tone_map_log(1.0)
    )
}

/// Writes a spectrum as PNG (log tone map, largest `k2` on top), scaled up by the smallest integer
/// factor that makes it at least [`SPECTRUM_PNG_MIN_SIDE`] pixels (`--res 100`: 300 pixels), with
/// `identity` (what the spectrum is of), `K` and [`spectrum_png_key`] stored in the file as its
/// description.
pub fn write_spectrum_png(path: &Path, values: &[f64], res: usize, identity: &str) -> Result<()> {
    let grey: Vec<u8> = spectrum_image_rows(values, res)
        .into_iter()
        .map(tone_map_log)
        .collect();
    let (side, pixels) = upscaled(&grey, res, SPECTRUM_PNG_MIN_SIDE);
    let scale = side / res;
    let key = format!(
        "Power spectrum of {identity}, K = {res} frequencies per side, {scale} x {scale} pixels each: {}",
        spectrum_png_key()
    );
    write_png_described(path, [side, side], 1, &pixels, Some(key))
}

/// A square `res × res` grey image scaled up by the smallest integer factor that makes its side at
/// least `min_side` pixels (nearest neighbour). Returns the new side and its pixels, row-major.
pub fn upscaled(grey: &[u8], res: usize, min_side: usize) -> (usize, Vec<u8>) {
    let ([side, _], pixels) = upscaled_rect(grey, [res, res], min_side);
    (side, pixels)
}

/// A `width × height` grey image scaled up by the smallest integer factor that makes its longer side
/// at least `min_side` pixels (nearest neighbour). Returns the new `[width, height]` and its pixels,
/// row-major.
pub fn upscaled_rect(
    grey: &[u8],
    [width, height]: [usize; 2],
    min_side: usize,
) -> ([usize; 2], Vec<u8>) {
    let scale = min_side.div_ceil(width.max(height).max(1)).max(1);
    let (w, h) = (width * scale, height * scale);
    let pixels = (0..w * h)
        .map(|i| grey[(i / w / scale) * width + (i % w) / scale])
        .collect();
    ([w, h], pixels)
}

/// Writes a spectrum as a one-channel (`Y`) EXR with the raw values, largest `k2` on top.
pub fn write_spectrum_exr(path: &Path, values: &[f64], res: usize) -> Result<()> {
    let rows: Vec<f32> = spectrum_image_rows(values, res)
        .iter()
        .map(|&v| v as f32)
        .collect();
    write_exr(path, res, res, &[("Y", rows)])
}

/// A PNG read back for tests: its size, its pixels (row-major, as stored) and its description.
#[cfg(test)]
pub(crate) struct DecodedPng {
    pub width: usize,
    pub height: usize,
    pub data: Vec<u8>,
    pub description: Option<String>,
}

/// Reads the PNG at `path` (tests only; panics on a bad file).
#[cfg(test)]
pub(crate) fn decode_png(path: &Path) -> DecodedPng {
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("the PNG exists"));
    let mut reader = png::Decoder::new(file).read_info().expect("a PNG header");
    let mut data = vec![0; reader.output_buffer_size().expect("a PNG of sane size")];
    let frame = reader.next_frame(&mut data).expect("PNG pixels");
    data.truncate(frame.buffer_size());
    let description = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == "Description")
        .map(|t| t.text.clone());
    DecodedPng {
        width: frame.width as usize,
        height: frame.height as usize,
        data,
        description,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spectrum_png_says_how_it_reads() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        // A PNG text chunk is Latin-1: characters outside ASCII are stored as '?'.
        write_spectrum_png(&path, &[1.0; 16], 4, "sätze.npy in xu").unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let reader = png::Decoder::new(file).read_info().unwrap();
        let info = reader.info();
        assert_eq!((info.width, info.height), (256, 256));
        let text = &info.uncompressed_latin1_text;
        assert_eq!(text.len(), 1);
        assert_eq!(text[0].keyword, "Description");
        assert!(text[0]
            .text
            .starts_with("Power spectrum of s?tze.npy in xu, K = 4 frequencies per side, 64 x 64"));
        assert!(text[0].text.ends_with(&spectrum_png_key()));
    }
}
