//! The plugin host: finds importer and exporter libraries, checks their ABI version
//! before calling anything, and runs them so that a broken plugin or a broken file gives
//! an error instead of taking Kiln down (plugins built with `kiln-plugin-api` turn their
//! panics into errors; the host's own callbacks never unwind into a plugin).
//!
//! Discovery order: `--plugin-dir` folders, `$KILN_PLUGIN_PATH`, the executable's folder,
//! and its `deps` folder, where `cargo build` leaves the workspace's plugins (there only
//! files named `libkiln_*`/`kiln_*` are considered). The first plugin of a name wins.

mod builder;
mod isolate;

use std::ffi::{CStr, CString, c_char};
use std::path::{Path, PathBuf};

use kiln_plugin_api as api;
use thiserror::Error;

pub use builder::Imported;
pub use isolate::Isolation;
// The film layer's: it writes the same film itself when no plugin handles the format.
pub use crate::film::output::{ExportFilm, ExportLayer};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PluginKind {
    Importer,
    Exporter,
    /// Reads material files into graphs, writes graphs as material files, or both.
    Material,
}

impl std::fmt::Display for PluginKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            PluginKind::Importer => "importer",
            PluginKind::Exporter => "exporter",
            PluginKind::Material => "material format",
        })
    }
}

#[derive(Clone, Debug)]
pub struct PluginInfo {
    pub name: String,
    pub version: String,
    pub kind: PluginKind,
    pub extensions: Vec<String>,
    pub path: PathBuf,
}

/// A library that was not loaded, and why.
#[derive(Clone, Debug)]
pub struct Rejected {
    pub path: PathBuf,
    pub reason: String,
}

#[derive(Debug, Error)]
pub enum PluginError {
    #[error("no {kind} plugin handles \".{extension}\" files (see `kiln plugins`)")]
    NoPlugin { kind: PluginKind, extension: String },
    #[error("{plugin} failed on {path}: {message}")]
    Failed {
        plugin: String,
        path: String,
        message: String,
    },
    #[error("{0}")]
    Invalid(String),
}

struct Loaded {
    info: PluginInfo,
    import: Option<api::ImportFn>,
    export: Option<api::ExportFn>,
    import_material: Option<api::MaterialImportFn>,
    export_material: Option<api::MaterialExportFn>,
    // Last: the functions above point into it.
    _library: &'static libloading::Library,
}

#[derive(Default)]
pub struct PluginHost {
    loaded: Vec<Loaded>,
    pub rejected: Vec<Rejected>,
    /// Where set, importers run in a worker process ([`Isolation`]).
    isolation: Option<Isolation>,
}

fn is_library(path: &Path) -> bool {
    matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("so") | Some("dylib") | Some("dll")
    )
}

/// Reads a descriptor string; `what` names it in errors.
unsafe fn descriptor_str(p: *const c_char, what: &str) -> Result<String, String> {
    if p.is_null() {
        return Err(format!("the descriptor's {what} is null"));
    }
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map(str::to_owned)
        .map_err(|_| format!("the descriptor's {what} is not UTF-8"))
}

impl PluginHost {
    /// Loads the plugins of the standard places and of `extra_dirs` (searched first).
    pub fn discover(extra_dirs: &[PathBuf]) -> Self {
        let mut host = Self::default();
        for dir in extra_dirs {
            host.load_dir(dir, false);
        }
        if let Some(paths) = std::env::var_os("KILN_PLUGIN_PATH") {
            for dir in std::env::split_paths(&paths) {
                host.load_dir(&dir, false);
            }
        }
        if let Some(exe_dir) = std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Path::to_owned))
        {
            host.load_dir(&exe_dir, true);
            host.load_dir(&exe_dir.join("deps"), true);
        }
        host
    }

    /// Loads every library in `dir`; with `kiln_only`, only those named `libkiln_*` or
    /// `kiln_*` (a build folder holds unrelated libraries).
    pub fn load_dir(&mut self, dir: &Path, kiln_only: bool) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| is_library(p))
            .collect();
        files.sort();
        for path in files {
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if kiln_only && !(name.starts_with("libkiln_") || name.starts_with("kiln_")) {
                continue;
            }
            // Cargo leaves the same library in the output folder and in its deps/: a
            // standard place's copy of a library already seen is not loaded twice.
            let seen = |p: &Path| p.file_name() == path.file_name();
            if kiln_only
                && (self.loaded.iter().any(|l| seen(&l.info.path))
                    || self.rejected.iter().any(|r| seen(&r.path)))
            {
                continue;
            }
            if let Err(reason) = self.load_file(&path) {
                tracing::warn!("plugin {} skipped: {reason}", path.display());
                self.rejected.push(Rejected { path, reason });
            }
        }
    }

    /// Loads one library; the reason it was not loaded otherwise.
    pub fn load_file(&mut self, path: &Path) -> Result<(), String> {
        // Loading runs the library's initialisers: only libraries put where plugins go
        // are loaded.
        // Libraries are never unloaded: a Rust plugin's thread-local destructors (and any
        // plugin's) would otherwise run after its code was unmapped, and crash. The host
        // loads each library once per process.
        let library: &'static libloading::Library = Box::leak(Box::new(
            unsafe { libloading::Library::new(path) }.map_err(|e| format!("cannot load: {e}"))?,
        ));
        let descriptor_fn = unsafe {
            library.get::<unsafe extern "C" fn() -> *const api::PluginDescriptor>(
                api::DESCRIPTOR_SYMBOL,
            )
        }
        .map_err(|_| "not a Kiln plugin: no kiln_plugin_descriptor symbol".to_owned())?;
        let descriptor = unsafe { descriptor_fn() };
        if descriptor.is_null() {
            return Err("kiln_plugin_descriptor returned null".into());
        }
        // Only the version field is read before the version is known to be spoken, and
        // a version-1 descriptor only as far as version 1 declares it.
        let version = unsafe { std::ptr::addr_of!((*descriptor).abi_version).read() };
        if !(api::MIN_ABI_VERSION..=api::ABI_VERSION).contains(&version) {
            return Err(format!(
                "plugin ABI version {version}, this Kiln speaks versions {} to {}",
                api::MIN_ABI_VERSION,
                api::ABI_VERSION
            ));
        }
        let d = unsafe { read_descriptor(descriptor, version) };
        let kind = match d.kind {
            api::KIND_IMPORTER if d.import.is_some() => PluginKind::Importer,
            api::KIND_EXPORTER if d.export.is_some() => PluginKind::Exporter,
            api::KIND_MATERIAL if d.import_material.is_some() || d.export_material.is_some() => {
                PluginKind::Material
            }
            k => return Err(format!("kind {k} without its function")),
        };
        let info = PluginInfo {
            name: unsafe { descriptor_str(d.name, "name") }?,
            version: unsafe { descriptor_str(d.version, "version") }?,
            kind,
            extensions: unsafe { descriptor_str(d.extensions, "extensions") }?
                .split(',')
                .map(|e| e.trim().trim_start_matches('.').to_ascii_lowercase())
                .filter(|e| !e.is_empty())
                .collect(),
            path: path.to_owned(),
        };
        if let Some(other) = self
            .loaded
            .iter()
            .find(|l| l.info.name == info.name && l.info.kind == info.kind)
        {
            return Err(format!(
                "{} {} is already loaded from {}",
                info.kind,
                info.name,
                other.info.path.display()
            ));
        }
        self.loaded.push(Loaded {
            info,
            import: d.import,
            export: d.export,
            import_material: d.import_material,
            export_material: d.export_material,
            _library: library,
        });
        Ok(())
    }

    pub fn plugins(&self) -> impl Iterator<Item = &PluginInfo> {
        self.loaded.iter().map(|l| &l.info)
    }

    fn find(&self, kind: PluginKind, path: &Path) -> Result<&Loaded, PluginError> {
        let extension = extension_of(path);
        self.loaded
            .iter()
            .find(|l| l.info.kind == kind && l.info.extensions.contains(&extension))
            .ok_or(PluginError::NoPlugin { kind, extension })
    }

    /// Whether a plugin of `kind` handles `path`'s extension.
    pub fn handles(&self, kind: PluginKind, path: &Path) -> bool {
        self.find(kind, path).is_ok()
    }

    /// From now on runs importers out of process, as `isolation` says.
    pub fn isolate_importers(&mut self, isolation: Isolation) {
        self.isolation = Some(isolation);
    }

    /// Imports `path` with the importer for its extension: in this process, or in a
    /// worker when [`PluginHost::isolate_importers`] was called.
    pub fn import(&self, path: &Path) -> Result<Imported, PluginError> {
        let plugin = self.find(PluginKind::Importer, path)?;
        let Some(isolation) = &self.isolation else {
            let mut state = builder::ImportState::new(path);
            let raw = state.raw_builder();
            plugin.run_import(path, &raw)?;
            return Ok(state.finish());
        };
        let failed = |message| PluginError::Failed {
            plugin: plugin.info.name.clone(),
            path: path.display().to_string(),
            message,
        };
        isolate::import(isolation, path)
            .map_err(failed)?
            .map_err(failed)
    }

    /// The worker's side of an isolated import ([`PluginHost::import`]): imports `path`
    /// in this process and returns the stream of the calls the importer made, ended by
    /// its outcome, for the host to replay.
    pub fn import_recorded(&self, path: &Path) -> Vec<u8> {
        let mut recorder = isolate::Recorder::new(path);
        let raw = recorder.raw_builder();
        let outcome = self
            .find(PluginKind::Importer, path)
            .and_then(|plugin| plugin.run_import(path, &raw))
            .map_err(|e| match e {
                PluginError::Failed { message, .. } => message,
                e => e.to_string(),
            });
        recorder.finish(outcome)
    }

    /// Writes `film` to `path` with the exporter plugin for its extension, or else with
    /// the host's own writer (PNG, JPEG, EXR).
    pub fn write_image(&self, path: &Path, film: &ExportFilm, options: &str) -> Result<(), String> {
        if self.handles(PluginKind::Exporter, path) {
            self.export(path, film, options).map_err(|e| e.to_string())
        } else {
            crate::film::output::write_image(path, film, options).map_err(|e| e.to_string())
        }
    }

    /// The extensions images can be written with: the exporter plugins' and the host's.
    pub fn export_extensions(&self) -> Vec<String> {
        let mut extensions: Vec<String> = crate::film::output::HOST_EXTENSIONS
            .map(String::from)
            .into();
        for plugin in self.plugins() {
            if plugin.kind == PluginKind::Exporter {
                extensions.extend(plugin.extensions.iter().cloned());
            }
        }
        extensions.sort();
        extensions.dedup();
        extensions
    }

    /// The material formats' extensions: those read (`writes` false) or written.
    pub fn material_extensions(&self, writes: bool) -> Vec<String> {
        let mut extensions: Vec<String> = self
            .loaded
            .iter()
            .filter(|l| {
                l.info.kind == PluginKind::Material
                    && if writes {
                        l.export_material.is_some()
                    } else {
                        l.import_material.is_some()
                    }
            })
            .flat_map(|l| l.info.extensions.iter().cloned())
            .collect();
        extensions.sort();
        extensions.dedup();
        extensions
    }

    /// Reads the materials of `path` with the material format for its extension. Each
    /// is parsed as a `.kmat` graph; one that does not parse is left out with a warning
    /// naming it. Image files the graphs name are resolved against `path`'s folder.
    pub fn import_materials(&self, path: &Path) -> Result<ImportedMaterials, PluginError> {
        let plugin = self.find(PluginKind::Material, path)?;
        let Some(import) = plugin.import_material else {
            return Err(PluginError::Invalid(format!(
                "{} writes \".{}\" files but does not read them",
                plugin.info.name,
                extension_of(path)
            )));
        };
        let c_path = c_path(path)?;
        let mut state = MaterialState {
            path: path.display().to_string(),
            imported: ImportedMaterials::default(),
        };
        let sink = api::MaterialSink {
            ctx: (&raw mut state).cast(),
            add_material: material_sink_add,
            warn: material_sink_warn,
        };
        plugin.call(path, |error| unsafe {
            import(c_path.as_ptr(), &sink, error)
        })?;
        Ok(state.imported)
    }

    /// Writes material `name` with `graph` to `path` with the material format for its
    /// extension, as `.kmat` text and the declarations of the node types it uses.
    pub fn export_material(
        &self,
        path: &Path,
        name: &str,
        graph: &crate::material::Graph,
    ) -> Result<(), PluginError> {
        let plugin = self.find(PluginKind::Material, path)?;
        let Some(export) = plugin.export_material else {
            return Err(PluginError::Invalid(format!(
                "{} reads \".{}\" files but does not write them",
                plugin.info.name,
                extension_of(path)
            )));
        };
        let c_path = c_path(path)?;
        let c_name = CString::new(name.replace('\0', " ")).expect("NULs replaced");
        let kmat = crate::material::material_text(name, graph)
            .map_err(|e| PluginError::Invalid(e.to_string()))?;
        let kinds = graph
            .nodes
            .values()
            .chain(graph.groups.values().flat_map(|g| g.nodes.values()))
            .map(|n| n.kind.as_str());
        let library = crate::material::docs::library_text(kinds);
        let c_kmat = CString::new(kmat.replace('\0', " ")).expect("NULs replaced");
        let c_library = CString::new(library).expect("no NULs in node declarations");
        plugin.call(path, |error| unsafe {
            export(
                c_path.as_ptr(),
                c_name.as_ptr(),
                c_kmat.as_ptr(),
                c_library.as_ptr(),
                error,
            )
        })
    }

    /// The extensions the importer plugins read.
    pub fn import_extensions(&self) -> Vec<String> {
        let mut extensions: Vec<String> = self
            .plugins()
            .filter(|p| p.kind == PluginKind::Importer)
            .flat_map(|p| p.extensions.iter().cloned())
            .collect();
        extensions.sort();
        extensions.dedup();
        extensions
    }

    /// Writes `film` to `path` with the exporter for its extension.
    pub fn export(&self, path: &Path, film: &ExportFilm, options: &str) -> Result<(), PluginError> {
        let plugin = self.find(PluginKind::Exporter, path)?;
        let export = plugin.export.expect("exporters have an export function");
        let c_path = c_path(path)?;
        let c_options = CString::new(options.replace('\0', " ")).expect("NULs replaced");
        let names: Vec<CString> = film
            .layers
            .iter()
            .map(|l| CString::new(l.name.replace('\0', " ")).expect("NULs replaced"))
            .collect();
        let layers: Vec<api::LayerView> = film
            .layers
            .iter()
            .zip(&names)
            .map(|(l, n)| api::LayerView {
                name: n.as_ptr(),
                channels: l.channels,
                data: l.data.as_ptr(),
            })
            .collect();
        let view = api::FilmView {
            width: film.width,
            height: film.height,
            radiance: film.radiance.as_ptr(),
            display: film.display.as_ptr(),
            layer_count: layers.len() as u32,
            layers: layers.as_ptr(),
        };
        plugin.call(path, |error| unsafe {
            export(c_path.as_ptr(), &view, c_options.as_ptr(), error)
        })
    }
}

/// A copy of the descriptor at `descriptor`, read field by field as far as ABI `version`
/// declares it (the functions of later versions are `None`).
///
/// # Safety
/// `descriptor` must point to a descriptor of `version`.
unsafe fn read_descriptor(
    descriptor: *const api::PluginDescriptor,
    version: u32,
) -> api::PluginDescriptor {
    use std::ptr::addr_of;
    unsafe {
        let (import_material, export_material) = if version >= 2 {
            (
                addr_of!((*descriptor).import_material).read(),
                addr_of!((*descriptor).export_material).read(),
            )
        } else {
            (None, None)
        };
        api::PluginDescriptor {
            abi_version: version,
            kind: addr_of!((*descriptor).kind).read(),
            name: addr_of!((*descriptor).name).read(),
            version: addr_of!((*descriptor).version).read(),
            extensions: addr_of!((*descriptor).extensions).read(),
            import: addr_of!((*descriptor).import).read(),
            export: addr_of!((*descriptor).export).read(),
            import_material,
            export_material,
        }
    }
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// What a material format's import gave: the materials that parsed, by name, and what
/// it (or the host) reported.
#[derive(Debug, Default)]
pub struct ImportedMaterials {
    pub materials: Vec<(String, crate::material::Graph)>,
    pub warnings: Vec<String>,
}

struct MaterialState {
    /// The imported file: graphs' image files are resolved against its folder.
    path: String,
    imported: ImportedMaterials,
}

/// A C string from a plugin, lossily.
unsafe fn lossy(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

unsafe extern "C" fn material_sink_add(
    ctx: *mut std::ffi::c_void,
    name: *const c_char,
    kmat: *const c_char,
) -> u32 {
    let state = unsafe { &mut *ctx.cast::<MaterialState>() };
    let (name, text) = unsafe { (lossy(name), lossy(kmat)) };
    let imported = &mut state.imported;
    match crate::material::parse_material(&text, &state.path) {
        Ok((_, graph)) => {
            imported.materials.push((name, graph));
            (imported.materials.len() - 1) as u32
        }
        Err(e) => {
            imported
                .warnings
                .push(format!("material {name} left out: {e}"));
            u32::MAX
        }
    }
}

unsafe extern "C" fn material_sink_warn(ctx: *mut std::ffi::c_void, message: *const c_char) {
    let state = unsafe { &mut *ctx.cast::<MaterialState>() };
    let message = unsafe { lossy(message) };
    state.imported.warnings.push(message);
}

fn c_path(path: &Path) -> Result<CString, PluginError> {
    CString::new(path.to_string_lossy().as_bytes())
        .map_err(|_| PluginError::Invalid(format!("{}: the path holds a NUL", path.display())))
}

impl Loaded {
    /// Runs the importer on `path` with `builder`.
    fn run_import(&self, path: &Path, builder: &api::SceneBuilder) -> Result<(), PluginError> {
        let import = self.import.expect("importers have an import function");
        let c_path = c_path(path)?;
        self.call(path, |error| unsafe {
            import(c_path.as_ptr(), builder, error)
        })
    }

    /// Runs a plugin function with an error buffer; its status and message as a result.
    fn call(
        &self,
        path: &Path,
        f: impl FnOnce(*mut api::ErrorBuffer) -> i32,
    ) -> Result<(), PluginError> {
        let mut message = vec![0 as c_char; 4096];
        let mut error = api::ErrorBuffer {
            data: message.as_mut_ptr(),
            capacity: message.len(),
        };
        let status = f(&mut error);
        if status == api::STATUS_OK {
            return Ok(());
        }
        let text = unsafe { CStr::from_ptr(message.as_ptr()) }
            .to_string_lossy()
            .into_owned();
        Err(PluginError::Failed {
            plugin: self.info.name.clone(),
            path: path.display().to_string(),
            message: if text.is_empty() {
                format!("error status {status}")
            } else {
                text
            },
        })
    }
}
