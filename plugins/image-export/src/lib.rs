//! Kiln's PNG and JPEG exporter: writes the film's display image (tonemapped,
//! sRGB-encoded, in [0, 1]) quantized to integers. It does no tonemapping of its own and
//! never sees scene-linear values; OpenEXR is the format for those (`kiln-exr`).
//!
//! Options (`key=value;…`):
//!
//! | option    | values       | default | applies to |
//! |-----------|--------------|---------|------------|
//! | `bits`    | `8`, `16`    | `8`     | PNG        |
//! | `quality` | `1` to `100` | `92`    | JPEG       |
//!
//! PNG keeps the display alpha (RGBA); JPEG has no alpha and drops it. An option this
//! exporter does not know, or one given for the other format, is an error rather than
//! silently ignored.

mod encode;

use std::path::Path;

use kiln_plugin_api::{Exporter, Film, export_exporter};

pub use encode::{Format, quantize};

/// The PNG/JPEG exporter.
pub struct ImageExport;

/// JPEG quality when none is given: visually lossless for renders at a moderate size.
pub const DEFAULT_JPEG_QUALITY: u8 = 92;

/// What the options and the extension ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    pub format: Format,
}

impl Settings {
    /// The format from `path`'s extension and the options; errors name `path`.
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
                        "unknown option \"{key}\" (this exporter takes bits=8|16 for PNG, quality=1..100 for JPEG)"
                    )));
                }
            }
        }
        Ok(Self { format })
    }
}

impl Exporter for ImageExport {
    const NAME: &'static str = "PNG/JPEG";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "png,jpg,jpeg";

    fn export(path: &Path, film: &Film, options: &[(&str, &str)]) -> Result<(), String> {
        let settings = Settings::new(path, options)?;
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
            encode::encode(
                writer,
                settings.format,
                film.width,
                film.height,
                film.display,
            )
        })
    }
}

export_exporter!(ImageExport);
