//! Kiln's MaterialX plugin: reads MaterialX 1.38/1.39 documents into Kiln material graphs
//! ([`import`]) and writes Kiln graphs as MaterialX ([`export`]). `docs/MATERIALX.md`
//! lists what maps to what.

pub mod export;
pub mod implement;
pub mod import;
pub mod surface;
pub mod table;

use std::path::Path;

use kiln_plugin_api::read::{MAX_FILE_BYTES, read_text_bounded};
use kiln_plugin_api::{MaterialFormat, Materials};

pub struct MaterialX;

impl MaterialFormat for MaterialX {
    const NAME: &'static str = "MaterialX";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "mtlx";

    fn import(path: &Path, materials: &mut Materials) -> Result<(), String> {
        let text = read_text_bounded(path, MAX_FILE_BYTES)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let imported = import::import(&text, path)?;
        for warning in &imported.warnings {
            materials.warn(warning);
        }
        for (name, kmat) in &imported.materials {
            materials.add(name, kmat);
        }
        Ok(())
    }

    fn export(path: &Path, name: &str, kmat: &str, library: &str) -> Result<(), String> {
        let text = export::export(name, kmat, library)?;
        kiln_plugin_api::atomic::write_atomically(path, |w| {
            std::io::Write::write_all(w, text.as_bytes()).map_err(|e| e.to_string())
        })
    }
}

kiln_plugin_api::export_material_format!(MaterialX);
