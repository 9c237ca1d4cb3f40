//! Kiln's plugin ABI: what an importer or exporter library exports, and what the host
//! hands it. Everything that crosses the boundary is `#[repr(C)]` (see `kiln_plugin.h`
//! for the same declarations in C); no Rust type does.
//!
//! A plugin exports one symbol, `kiln_plugin_descriptor`, a function returning a pointer
//! to a [`PluginDescriptor`] whose first field is the ABI version. The host reads that
//! field and nothing else unless it equals [`ABI_VERSION`].
//!
//! Rust plugins implement [`Importer`] or [`Exporter`] and call [`export_importer!`] or
//! [`export_exporter!`], which generate the descriptor and C shims that turn panics into
//! errors. See `docs/PLUGINS.md` for complete examples. [`kmat`] writes the material
//! graphs importers hand over; [`recording`] is a host for a plugin's own tests.

pub mod atomic;
pub mod kmat;
pub mod read;
pub mod recording;

use std::ffi::{CStr, CString, c_char, c_void};

/// Bumped on any change to the types below. Version 2 appended the material-format
/// functions to [`PluginDescriptor`]; the host still loads version-1 plugins (whose
/// descriptors end before them) and reads those fields only from version 2 on.
pub const ABI_VERSION: u32 = 2;
/// The oldest version the host loads.
pub const MIN_ABI_VERSION: u32 = 1;

/// The symbol every plugin exports.
pub const DESCRIPTOR_SYMBOL: &[u8] = b"kiln_plugin_descriptor";

/// The environment variable through which the host hands its limit on the vertices, and
/// the triangles, of one import (`kiln --max-triangles`) to the importers it loads, in
/// its own process or an isolated one, so that an importer can refuse the counts a file
/// claims before allocating them. The host sets it before it loads any plugin.
pub const MAX_TRIANGLES_ENV: &str = "KILN_MAX_TRIANGLES";
/// The host's limit when it sets none.
pub const DEFAULT_MAX_TRIANGLES: u64 = 1 << 26;

/// The limit in [`MAX_TRIANGLES_ENV`], or [`DEFAULT_MAX_TRIANGLES`].
pub fn max_triangles() -> u64 {
    std::env::var(MAX_TRIANGLES_ENV)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_MAX_TRIANGLES)
}

pub const KIND_IMPORTER: u32 = 1;
pub const KIND_EXPORTER: u32 = 2;
/// A material format (MaterialX, …): reads files into material graphs, writes graphs to
/// files, or both (ABI version 2).
pub const KIND_MATERIAL: u32 = 3;

/// Return codes of `import` and `export`.
pub const STATUS_OK: i32 = 0;
pub const STATUS_ERROR: i32 = 1;

pub type ImportFn = unsafe extern "C" fn(
    path: *const c_char,
    builder: *const SceneBuilder,
    error: *mut ErrorBuffer,
) -> i32;
pub type ExportFn = unsafe extern "C" fn(
    path: *const c_char,
    film: *const FilmView,
    options: *const c_char,
    error: *mut ErrorBuffer,
) -> i32;

/// Reads the material file `path` and hands each material it holds to `sink`.
pub type MaterialImportFn = unsafe extern "C" fn(
    path: *const c_char,
    sink: *const MaterialSink,
    error: *mut ErrorBuffer,
) -> i32;
/// Writes the material graph `kmat` (the text of a `.kmat` file) named `name` to `path`.
/// Files it names are relative to `path`'s folder, as the host has rewritten them.
/// `library` declares the node types the graph uses (RON, [`kmat::read::parse_library`]):
/// their sockets' types and defaults, which the graph's text does not carry.
pub type MaterialExportFn = unsafe extern "C" fn(
    path: *const c_char,
    name: *const c_char,
    kmat: *const c_char,
    library: *const c_char,
    error: *mut ErrorBuffer,
) -> i32;

/// What `kiln_plugin_descriptor` returns. Strings are NUL-terminated UTF-8 and live as
/// long as the library is loaded.
#[repr(C)]
pub struct PluginDescriptor {
    /// Must be first: the host checks it before reading anything else.
    pub abi_version: u32,
    pub kind: u32,
    pub name: *const c_char,
    pub version: *const c_char,
    /// File extensions handled, lower case, comma-separated, without dots: `"gltf,glb"`.
    pub extensions: *const c_char,
    /// For importers; null for exporters.
    pub import: Option<ImportFn>,
    /// For exporters; null for importers.
    pub export: Option<ExportFn>,
    /// For material formats that read files (ABI version 2 on); null otherwise.
    pub import_material: Option<MaterialImportFn>,
    /// For material formats that write files (ABI version 2 on); null otherwise.
    pub export_material: Option<MaterialExportFn>,
}

// The descriptor is immutable static data.
unsafe impl Sync for PluginDescriptor {}

/// Where a plugin writes the message of a failure (NUL-terminated, truncated to fit).
#[repr(C)]
pub struct ErrorBuffer {
    pub data: *mut c_char,
    pub capacity: usize,
}

impl ErrorBuffer {
    /// Writes `message`, truncated at a character boundary to the buffer's capacity.
    ///
    /// # Safety
    /// `self.data` must point to `self.capacity` writable bytes (or be null).
    pub unsafe fn write(&mut self, message: &str) {
        if self.data.is_null() || self.capacity == 0 {
            return;
        }
        let mut end = message.len().min(self.capacity - 1);
        while !message.is_char_boundary(end) {
            end -= 1;
        }
        let bytes = &message.as_bytes()[..end];
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), self.data.cast::<u8>(), end);
            *self.data.add(end) = 0;
        }
    }
}

/// A mesh as arrays the plugin owns for the duration of the call; the host copies them
/// once into its own storage. Optional arrays are null or hold one entry per vertex.
#[repr(C)]
pub struct MeshData {
    pub name: *const c_char,
    pub vertex_count: usize,
    /// 3 floats per vertex.
    pub positions: *const f32,
    /// 3 floats per vertex, or null.
    pub normals: *const f32,
    /// 2 floats per vertex (v up, as glTF's and OBJ's flipped where needed), or null.
    pub uvs: *const f32,
    /// A second set of texture coordinates (glTF TEXCOORD_1), like `uvs`, or null.
    pub uvs1: *const f32,
    /// 4 floats per vertex (xyz tangent, w handedness), or null.
    pub tangents: *const f32,
    /// 4 floats per vertex (linear RGBA), or null.
    pub colors: *const f32,
    /// 3 indices per triangle.
    pub indices: *const u32,
    pub index_count: usize,
}

/// A perspective camera: a world transform (camera looks down its -z, y up) and the
/// vertical field of view.
#[repr(C)]
pub struct CameraData {
    /// Column-major 4×4 camera-to-world matrix.
    pub to_world: [f32; 16],
    pub fov_y_degrees: f32,
    pub aperture_radius: f32,
    pub focus_distance: f32,
}

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DISTANT: u32 = 2;

/// A punctual light (KHR_lights_punctual): position and direction in world space.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightData {
    pub kind: u32,
    pub position: [f32; 3],
    /// The direction light travels (spot, distant).
    pub direction: [f32; 3],
    /// Radiant intensity in W/sr (point, spot) or irradiance in W/m² (distant), linear RGB.
    pub intensity: [f32; 3],
    /// Half-angle of the spot's cone in degrees (glTF's outer cone angle), and the
    /// fraction of it over which the light fades out.
    pub cone_angle_degrees: f32,
    pub blend: f32,
    pub radius: f32,
}

/// Callbacks the host provides to importers. Ids are indices in the order of the calls;
/// `u32::MAX` means the host rejected the data (the reason is reported as a warning).
#[repr(C)]
pub struct SceneBuilder {
    pub ctx: *mut c_void,
    pub add_mesh: unsafe extern "C" fn(ctx: *mut c_void, mesh: *const MeshData) -> u32,
    /// A material as the text of a `.kmat` file (a node graph, docs/NODES.md). Image
    /// files it names are relative to the imported file; `image:N` names an image given
    /// by `add_image`.
    pub add_material:
        unsafe extern "C" fn(ctx: *mut c_void, name: *const c_char, kmat: *const c_char) -> u32,
    /// An encoded image (PNG, JPEG, …) the materials refer to as `image:N`.
    pub add_image: unsafe extern "C" fn(
        ctx: *mut c_void,
        name: *const c_char,
        bytes: *const u8,
        len: usize,
    ) -> u32,
    /// An instance of a mesh with a material and a column-major 4×4 object-to-world
    /// transform.
    pub add_instance: unsafe extern "C" fn(
        ctx: *mut c_void,
        mesh: u32,
        material: u32,
        to_world: *const [f32; 16],
    ) -> u32,
    pub set_camera: unsafe extern "C" fn(ctx: *mut c_void, camera: *const CameraData),
    pub add_light: unsafe extern "C" fn(ctx: *mut c_void, light: *const LightData) -> u32,
    /// Something the plugin could not represent (an unsupported extension, a skipped
    /// primitive): reported, not silently dropped.
    pub warn: unsafe extern "C" fn(ctx: *mut c_void, message: *const c_char),
}

/// Callbacks the host provides to material importers.
#[repr(C)]
pub struct MaterialSink {
    pub ctx: *mut c_void,
    /// A material as the text of a `.kmat` file; image files it names are relative to
    /// the imported file. Returns the material's index, or `u32::MAX` when the host
    /// rejected it (the reason is reported as a warning).
    pub add_material:
        unsafe extern "C" fn(ctx: *mut c_void, name: *const c_char, kmat: *const c_char) -> u32,
    /// Something the plugin could not represent (a node it cannot map, a missing
    /// texture): reported, not silently dropped.
    pub warn: unsafe extern "C" fn(ctx: *mut c_void, message: *const c_char),
}

/// One named image layer of the film: `channels` floats per pixel, row-major from the
/// top-left.
#[repr(C)]
pub struct LayerView {
    pub name: *const c_char,
    pub channels: u32,
    pub data: *const f32,
}

/// What exporters receive: the film as linear radiance (RGBA f32), the same tonemapped
/// for display (RGBA in [0, 1], sRGB-encoded), and AOV layers (albedo, normal, depth, …).
#[repr(C)]
pub struct FilmView {
    pub width: u32,
    pub height: u32,
    pub radiance: *const f32,
    pub display: *const f32,
    pub layer_count: u32,
    pub layers: *const LayerView,
}

// ------------------------------------------------------------------- Rust side

/// A safe view of the host's builder for Rust importers.
pub struct Builder<'a> {
    raw: &'a SceneBuilder,
}

/// A mesh given to [`Builder::add_mesh`]; empty optional arrays mean "none".
#[derive(Default)]
pub struct Mesh<'a> {
    pub name: &'a str,
    pub positions: &'a [[f32; 3]],
    pub normals: &'a [[f32; 3]],
    pub uvs: &'a [[f32; 2]],
    pub uvs1: &'a [[f32; 2]],
    pub tangents: &'a [[f32; 4]],
    pub colors: &'a [[f32; 4]],
    pub indices: &'a [u32],
}

fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("NULs replaced")
}

fn ptr_or_null<T>(v: &[T]) -> *const f32 {
    if v.is_empty() {
        std::ptr::null()
    } else {
        v.as_ptr().cast()
    }
}

impl<'a> Builder<'a> {
    /// # Safety
    /// `raw` must be a valid builder for the duration of the import call.
    pub unsafe fn from_raw(raw: &'a SceneBuilder) -> Self {
        Self { raw }
    }

    /// Adds a mesh; `None` if the host rejected it (it says why through a warning).
    pub fn add_mesh(&mut self, mesh: &Mesh) -> Option<u32> {
        let name = c_string(mesh.name);
        let data = MeshData {
            name: name.as_ptr(),
            vertex_count: mesh.positions.len(),
            positions: ptr_or_null(mesh.positions),
            normals: ptr_or_null(mesh.normals),
            uvs: ptr_or_null(mesh.uvs),
            uvs1: ptr_or_null(mesh.uvs1),
            tangents: ptr_or_null(mesh.tangents),
            colors: ptr_or_null(mesh.colors),
            indices: mesh.indices.as_ptr(),
            index_count: mesh.indices.len(),
        };
        let id = unsafe { (self.raw.add_mesh)(self.raw.ctx, &data) };
        (id != u32::MAX).then_some(id)
    }

    /// Adds a material given as `.kmat` text.
    pub fn add_material(&mut self, name: &str, kmat: &str) -> Option<u32> {
        let (name, kmat) = (c_string(name), c_string(kmat));
        let id = unsafe { (self.raw.add_material)(self.raw.ctx, name.as_ptr(), kmat.as_ptr()) };
        (id != u32::MAX).then_some(id)
    }

    /// Adds an encoded image; materials refer to it as `image:N`.
    pub fn add_image(&mut self, name: &str, bytes: &[u8]) -> Option<u32> {
        let name = c_string(name);
        let id = unsafe {
            (self.raw.add_image)(self.raw.ctx, name.as_ptr(), bytes.as_ptr(), bytes.len())
        };
        (id != u32::MAX).then_some(id)
    }

    pub fn add_instance(&mut self, mesh: u32, material: u32, to_world: [f32; 16]) -> Option<u32> {
        let id = unsafe { (self.raw.add_instance)(self.raw.ctx, mesh, material, &to_world) };
        (id != u32::MAX).then_some(id)
    }

    pub fn set_camera(&mut self, camera: &CameraData) {
        unsafe { (self.raw.set_camera)(self.raw.ctx, camera) }
    }

    pub fn add_light(&mut self, light: &LightData) -> Option<u32> {
        let id = unsafe { (self.raw.add_light)(self.raw.ctx, light) };
        (id != u32::MAX).then_some(id)
    }

    pub fn warn(&mut self, message: &str) {
        let m = c_string(message);
        unsafe { (self.raw.warn)(self.raw.ctx, m.as_ptr()) }
    }
}

/// A safe view of the host's material sink for Rust material importers.
pub struct Materials<'a> {
    raw: &'a MaterialSink,
}

impl<'a> Materials<'a> {
    /// # Safety
    /// `raw` must be a valid sink for the duration of the import call.
    pub unsafe fn from_raw(raw: &'a MaterialSink) -> Self {
        Self { raw }
    }

    /// Adds a material given as `.kmat` text; `None` if the host rejected it.
    pub fn add(&mut self, name: &str, kmat: &str) -> Option<u32> {
        let (name, kmat) = (c_string(name), c_string(kmat));
        let id = unsafe { (self.raw.add_material)(self.raw.ctx, name.as_ptr(), kmat.as_ptr()) };
        (id != u32::MAX).then_some(id)
    }

    pub fn warn(&mut self, message: &str) {
        let m = c_string(message);
        unsafe { (self.raw.warn)(self.raw.ctx, m.as_ptr()) }
    }
}

/// A safe view of the film for Rust exporters.
pub struct Film<'a> {
    pub width: u32,
    pub height: u32,
    /// Linear RGBA, 4 floats per pixel.
    pub radiance: &'a [f32],
    /// Tonemapped, sRGB-encoded RGBA in [0, 1].
    pub display: &'a [f32],
    pub layers: Vec<Layer<'a>>,
}

pub struct Layer<'a> {
    pub name: &'a str,
    pub channels: u32,
    pub data: &'a [f32],
}

impl<'a> Film<'a> {
    /// # Safety
    /// `raw` and everything it points to must be valid for `'a`.
    pub unsafe fn from_raw(raw: &'a FilmView) -> Self {
        let pixels = (raw.width as usize).saturating_mul(raw.height as usize);
        // A size whose arrays would not fit in memory has no data (exporters check lengths).
        let slice = |p: *const f32, n: Option<usize>| match n {
            Some(n) if !p.is_null() && n <= isize::MAX as usize / 4 => unsafe {
                std::slice::from_raw_parts(p, n)
            },
            _ => &[][..],
        };
        let layers = (0..raw.layer_count as usize)
            .map(|i| {
                let l = unsafe { &*raw.layers.add(i) };
                Layer {
                    name: unsafe { CStr::from_ptr(l.name) }.to_str().unwrap_or("?"),
                    channels: l.channels,
                    data: slice(l.data, pixels.checked_mul(l.channels as usize)),
                }
            })
            .collect();
        Self {
            width: raw.width,
            height: raw.height,
            radiance: slice(raw.radiance, pixels.checked_mul(4)),
            display: slice(raw.display, pixels.checked_mul(4)),
            layers,
        }
    }
}

/// Export options, `key=value` separated by `;` (e.g. `bits=16;quality=90`).
pub fn parse_options(options: &str) -> Vec<(&str, &str)> {
    options
        .split(';')
        .filter(|s| !s.trim().is_empty())
        .map(|kv| kv.split_once('=').unwrap_or((kv, "")))
        .map(|(k, v)| (k.trim(), v.trim()))
        .collect()
}

/// An importer: reads a file and describes it to the builder.
pub trait Importer {
    const NAME: &'static str;
    const VERSION: &'static str;
    /// Lower case, comma-separated, without dots.
    const EXTENSIONS: &'static str;
    fn import(path: &std::path::Path, builder: &mut Builder) -> Result<(), String>;
}

/// An exporter: writes the film to a file.
pub trait Exporter {
    const NAME: &'static str;
    const VERSION: &'static str;
    const EXTENSIONS: &'static str;
    fn export(path: &std::path::Path, film: &Film, options: &[(&str, &str)]) -> Result<(), String>;
}

/// A material format: reads material files into `.kmat` graphs, and writes graphs as
/// files. A format that only reads (or only writes) returns an error from the other.
pub trait MaterialFormat {
    const NAME: &'static str;
    const VERSION: &'static str;
    const EXTENSIONS: &'static str;
    /// Whether [`MaterialFormat::import`] and [`MaterialFormat::export`] are
    /// implemented: the descriptor offers only those that are.
    const READS: bool = true;
    const WRITES: bool = true;
    fn import(path: &std::path::Path, materials: &mut Materials) -> Result<(), String>;
    /// `library` is the host's declaration of the node types `kmat` uses.
    fn export(path: &std::path::Path, name: &str, kmat: &str, library: &str) -> Result<(), String>;
}

/// The message of a caught panic.
pub fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_owned()
    }
}

/// # Safety
/// `path` must be null or a NUL-terminated string.
#[doc(hidden)]
pub unsafe fn path_from_c(path: *const c_char) -> Result<std::path::PathBuf, String> {
    if path.is_null() {
        return Err("null path".into());
    }
    let s = unsafe { CStr::from_ptr(path) }
        .to_str()
        .map_err(|_| "the path is not UTF-8".to_owned())?;
    Ok(std::path::PathBuf::from(s))
}

thread_local! {
    static PANIC_LOCATION: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
    static IN_GUARD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// A panic hook that, for panics inside [`guarded`], records where they happened instead
/// of printing to the host's terminal (the panic comes back as an error message); other
/// panics go to the hook that was there before.
fn install_quiet_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if IN_GUARD.with(|g| g.get()) {
                let location = info
                    .location()
                    .map(|l| format!("{}:{}", l.file(), l.line()));
                PANIC_LOCATION.with(|p| *p.borrow_mut() = location);
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `f`, turning an error or a panic into `STATUS_ERROR` and a message.
///
/// # Safety
/// `error` must be null or point to a valid [`ErrorBuffer`].
#[doc(hidden)]
pub unsafe fn guarded(error: *mut ErrorBuffer, f: impl FnOnce() -> Result<(), String>) -> i32 {
    install_quiet_panic_hook();
    let was = IN_GUARD.with(|g| g.replace(true));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    IN_GUARD.with(|g| g.set(was));
    let message = match outcome {
        Ok(Ok(())) => return STATUS_OK,
        Ok(Err(e)) => e,
        Err(payload) => {
            let location = PANIC_LOCATION.with(|p| p.borrow_mut().take());
            match location {
                Some(at) => format!("the plugin panicked at {at}: {}", panic_message(payload)),
                None => format!("the plugin panicked: {}", panic_message(payload)),
            }
        }
    };
    if !error.is_null() {
        unsafe { (*error).write(&message) };
    }
    STATUS_ERROR
}

/// A descriptor with the strings it points to, built once per library.
#[doc(hidden)]
pub struct StaticDescriptor {
    _strings: [CString; 3],
    pub descriptor: PluginDescriptor,
}

// Immutable after construction; the strings live as long as the descriptor.
unsafe impl Send for StaticDescriptor {}
unsafe impl Sync for StaticDescriptor {}

impl StaticDescriptor {
    #[doc(hidden)]
    pub fn new(
        kind: u32,
        name: &str,
        version: &str,
        extensions: &str,
        import: Option<ImportFn>,
        export: Option<ExportFn>,
    ) -> Self {
        Self::with_materials(kind, name, version, extensions, import, export, None, None)
    }

    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    pub fn with_materials(
        kind: u32,
        name: &str,
        version: &str,
        extensions: &str,
        import: Option<ImportFn>,
        export: Option<ExportFn>,
        import_material: Option<MaterialImportFn>,
        export_material: Option<MaterialExportFn>,
    ) -> Self {
        let strings = [c_string(name), c_string(version), c_string(extensions)];
        let descriptor = PluginDescriptor {
            abi_version: ABI_VERSION,
            kind,
            name: strings[0].as_ptr(),
            version: strings[1].as_ptr(),
            extensions: strings[2].as_ptr(),
            import,
            export,
            import_material,
            export_material,
        };
        Self {
            _strings: strings,
            descriptor,
        }
    }
}

/// The body of `kiln_plugin_descriptor`: the descriptor of `$t`, built on first call.
#[doc(hidden)]
#[macro_export]
macro_rules! __kiln_descriptor {
    ($kind:expr, $trait:path, $t:ty, $import:expr, $export:expr) => {{
        static DESCRIPTOR: ::std::sync::OnceLock<$crate::StaticDescriptor> =
            ::std::sync::OnceLock::new();
        &DESCRIPTOR
            .get_or_init(|| {
                $crate::StaticDescriptor::new(
                    $kind,
                    <$t as $trait>::NAME,
                    <$t as $trait>::VERSION,
                    <$t as $trait>::EXTENSIONS,
                    $import,
                    $export,
                )
            })
            .descriptor
    }};
}

/// Exports `$t: Importer` as this library's plugin: the descriptor symbol and a C shim
/// that catches panics and reports errors.
#[macro_export]
macro_rules! export_importer {
    ($t:ty) => {
        #[unsafe(no_mangle)]
        pub extern "C" fn kiln_plugin_descriptor() -> *const $crate::PluginDescriptor {
            unsafe extern "C" fn import(
                path: *const ::std::ffi::c_char,
                builder: *const $crate::SceneBuilder,
                error: *mut $crate::ErrorBuffer,
            ) -> i32 {
                let run = || {
                    let path = unsafe { $crate::path_from_c(path) }?;
                    if builder.is_null() {
                        return Err("null builder".into());
                    }
                    let mut b = unsafe { $crate::Builder::from_raw(&*builder) };
                    <$t as $crate::Importer>::import(&path, &mut b)
                };
                unsafe { $crate::guarded(error, run) }
            }
            $crate::__kiln_descriptor!(
                $crate::KIND_IMPORTER,
                $crate::Importer,
                $t,
                Some(import),
                None
            )
        }
    };
}

/// Exports `$t: Exporter` as this library's plugin.
#[macro_export]
macro_rules! export_exporter {
    ($t:ty) => {
        #[unsafe(no_mangle)]
        pub extern "C" fn kiln_plugin_descriptor() -> *const $crate::PluginDescriptor {
            unsafe extern "C" fn export(
                path: *const ::std::ffi::c_char,
                film: *const $crate::FilmView,
                options: *const ::std::ffi::c_char,
                error: *mut $crate::ErrorBuffer,
            ) -> i32 {
                let run = || {
                    let path = unsafe { $crate::path_from_c(path) }?;
                    if film.is_null() {
                        return Err("null film".into());
                    }
                    let film = unsafe { $crate::Film::from_raw(&*film) };
                    let options = if options.is_null() {
                        ""
                    } else {
                        unsafe { ::std::ffi::CStr::from_ptr(options) }
                            .to_str()
                            .unwrap_or("")
                    };
                    <$t as $crate::Exporter>::export(&path, &film, &$crate::parse_options(options))
                };
                unsafe { $crate::guarded(error, run) }
            }
            $crate::__kiln_descriptor!(
                $crate::KIND_EXPORTER,
                $crate::Exporter,
                $t,
                None,
                Some(export)
            )
        }
    };
}

/// Exports `$t: MaterialFormat` as this library's plugin: the descriptor symbol and C
/// shims that catch panics and report errors.
#[macro_export]
macro_rules! export_material_format {
    ($t:ty) => {
        #[unsafe(no_mangle)]
        pub extern "C" fn kiln_plugin_descriptor() -> *const $crate::PluginDescriptor {
            unsafe extern "C" fn import_material(
                path: *const ::std::ffi::c_char,
                sink: *const $crate::MaterialSink,
                error: *mut $crate::ErrorBuffer,
            ) -> i32 {
                let run = || {
                    let path = unsafe { $crate::path_from_c(path) }?;
                    if sink.is_null() {
                        return Err("null material sink".into());
                    }
                    let mut m = unsafe { $crate::Materials::from_raw(&*sink) };
                    <$t as $crate::MaterialFormat>::import(&path, &mut m)
                };
                unsafe { $crate::guarded(error, run) }
            }
            unsafe extern "C" fn export_material(
                path: *const ::std::ffi::c_char,
                name: *const ::std::ffi::c_char,
                kmat: *const ::std::ffi::c_char,
                library: *const ::std::ffi::c_char,
                error: *mut $crate::ErrorBuffer,
            ) -> i32 {
                let run = || {
                    let path = unsafe { $crate::path_from_c(path) }?;
                    let text = |p: *const ::std::ffi::c_char, what: &str| {
                        if p.is_null() {
                            return Err(format!("null {what}"));
                        }
                        unsafe { ::std::ffi::CStr::from_ptr(p) }
                            .to_str()
                            .map_err(|_| format!("the {what} is not UTF-8"))
                    };
                    let (name, kmat) = (text(name, "name")?, text(kmat, "material")?);
                    let library = text(library, "node library")?;
                    <$t as $crate::MaterialFormat>::export(&path, name, kmat, library)
                };
                unsafe { $crate::guarded(error, run) }
            }
            static DESCRIPTOR: ::std::sync::OnceLock<$crate::StaticDescriptor> =
                ::std::sync::OnceLock::new();
            &DESCRIPTOR
                .get_or_init(|| {
                    $crate::StaticDescriptor::with_materials(
                        $crate::KIND_MATERIAL,
                        <$t as $crate::MaterialFormat>::NAME,
                        <$t as $crate::MaterialFormat>::VERSION,
                        <$t as $crate::MaterialFormat>::EXTENSIONS,
                        None,
                        None,
                        <$t as $crate::MaterialFormat>::READS.then_some(import_material as _),
                        <$t as $crate::MaterialFormat>::WRITES.then_some(export_material as _),
                    )
                })
                .descriptor
        }
    };
}
