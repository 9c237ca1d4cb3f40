//! The `.kiln` scene file: a versioned, human-editable description of a
//! [`Scene`](super::Scene).
//!
//! The format is [RON](https://github.com/ron-rs/ron): it has comments, trailing commas
//! and named enum variants (`Sphere(segments: 64, rings: 32)`), which keeps hand-written
//! scenes readable, and serde reads it directly. Unknown fields are errors, so a typo
//! never silently falls back to a default. Relative paths (mesh files) resolve against the
//! folder of the scene file. `docs/SCENE_FORMAT.md` documents every field.
//!
//! ```ron
//! (
//!     version: 1,
//!     render: (width: 512, height: 512, samples_per_pixel: 64, max_bounces: 8),
//!     camera: (position: (0, 1, 5), look_at: (0, 1, 0), projection: Perspective(fov_y: 40)),
//!     environment: (0.1, 0.1, 0.1),
//!     materials: { "red": (base_color: (0.8, 0.1, 0.1)) },
//!     meshes: { "ball": Sphere(segments: 64, rings: 32) },
//!     instances: [ (mesh: "ball", material: "red", transform: (translate: (0, 1, 0))) ],
//! )
//! ```
//!
//! The format is split by job: `scene/schema.rs` declares the serde types (what a file may
//! say), `scene/load.rs` turns a file into a validated scene, `scene/save.rs` writes one
//! back, and `scene/obj.rs` reads and writes the OBJ mesh files a scene refers to. This
//! module holds what they share: the format version and the error type.

use std::path::PathBuf;

use thiserror::Error;

pub use super::load::{load_scene, parse_scene};
pub use super::save::save_scene;

/// The version this build reads and writes. Older versions are upgraded on load where
/// possible; newer ones are refused with a message saying so.
pub const SCENE_FORMAT_VERSION: u32 = 1;

#[derive(Debug, Error)]
pub enum SceneError {
    // The cause is in the message, not a `source`: a report of the error chain would
    // name it twice.
    #[error("cannot read scene file {path}: {cause}")]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error(
        "{path}: scene format version {found} is not supported (this build reads version {SCENE_FORMAT_VERSION}{newer})",
        newer = if *found > SCENE_FORMAT_VERSION { "; the file was written by a newer Kiln" } else { "" }
    )]
    Version { path: PathBuf, found: u32 },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error("cannot save scene {path}: {message}")]
    Save { path: PathBuf, message: String },
    #[error("{path}: mesh \"{mesh}\": cannot load {file}: {message}")]
    MeshFile {
        path: PathBuf,
        mesh: String,
        file: PathBuf,
        message: String,
    },
}
