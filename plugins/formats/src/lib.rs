//! The file formats that Kiln's host and its bundled plugins both read or write, in one
//! place so that both run literally the same code: the host loads the OBJ meshes a
//! `.kiln` scene references with [`obj`], which the OBJ importer plugin (`kiln-obj`)
//! wraps; the host writes PNG, JPEG and OpenEXR films with [`image`] and [`exr`], which
//! the exporter plugins (`kiln-image-export`, `kiln-exr`) wrap. Every write is atomic
//! (`kiln_plugin_api::atomic`).
//!
//! This is a plain library: it exports no plugin symbol, so the host can link it (a
//! plugin crate's rlib would bring its `kiln_plugin_descriptor` along). What only one
//! side needs stays there: MTL → `.kmat` conversion in the OBJ plugin, the film's
//! tonemapping in the host.

pub mod exr;
pub mod image;
pub mod obj;
