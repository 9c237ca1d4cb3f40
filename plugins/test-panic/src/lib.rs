//! A plugin that panics on every import, for the host's tests: the export macro must turn
//! the panic into an error, and Kiln must keep running. Its library name does not start
//! with `kiln_`, so Kiln never picks it up from the build folder by itself.

use kiln_plugin_api::{Builder, Importer, export_importer};

pub struct Panicking;

impl Importer for Panicking {
    const NAME: &'static str = "panicking test importer";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    const EXTENSIONS: &'static str = "panic";

    fn import(path: &std::path::Path, builder: &mut Builder) -> Result<(), String> {
        builder.warn("about to panic");
        panic!("deliberate panic while importing {}", path.display());
    }
}

export_importer!(Panicking);
