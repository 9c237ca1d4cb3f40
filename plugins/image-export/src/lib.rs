//! Kiln's PNG and JPEG exporter: writes the film's display image (tonemapped,
//! sRGB-encoded, in [0, 1]) quantized to integers, through `kiln_formats::image`, the
//! writer the host also uses when no exporter plugin is found. It does no tonemapping of
//! its own and never sees scene-linear values; OpenEXR is the format for those
//! (`kiln-exr`).
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

use std::path::Path;

use kiln_formats::image::{Format, write};
use kiln_plugin_api::{Exporter, Film, export_exporter};

/// The PNG/JPEG exporter.
pub struct ImageExport;

impl Exporter for ImageExport {
    const NAME: &'static str = "PNG/JPEG";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "png,jpg,jpeg";

    fn export(path: &Path, film: &Film, options: &[(&str, &str)]) -> Result<(), String> {
        write(path, film, Format::new(path, options)?)
    }
}

export_exporter!(ImageExport);
