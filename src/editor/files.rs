//! Reading and writing the editor's files: `.kiln` scenes through the scene module
//! (atomic, lossless), any other format an importer plugin reads, and the file dialogs
//! that ask for paths, behind [`FileDialogs`] so that tests answer them.

use std::path::{Path, PathBuf};

use crate::plugin::PluginHost;
use crate::scene::{self, Scene};

use super::document::Document;

/// Asks the user for a path. The editor calls it only in response to a user's action.
pub trait FileDialogs {
    /// A file to open (a `.kiln` scene or a file an importer reads); None if cancelled.
    fn open_path(&mut self) -> Option<PathBuf>;
    /// Where to save a `.kiln` scene, starting from `current`; None if cancelled.
    fn save_path(&mut self, current: Option<&Path>) -> Option<PathBuf>;
    /// A file to add to the scene through an importer plugin reading `extensions`.
    fn import_path(&mut self, extensions: &[String]) -> Option<PathBuf>;
    /// Where to write a rendered image, in one of `extensions`.
    fn export_path(&mut self, extensions: &[String]) -> Option<PathBuf>;
    /// An equirectangular environment map (`.hdr`, `.exr`).
    fn environment_path(&mut self) -> Option<PathBuf>;
    /// An image for an image-texture node (any of [`IMAGE_EXTENSIONS`]).
    fn image_path(&mut self) -> Option<PathBuf>;
    /// A material file (MaterialX, …) a material-format plugin reads, in `extensions`.
    fn material_import_path(&mut self, extensions: &[String]) -> Option<PathBuf>;
    /// Where to write material `name`, in one of `extensions`.
    fn material_export_path(&mut self, name: &str, extensions: &[String]) -> Option<PathBuf>;
}

/// The extensions of the images a texture reads, as dialogs offer them and a file
/// dropped on the node editor is recognised by.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr", "hdr"];

/// Whether `path` names an image a texture can read (by its extension).
pub fn is_image(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|x| x.eq_ignore_ascii_case(e)))
}

/// The platform's native dialogs (`rfd`).
pub struct NativeDialogs {
    /// Extensions the importer plugins read, offered beside `.kiln`.
    pub import_extensions: Vec<String>,
}

impl FileDialogs for NativeDialogs {
    fn open_path(&mut self) -> Option<PathBuf> {
        let mut all: Vec<&str> = vec!["kiln"];
        all.extend(self.import_extensions.iter().map(String::as_str));
        rfd::FileDialog::new()
            .set_title("Open")
            .add_filter("Scenes", &all)
            .add_filter("Kiln scene", &["kiln"])
            .pick_file()
    }

    fn save_path(&mut self, current: Option<&Path>) -> Option<PathBuf> {
        let mut dialog = rfd::FileDialog::new()
            .set_title("Save As")
            .add_filter("Kiln scene", &["kiln"]);
        if let Some(dir) = current.and_then(Path::parent) {
            dialog = dialog.set_directory(dir);
        }
        if let Some(name) = current.and_then(Path::file_name) {
            dialog = dialog.set_file_name(name.to_string_lossy());
        } else {
            dialog = dialog.set_file_name("untitled.kiln");
        }
        dialog.save_file().map(|p| {
            if p.extension().is_none() {
                p.with_extension("kiln")
            } else {
                p
            }
        })
    }

    fn import_path(&mut self, extensions: &[String]) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Import")
            .add_filter("Importable files", extensions)
            .pick_file()
    }

    fn export_path(&mut self, extensions: &[String]) -> Option<PathBuf> {
        let mut dialog = rfd::FileDialog::new()
            .set_title("Export Render")
            .set_file_name("render.png");
        for extension in extensions {
            dialog = dialog.add_filter(extension.to_uppercase(), &[extension]);
        }
        dialog.save_file().map(|p| {
            if p.extension().is_none() {
                p.with_extension("png")
            } else {
                p
            }
        })
    }

    fn environment_path(&mut self) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Environment Map")
            .add_filter("HDR images", &["hdr", "exr"])
            .pick_file()
    }

    fn image_path(&mut self) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Image Texture")
            .add_filter("Images", IMAGE_EXTENSIONS)
            .add_filter("PNG", &["png"])
            .add_filter("JPEG", &["jpg", "jpeg"])
            .add_filter("OpenEXR", &["exr"])
            .add_filter("Radiance HDR", &["hdr"])
            .pick_file()
    }

    fn material_import_path(&mut self, extensions: &[String]) -> Option<PathBuf> {
        rfd::FileDialog::new()
            .set_title("Import Materials")
            .add_filter("Material files", extensions)
            .pick_file()
    }

    fn material_export_path(&mut self, name: &str, extensions: &[String]) -> Option<PathBuf> {
        let first = extensions.first().map_or("mtlx", String::as_str);
        let mut dialog = rfd::FileDialog::new()
            .set_title("Export Material")
            .set_file_name(format!("{name}.{first}"));
        for extension in extensions {
            dialog = dialog.add_filter(extension.to_uppercase(), &[extension]);
        }
        dialog.save_file().map(|p| {
            if p.extension().is_none() {
                p.with_extension(first)
            } else {
                p
            }
        })
    }
}

/// Dialogs that answer from a queue of paths, for tests and scripted sessions; an empty
/// queue answers "cancelled".
#[derive(Default)]
pub struct ScriptedDialogs {
    pub open: std::collections::VecDeque<PathBuf>,
    pub save: std::collections::VecDeque<PathBuf>,
    pub import: std::collections::VecDeque<PathBuf>,
    pub export: std::collections::VecDeque<PathBuf>,
    pub environment: std::collections::VecDeque<PathBuf>,
    pub image: std::collections::VecDeque<PathBuf>,
    pub material_import: std::collections::VecDeque<PathBuf>,
    pub material_export: std::collections::VecDeque<PathBuf>,
}

impl FileDialogs for ScriptedDialogs {
    fn open_path(&mut self) -> Option<PathBuf> {
        self.open.pop_front()
    }

    fn save_path(&mut self, _current: Option<&Path>) -> Option<PathBuf> {
        self.save.pop_front()
    }

    fn import_path(&mut self, _extensions: &[String]) -> Option<PathBuf> {
        self.import.pop_front()
    }

    fn export_path(&mut self, _extensions: &[String]) -> Option<PathBuf> {
        self.export.pop_front()
    }

    fn environment_path(&mut self) -> Option<PathBuf> {
        self.environment.pop_front()
    }

    fn image_path(&mut self) -> Option<PathBuf> {
        self.image.pop_front()
    }

    fn material_import_path(&mut self, _extensions: &[String]) -> Option<PathBuf> {
        self.material_import.pop_front()
    }

    fn material_export_path(&mut self, _name: &str, _extensions: &[String]) -> Option<PathBuf> {
        self.material_export.pop_front()
    }
}

/// Whether `path` is a Kiln scene file (by its extension).
pub fn is_kiln_scene(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("kiln"))
}

/// Reads a document: a `.kiln` scene, or a file an importer plugin of `plugins` reads.
/// An imported document has no path yet (saving asks where). The message names the file
/// and what is wrong with it.
pub fn open_document(path: &Path, plugins: &PluginHost) -> Result<Document, String> {
    if is_kiln_scene(path) {
        let scene = scene::load_scene(path).map_err(|e| e.to_string())?;
        return Ok(Document::new(scene, Some(path.to_owned()), Vec::new()));
    }
    let imported = plugins
        .import(path)
        .map_err(|e| format!("cannot import {}: {e}", path.display()))?;
    let mut scene = imported.scene;
    if !imported.has_lights {
        scene::lookdev::add_ground(&mut scene, scene::lookdev::Ground::Plane);
    }
    scene
        .validate()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Document::new(scene, None, imported.images))
}

/// Writes `document`'s scene to `path` (atomically, with its assets beside it) and
/// records it as saved there.
pub fn save_document(document: &mut Document, path: &Path) -> Result<(), String> {
    let scene: &Scene = document.scene();
    scene::save_scene(scene, path, document.images()).map_err(|e| e.to_string())?;
    document.mark_saved(path.to_owned());
    Ok(())
}
