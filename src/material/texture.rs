//! Image textures for the image-texture node: loaded with bounded memory, converted to
//! the GPU layout `shaders/nodes/image.wgsl` reads (8-bit sources as RGBA8, deeper ones as
//! RGBA16F), and gathered per scene into one storage buffer.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use kiln_plugin_api::read::{MAX_FILE_BYTES, read_bounded};

/// A decoded image in the GPU's texel layout.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    pub width: u32,
    pub height: u32,
    /// 0: one u32 per texel, RGBA8; 1: two u32 per texel, RGBA16F.
    pub format: u32,
    pub texels: Vec<u32>,
}

/// The image file at `path`: a regular file of at most [`MAX_FILE_BYTES`] (a FIFO would
/// block the render, a device never end), its format by extension or else by content.
pub fn load_texture(path: &Path) -> Result<TextureImage, String> {
    let bytes = read_bounded(path, MAX_FILE_BYTES)
        .map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    let reader = reader
        .with_guessed_format()
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    decode(reader, &path.display().to_string())
}

/// An encoded image held in memory (embedded in an imported file); `what` names it.
pub fn decode_texture(bytes: &[u8], what: &str) -> Result<TextureImage, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read {what}: {e}"))?;
    decode(reader, what)
}

fn decode<R: std::io::BufRead + std::io::Seek>(
    mut reader: image::ImageReader<R>,
    what: &str,
) -> Result<TextureImage, String> {
    let path = what;
    // The largest width or height accepted ([`crate::limits::Limits::texture_size`]):
    // bigger claims are refused before decoding.
    let size = crate::limits::current().texture_size;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(size);
    limits.max_image_height = Some(size);
    // Room for the largest image allowed, as 16-bit RGBA, and no more.
    limits.max_alloc = Some((2u64 << 30).max(u64::from(size) * u64::from(size) * 8));
    reader.limits(limits);
    let img = reader.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => format!(
            "cannot decode {path}: {e} (images are limited to {size} texels a side; \
             --max-texture-size raises the limit)"
        ),
        e => format!("cannot decode {path}: {e}"),
    })?;
    let (width, height) = (img.width(), img.height());
    let eight_bit = matches!(
        img.color(),
        image::ColorType::L8
            | image::ColorType::La8
            | image::ColorType::Rgb8
            | image::ColorType::Rgba8
    );
    let texels = if eight_bit {
        img.to_rgba8()
            .pixels()
            .map(|p| u32::from_le_bytes(p.0))
            .collect()
    } else {
        img.to_rgba32f()
            .pixels()
            .flat_map(|p| {
                let h = |v: f32| half_bits(v) as u32;
                [h(p.0[0]) | h(p.0[1]) << 16, h(p.0[2]) | h(p.0[3]) << 16]
            })
            .collect()
    };
    Ok(TextureImage {
        width,
        height,
        format: if eight_bit { 0 } else { 1 },
        texels,
    })
}

/// f32 → IEEE half bits, as `nd_half` (shaders/nodes/image.wgsl) reads them; NaN reads
/// as 0 and values beyond the half range as the largest half, never as infinity.
fn half_bits(v: f32) -> u16 {
    let v = if v.is_nan() {
        0.0
    } else {
        v.clamp(-65504.0, 65504.0)
    };
    half::f16::from_f32(v).to_bits()
}

/// A scene's textures, in the order of their indices, and the index of each file.
#[derive(Debug, Default)]
pub struct TextureTable {
    pub index: BTreeMap<String, u32>,
    pub images: Vec<Arc<TextureImage>>,
}

impl TextureTable {
    /// The buffer `texture_data`: per texture (offset in words, width, height, format),
    /// then the texels.
    pub fn gpu_words(&self) -> Vec<u32> {
        let mut words = Vec::new();
        let mut offset = 4 * self.images.len() as u32;
        for img in &self.images {
            words.extend([offset, img.width, img.height, img.format]);
            offset += img.texels.len() as u32;
        }
        for img in &self.images {
            words.extend_from_slice(&img.texels);
        }
        words
    }
}
