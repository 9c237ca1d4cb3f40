//! PNG and JPEG: the film's display image (tonemapped, sRGB-encoded RGBA in [0, 1],
//! computed by the host) quantized to integers and encoded with the `image` crate. No
//! tonemapping here, and no scene-linear values: OpenEXR ([`crate::exr`]) is the format
//! for those.
//!
//! Options (`key=value`, as `kiln_plugin_api::parse_options` splits them):
//!
//! | option    | values       | default | applies to |
//! |-----------|--------------|---------|------------|
//! | `bits`    | `8`, `16`    | `8`     | PNG        |
//! | `quality` | `1` to `100` | `92`    | JPEG       |
//!
//! PNG keeps the display alpha (RGBA); JPEG has no alpha and drops it. An option not
//! known, or one given for the other format, is an error rather than silently ignored.

use std::io::{Seek, Write};
use std::path::Path;

use ::image::codecs::jpeg::JpegEncoder;
use ::image::{ImageBuffer, ImageFormat, Rgb, Rgba};
use kiln_plugin_api::Film;

/// JPEG quality when none is given: visually lossless for renders at a moderate size.
pub const DEFAULT_JPEG_QUALITY: u8 = 92;

/// The encoding asked for by a path's extension and the options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png { sixteen_bit: bool },
    Jpeg { quality: u8 },
}

impl Format {
    /// The format from `path`'s extension (`.png`, `.jpg`, `.jpeg`) and the options;
    /// errors name `path`.
    pub fn new(path: &Path, options: &[(&str, &str)]) -> Result<Self, String> {
        let fail = |message: String| format!("cannot write {}: {message}", path.display());
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let mut format = match extension.as_deref() {
            Some("png") => Format::Png { sixteen_bit: false },
            Some("jpg" | "jpeg") => Format::Jpeg {
                quality: DEFAULT_JPEG_QUALITY,
            },
            _ => {
                return Err(fail("the extension must be .png, .jpg or .jpeg".to_owned()));
            }
        };
        for &(key, value) in options {
            match (key, &mut format) {
                ("bits", Format::Png { sixteen_bit }) => {
                    *sixteen_bit = match value {
                        "8" => false,
                        "16" => true,
                        _ => {
                            return Err(fail(format!("bits={value}: PNG takes bits=8 or bits=16")));
                        }
                    }
                }
                ("quality", Format::Jpeg { quality }) => {
                    *quality = value
                        .parse::<u8>()
                        .ok()
                        .filter(|q| (1..=100).contains(q))
                        .ok_or_else(|| fail(format!("quality={value}: JPEG quality is 1 to 100")))?
                }
                ("bits", Format::Jpeg { .. }) => {
                    return Err(fail("bits applies to PNG only (JPEG is 8-bit)".to_owned()));
                }
                ("quality", Format::Png { .. }) => {
                    return Err(fail(
                        "quality applies to JPEG only (PNG is lossless)".to_owned(),
                    ));
                }
                _ => {
                    return Err(fail(format!(
                        "unknown option \"{key}\" (PNG takes bits=8|16, JPEG quality=1..100)"
                    )));
                }
            }
        }
        Ok(format)
    }
}

/// `value` in [0, 1] as an integer in [0, `max`], rounded to nearest; values outside
/// [0, 1] are clamped (infinities included) and NaN becomes 0.
pub fn quantize(value: f32, max: u16) -> u16 {
    if value.is_nan() {
        return 0;
    }
    // In range after the clamp: the cast cannot saturate.
    (value.clamp(0.0, 1.0) * f32::from(max)).round() as u16
}

/// Encodes `display` (RGBA, row-major from the top-left) into `writer`.
pub fn encode<W: Write + Seek>(
    writer: &mut W,
    format: Format,
    width: u32,
    height: u32,
    display: &[f32],
) -> Result<(), String> {
    let pixels = display.chunks_exact(4);
    let result = match format {
        Format::Png { sixteen_bit: false } => {
            let data: Vec<u8> = display.iter().map(|&v| quantize(v, 255) as u8).collect();
            ImageBuffer::<Rgba<u8>, _>::from_raw(width, height, data)
                .ok_or("the pixel buffer does not match the film's size")?
                .write_to(writer, ImageFormat::Png)
        }
        Format::Png { sixteen_bit: true } => {
            let data: Vec<u16> = display.iter().map(|&v| quantize(v, u16::MAX)).collect();
            ImageBuffer::<Rgba<u16>, _>::from_raw(width, height, data)
                .ok_or("the pixel buffer does not match the film's size")?
                .write_to(writer, ImageFormat::Png)
        }
        Format::Jpeg { quality } => {
            let data: Vec<u8> = pixels
                .flat_map(|p| [p[0], p[1], p[2]])
                .map(|v| quantize(v, 255) as u8)
                .collect();
            ImageBuffer::<Rgb<u8>, _>::from_raw(width, height, data)
                .ok_or("the pixel buffer does not match the film's size")?
                .write_with_encoder(JpegEncoder::new_with_quality(writer, quality))
        }
    };
    result.map_err(|e| e.to_string())
}

/// Writes the film's display image to `path` in `format`, atomically; errors name `path`.
pub fn write(path: &Path, film: &Film, format: Format) -> Result<(), String> {
    let fail = |message: String| format!("cannot write {}: {message}", path.display());
    if film.width == 0 || film.height == 0 {
        return Err(fail(format!(
            "the film is {}×{}: nothing to write",
            film.width, film.height
        )));
    }
    let expected = (film.width as usize)
        .checked_mul(film.height as usize)
        .and_then(|n| n.checked_mul(4))
        .ok_or_else(|| {
            fail(format!(
                "a {}×{} film is too large",
                film.width, film.height
            ))
        })?;
    if film.display.len() != expected {
        return Err(fail(format!(
            "the display image holds {} floats, a {}×{} RGBA film needs {expected}",
            film.display.len(),
            film.width,
            film.height
        )));
    }
    kiln_plugin_api::atomic::write_atomically(path, |writer| {
        encode(writer, format, film.width, film.height, film.display)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantize_rounds_to_nearest_and_clamps() {
        assert_eq!(quantize(0.5 / 255.0, 255), 1);
        assert_eq!(quantize(0.49 / 255.0, 255), 0);
        assert_eq!(quantize(1.5, 255), 255);
        assert_eq!(quantize(f32::NEG_INFINITY, 255), 0);
        assert_eq!(quantize(f32::NAN, u16::MAX), 0);
        assert_eq!(quantize(1.0, u16::MAX), u16::MAX);
    }

    #[test]
    fn the_extension_and_options_choose_the_encoding() {
        let png = Path::new("a.PNG");
        assert_eq!(
            Format::new(png, &[]).unwrap(),
            Format::Png { sixteen_bit: false }
        );
        assert_eq!(
            Format::new(png, &[("bits", "16")]).unwrap(),
            Format::Png { sixteen_bit: true }
        );
        assert_eq!(
            Format::new(Path::new("a.jpeg"), &[("quality", "50")]).unwrap(),
            Format::Jpeg { quality: 50 }
        );
        for (path, options) in [
            ("a.png", [("quality", "50")]),
            ("a.jpg", [("bits", "16")]),
            ("a.jpg", [("quality", "0")]),
            ("a.png", [("gamma", "2")]),
            ("a.tif", [("bits", "8")]),
        ] {
            let e = Format::new(Path::new(path), &options).unwrap_err();
            assert!(e.contains(path), "{e}");
        }
    }
}
