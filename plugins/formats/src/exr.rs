//! OpenEXR: the film's linear radiance and its AOV layers as 32-bit floats, exactly as
//! rendered (no tonemapping, no clamping, no half floats).
//!
//! One single-part file holds every layer, named by channel prefixes in OpenEXR's
//! classic layer convention: the main image is `R`, `G`, `B`, `A` and each AOV is
//! `<name>.<channel>` (`albedo.R`, `normal.X`, `depth.Z`; see [`channel_names`]).
//! This is the layout Blender writes and reads as a multilayer file, and OpenImageIO,
//! Nuke and every OpenEXR 1.x reader see as one image with layers. The `exr` crate also
//! writes multi-part files (it calls them "layers"), but viewers such as DJV and
//! xStudio, and OpenEXR 1.x libraries, read only the first part of those.
//!
//! Options (`key=value`, as `kiln_plugin_api::parse_options` splits them):
//!
//! | option        | values                               | default |
//! |---------------|--------------------------------------|---------|
//! | `compression` | `none`, `rle`, `zip`, `zips`, `piz`  | `zip`   |
//!
//! Only lossless compressions are offered: `zip` (zlib over blocks of 16 scan lines,
//! OpenEXR's `ZIP_COMPRESSION`), `zips` (one scan line per block), `rle` and `piz`
//! (wavelet, best on noisy images). The lossy ones (`pxr24`, `b44`, `dwaa`, …) round
//! 32-bit floats and are refused.

use std::path::Path;

pub use ::exr::prelude::Compression;
use ::exr::prelude::{
    AnyChannel, AnyChannels, Blocks, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    LineOrder, SmallVec, Text, Vec2, WritableImage,
};
use kiln_plugin_api::Film;

/// Layers whose values are vectors rather than colours.
const VECTOR_LAYERS: [&str; 6] = [
    "normal", "position", "motion", "velocity", "tangent", "vector",
];
/// Single-channel layers that hold a distance.
const DEPTH_LAYERS: [&str; 3] = ["depth", "z", "mist"];

/// The full channel names (`"<layer>.<channel>"`) of an AOV with `channels` channels, in
/// the conventions compositors expect: colours are `R`, `G`, `B` (`A`), directions and
/// positions `X`, `Y`, `Z` (`W`), depth is `Z` (as Blender's `Depth.Z`), and any other
/// single channel is `Y`, OpenEXR's greyscale.
pub fn channel_names(layer: &str, channels: u32) -> Vec<String> {
    let lower = layer.to_ascii_lowercase();
    let vector = VECTOR_LAYERS.iter().any(|v| lower.contains(v));
    let suffixes: Vec<String> = match channels {
        1 if DEPTH_LAYERS.contains(&lower.as_str()) => vec!["Z".into()],
        1 => vec!["Y".into()],
        2 => vec!["X".into(), "Y".into()],
        3 | 4 if vector => ["X", "Y", "Z", "W"][..channels as usize]
            .iter()
            .map(|s| (*s).to_owned())
            .collect(),
        3 | 4 => ["R", "G", "B", "A"][..channels as usize]
            .iter()
            .map(|s| (*s).to_owned())
            .collect(),
        n => (0..n).map(|i| i.to_string()).collect(),
    };
    suffixes
        .into_iter()
        .map(|s| format!("{layer}.{s}"))
        .collect()
}

/// The compression from the options (`zip` when not given).
pub fn compression(options: &[(&str, &str)]) -> Result<Compression, String> {
    let mut compression = Compression::ZIP16;
    for &(key, value) in options {
        if key != "compression" {
            return Err(format!(
                "unknown option \"{key}\" (OpenEXR takes compression=none|rle|zip|zips|piz)"
            ));
        }
        compression = match value.to_ascii_lowercase().as_str() {
            "none" => Compression::Uncompressed,
            "rle" => Compression::RLE,
            "zip" => Compression::ZIP16,
            "zips" => Compression::ZIP1,
            "piz" => Compression::PIZ,
            "pxr24" | "b44" | "b44a" | "dwaa" | "dwab" => {
                return Err(format!(
                    "compression={value} is lossy for 32-bit floats; use none, rle, zip, zips or piz"
                ));
            }
            _ => {
                return Err(format!(
                    "compression={value}: use none, rle, zip, zips or piz"
                ));
            }
        };
    }
    Ok(compression)
}

/// One channel: its full name and its samples, split out of an interleaved buffer.
fn channel(
    name: &str,
    data: &[f32],
    stride: usize,
    offset: usize,
) -> Result<AnyChannel<FlatSamples>, String> {
    let text = Text::new_or_none(name)
        .ok_or_else(|| format!("the channel name \"{name}\" is not Latin-1 text"))?;
    let samples = data.iter().skip(offset).step_by(stride).copied().collect();
    Ok(AnyChannel::new(text, FlatSamples::F32(samples)))
}

/// The film's channels: radiance as `R`, `G`, `B`, `A`, then each AOV's.
fn film_channels(film: &Film) -> Result<SmallVec<[AnyChannel<FlatSamples>; 4]>, String> {
    let pixels = (film.width as usize)
        .checked_mul(film.height as usize)
        .filter(|n| n.checked_mul(4).is_some())
        .ok_or_else(|| format!("a {}×{} film is too large", film.width, film.height))?;
    if film.radiance.len() != pixels * 4 {
        return Err(format!(
            "the radiance holds {} floats, a {}×{} RGBA film needs {}",
            film.radiance.len(),
            film.width,
            film.height,
            pixels * 4
        ));
    }
    let mut list = SmallVec::new();
    for (i, name) in ["R", "G", "B", "A"].into_iter().enumerate() {
        list.push(channel(name, film.radiance, 4, i)?);
    }
    let mut names: Vec<String> = ["R", "G", "B", "A"].map(str::to_owned).into();
    for layer in &film.layers {
        if layer.name.is_empty() {
            return Err("an AOV layer has no name".to_owned());
        }
        let n = layer.channels as usize;
        if n == 0 || pixels.checked_mul(n) != Some(layer.data.len()) {
            return Err(format!(
                "AOV \"{}\" holds {} floats for {} channels of {pixels} pixels",
                layer.name,
                layer.data.len(),
                layer.channels
            ));
        }
        for (i, name) in channel_names(layer.name, layer.channels)
            .into_iter()
            .enumerate()
        {
            if names.contains(&name) {
                return Err(format!(
                    "two layers would write the channel \"{name}\" (AOV names must be unique)"
                ));
            }
            list.push(channel(&name, layer.data, n, i)?);
            names.push(name);
        }
    }
    Ok(list)
}

/// Writes the film's radiance and AOV layers to `path` with `compression`, atomically;
/// errors name `path`.
pub fn write(path: &Path, film: &Film, compression: Compression) -> Result<(), String> {
    let fail = |message: String| format!("cannot write {}: {message}", path.display());
    if film.width == 0 || film.height == 0 {
        return Err(fail(format!(
            "the film is {}×{}: nothing to write",
            film.width, film.height
        )));
    }
    let channels = film_channels(film).map_err(fail)?;
    let size = Vec2(film.width as usize, film.height as usize);
    let encoding = Encoding {
        compression,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(channels),
    );
    let image = Image::from_layer(layer);
    kiln_plugin_api::atomic::write_atomically(path, |writer| {
        image.write().to_buffered(writer).map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn common_aovs_get_the_conventional_channel_names() {
        assert_eq!(
            channel_names("albedo", 3),
            ["albedo.R", "albedo.G", "albedo.B"]
        );
        assert_eq!(
            channel_names("normal", 3),
            ["normal.X", "normal.Y", "normal.Z"]
        );
        assert_eq!(channel_names("depth", 1), ["depth.Z"]);
        assert_eq!(channel_names("coverage", 1), ["coverage.Y"]);
        assert_eq!(
            channel_names("beauty", 4),
            ["beauty.R", "beauty.G", "beauty.B", "beauty.A"]
        );
        assert_eq!(channel_names("extra", 5).len(), 5);
    }
}
