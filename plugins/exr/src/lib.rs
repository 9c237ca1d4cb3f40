//! Kiln's OpenEXR exporter: the film's linear radiance and its AOV layers as 32-bit
//! floats, exactly as rendered (no tonemapping, no clamping, no half floats).
//!
//! One single-part file holds every layer, named by channel prefixes in OpenEXR's
//! classic layer convention: the main image is `R`, `G`, `B`, `A` and each AOV is
//! `<name>.<channel>` (`albedo.R`, `normal.X`, `depth.Z`; see [`channels::channel_names`]).
//! This is the layout Blender writes and reads as a multilayer file, and OpenImageIO,
//! Nuke and every OpenEXR 1.x reader see as one image with layers. The `exr` crate also
//! writes multi-part files (it calls them "layers"), but viewers such as DJV and
//! xStudio, and OpenEXR 1.x libraries, read only the first part of those.
//!
//! Options (`key=value;…`):
//!
//! | option        | values                               | default |
//! |---------------|--------------------------------------|---------|
//! | `compression` | `none`, `rle`, `zip`, `zips`, `piz`  | `zip`   |
//!
//! Only lossless compressions are offered: `zip` (zlib over blocks of 16 scan lines,
//! OpenEXR's `ZIP_COMPRESSION`), `zips` (one scan line per block), `rle` and `piz`
//! (wavelet, best on noisy images). The lossy ones (`pxr24`, `b44`, `dwaa`, …) round
//! 32-bit floats and are refused.

pub mod channels;

use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image, Layer,
    LayerAttributes, LineOrder, SmallVec, Text, Vec2, WritableImage,
};
use kiln_plugin_api::{Exporter, Film, export_exporter};

/// The OpenEXR exporter.
pub struct ExrExport;

/// The compression from the options (`zip` when not given).
pub fn compression(options: &[(&str, &str)]) -> Result<Compression, String> {
    let mut compression = Compression::ZIP16;
    for &(key, value) in options {
        if key != "compression" {
            return Err(format!(
                "unknown option \"{key}\" (this exporter takes compression=none|rle|zip|zips|piz)"
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
        for (i, name) in channels::channel_names(layer.name, layer.channels)
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

impl Exporter for ExrExport {
    const NAME: &'static str = "OpenEXR";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "exr";

    fn export(path: &Path, film: &Film, options: &[(&str, &str)]) -> Result<(), String> {
        let fail = |message: String| format!("cannot write {}: {message}", path.display());
        let compression = compression(options).map_err(fail)?;
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
}

export_exporter!(ExrExport);
