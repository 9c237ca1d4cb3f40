//! Quantizing display values and encoding them as PNG or JPEG with the `image` crate.

use std::io::{Seek, Write};

use image::codecs::jpeg::JpegEncoder;
use image::{ImageBuffer, ImageFormat, Rgb, Rgba};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png { sixteen_bit: bool },
    Jpeg { quality: u8 },
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
