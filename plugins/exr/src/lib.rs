//! Kiln's OpenEXR exporter: the film's linear radiance and its AOV layers as 32-bit
//! floats in one single-part file, written by `kiln_formats::exr` (which documents the
//! layout), the writer the host also uses when no exporter plugin is found.
//!
//! Options (`key=value;…`):
//!
//! | option        | values                               | default |
//! |---------------|--------------------------------------|---------|
//! | `compression` | `none`, `rle`, `zip`, `zips`, `piz`  | `zip`   |
//!
//! Only lossless compressions are offered; the lossy ones round 32-bit floats and are
//! refused.

use std::path::Path;

use kiln_formats::exr;
use kiln_plugin_api::{Exporter, Film, export_exporter};

/// The OpenEXR exporter.
pub struct ExrExport;

impl Exporter for ExrExport {
    const NAME: &'static str = "OpenEXR";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "exr";

    fn export(path: &Path, film: &Film, options: &[(&str, &str)]) -> Result<(), String> {
        let compression = exr::compression(options)
            .map_err(|message| format!("cannot write {}: {message}", path.display()))?;
        exr::write(path, film, compression)
    }
}

export_exporter!(ExrExport);
