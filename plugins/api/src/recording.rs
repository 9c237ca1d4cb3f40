//! A test host for plugin authors: a [`SceneBuilder`] that records everything an importer
//! hands over, driven through the plugin's exported C entry point as Kiln's host drives
//! it, and a film an exporter can be called with.
//!
//! The recorder checks what the host would refuse (empty or malformed meshes, indices out
//! of range, instances of missing meshes, non-finite transforms and lights, images
//! without data) and lists it in [`Recorded::violations`]; an importer's tests should
//! expect none. Material graphs are not checked unless the test passes a check (this crate
//! cannot depend on Kiln's compiler; a plugin's tests can, and pass
//! `kiln::material::parse_material` + `compile` as [`Recorder::check_materials`]).
//! It is not a host: nothing is rendered or kept beyond the import.

use std::ffi::{CStr, CString, c_char, c_void};
use std::path::Path;

use crate::{
    ABI_VERSION, CameraData, ErrorBuffer, FilmView, LayerView, LightData, MeshData,
    PluginDescriptor, STATUS_OK, SceneBuilder, ptr_or_null,
};

/// A mesh as the importer handed it over; optional arrays it did not send are `None`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordedMesh {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
    pub uvs1: Option<Vec<[f32; 2]>>,
    pub tangents: Option<Vec<[f32; 4]>>,
    pub colors: Option<Vec<[f32; 4]>>,
    pub indices: Vec<u32>,
}

/// Everything an import added, in the order of the calls (ids are indices).
#[derive(Clone, Debug, Default)]
pub struct Recorded {
    pub meshes: Vec<RecordedMesh>,
    /// (name, `.kmat` text)
    pub materials: Vec<(String, String)>,
    /// (name, encoded bytes)
    pub images: Vec<(String, Vec<u8>)>,
    /// (mesh, material, column-major object-to-world transform)
    pub instances: Vec<(u32, u32, [f32; 16])>,
    /// (to_world, fov_y_degrees) of every `set_camera` call.
    pub cameras: Vec<([f32; 16], f32)>,
    pub lights: Vec<LightData>,
    pub warnings: Vec<String>,
    /// Data the host would have refused: an importer should never send it.
    pub violations: Vec<String>,
}

impl Recorded {
    /// The `.kmat` text of material `id`.
    pub fn material(&self, id: u32) -> &str {
        &self.materials[id as usize].1
    }
}

/// Checks a material as (name, `.kmat` text); the error refuses it.
pub type MaterialCheck = Box<dyn Fn(&str, &str) -> Result<(), String>>;

/// The recording host: what it checks and refuses, and what it has recorded.
#[derive(Default)]
pub struct Recorder {
    /// Run on every material; an error is recorded as a violation and the material
    /// refused.
    pub check_material: Option<MaterialCheck>,
    /// Refuse every mesh and material, as a host out of memory would.
    pub refuse: bool,
    pub recorded: Recorded,
}

impl Recorder {
    /// A recorder that checks every material with `check`.
    pub fn check_materials(check: impl Fn(&str, &str) -> Result<(), String> + 'static) -> Self {
        Self {
            check_material: Some(Box::new(check)),
            ..Self::default()
        }
    }

    /// The C builder whose callbacks record into `self`; valid while `self` is neither
    /// moved nor dropped.
    pub fn scene_builder(&mut self) -> SceneBuilder {
        SceneBuilder {
            ctx: (self as *mut Recorder).cast(),
            add_mesh,
            add_material,
            add_image,
            add_instance,
            set_camera,
            add_light,
            warn,
        }
    }

    /// Imports `path` through the importer `descriptor` describes (after checking its ABI
    /// version): the import's result, with the error message the plugin wrote, and what
    /// it added.
    pub fn import(
        mut self,
        descriptor: &PluginDescriptor,
        path: &Path,
    ) -> (Result<(), String>, Recorded) {
        assert_eq!(
            descriptor.abi_version, ABI_VERSION,
            "the plugin's ABI version"
        );
        let import = descriptor
            .import
            .expect("an importer has an import function");
        let builder = self.scene_builder();
        let c_path = CString::new(path.to_string_lossy().as_bytes()).expect("no NUL in a path");
        let mut message = vec![0 as c_char; 4096];
        let mut error = ErrorBuffer {
            data: message.as_mut_ptr(),
            capacity: message.len(),
        };
        let status = unsafe { import(c_path.as_ptr(), &builder, &mut error) };
        // The plugin API installs a hook that silences panics inside plugin calls (they
        // come back as errors); a test process wants its own assertion messages printed.
        drop(std::panic::take_hook());
        let result = if status == STATUS_OK {
            Ok(())
        } else {
            Err(text(message.as_ptr()))
        };
        (result, self.recorded)
    }
}

fn recorder<'a>(ctx: *mut c_void) -> &'a mut Recorder {
    // `scene_builder` passes a live `Recorder` as the context.
    unsafe { &mut *ctx.cast::<Recorder>() }
}

fn text(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// `n` items of `N` floats from `p`, or None for a null array.
///
/// # Safety
/// `p` must be null or point to `n * N` floats.
unsafe fn array<const N: usize>(p: *const f32, n: usize) -> Option<Vec<[f32; N]>> {
    if p.is_null() {
        return None;
    }
    let flat = unsafe { std::slice::from_raw_parts(p, n * N) };
    Some(
        flat.chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect(),
    )
}

unsafe extern "C" fn add_mesh(ctx: *mut c_void, m: *const MeshData) -> u32 {
    let r = recorder(ctx);
    if r.refuse {
        return u32::MAX;
    }
    let s = &mut r.recorded;
    let m = unsafe { &*m };
    let n = m.vertex_count;
    let name = text(m.name);
    if m.positions.is_null() || m.indices.is_null() || m.index_count % 3 != 0 || n == 0 {
        s.violations
            .push(format!("mesh {name}: empty or malformed"));
        return u32::MAX;
    }
    let indices = unsafe { std::slice::from_raw_parts(m.indices, m.index_count) }.to_vec();
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        s.violations.push(format!(
            "mesh {name}: index {bad} out of range for {n} vertices"
        ));
        return u32::MAX;
    }
    let mesh = RecordedMesh {
        name,
        positions: unsafe { array::<3>(m.positions, n) }.unwrap_or_default(),
        normals: unsafe { array::<3>(m.normals, n) },
        uvs: unsafe { array::<2>(m.uvs, n) },
        uvs1: unsafe { array::<2>(m.uvs1, n) },
        tangents: unsafe { array::<4>(m.tangents, n) },
        colors: unsafe { array::<4>(m.colors, n) },
        indices,
    };
    if mesh.positions.iter().flatten().any(|v| !v.is_finite()) {
        // The host refuses these with a warning; not the importer's fault.
        s.warnings
            .push(format!("host: mesh {}: non-finite positions", mesh.name));
        return u32::MAX;
    }
    s.meshes.push(mesh);
    (s.meshes.len() - 1) as u32
}

unsafe extern "C" fn add_material(
    ctx: *mut c_void,
    name: *const c_char,
    kmat: *const c_char,
) -> u32 {
    let r = recorder(ctx);
    if r.refuse {
        return u32::MAX;
    }
    let (name, kmat) = (text(name), text(kmat));
    if let Some(Err(e)) = r.check_material.as_ref().map(|check| check(&name, &kmat)) {
        r.recorded.violations.push(format!("material {name}: {e}"));
        return u32::MAX;
    }
    let s = &mut r.recorded;
    s.materials.push((name, kmat));
    (s.materials.len() - 1) as u32
}

unsafe extern "C" fn add_image(
    ctx: *mut c_void,
    name: *const c_char,
    bytes: *const u8,
    len: usize,
) -> u32 {
    let s = &mut recorder(ctx).recorded;
    if bytes.is_null() || len == 0 {
        s.violations.push("image without data".into());
        return u32::MAX;
    }
    let data = unsafe { std::slice::from_raw_parts(bytes, len) }.to_vec();
    s.images.push((text(name), data));
    (s.images.len() - 1) as u32
}

unsafe extern "C" fn add_instance(
    ctx: *mut c_void,
    mesh: u32,
    material: u32,
    m: *const [f32; 16],
) -> u32 {
    let s = &mut recorder(ctx).recorded;
    let m = unsafe { *m };
    if mesh as usize >= s.meshes.len() {
        s.violations
            .push(format!("instance of missing mesh {mesh}"));
        return u32::MAX;
    }
    if material != u32::MAX && material as usize >= s.materials.len() {
        s.violations
            .push(format!("instance with missing material {material}"));
    }
    if m.iter().any(|v| !v.is_finite()) {
        s.violations
            .push("instance with a non-finite transform".into());
        return u32::MAX;
    }
    s.instances.push((mesh, material, m));
    (s.instances.len() - 1) as u32
}

unsafe extern "C" fn set_camera(ctx: *mut c_void, c: *const CameraData) {
    let c = unsafe { &*c };
    recorder(ctx)
        .recorded
        .cameras
        .push((c.to_world, c.fov_y_degrees));
}

unsafe extern "C" fn add_light(ctx: *mut c_void, l: *const LightData) -> u32 {
    let s = &mut recorder(ctx).recorded;
    let l = unsafe { &*l };
    let all_finite = l
        .position
        .iter()
        .chain(&l.direction)
        .chain(&l.intensity)
        .chain([&l.cone_angle_degrees, &l.blend])
        .all(|v| v.is_finite());
    if !all_finite {
        s.violations.push("light with non-finite data".into());
        return u32::MAX;
    }
    s.lights.push(*l);
    (s.lights.len() - 1) as u32
}

unsafe extern "C" fn warn(ctx: *mut c_void, message: *const c_char) {
    recorder(ctx).recorded.warnings.push(text(message));
}

// ------------------------------------------------------------------- exporters

/// An image layer a [`TestFilm`] owns.
#[derive(Clone, Debug)]
pub struct TestLayer {
    pub name: CString,
    pub channels: u32,
    pub data: Vec<f32>,
}

/// A film a test owns, to be lent to an exporter as a [`FilmView`]. Empty arrays are
/// lent as null pointers, as a host without that buffer would.
#[derive(Clone, Debug, Default)]
pub struct TestFilm {
    pub width: u32,
    pub height: u32,
    /// Linear RGBA, 4 floats per pixel.
    pub radiance: Vec<f32>,
    /// Tonemapped RGBA in [0, 1].
    pub display: Vec<f32>,
    pub layers: Vec<TestLayer>,
}

impl TestFilm {
    /// Calls `f` with a view of the film, valid for that call.
    pub fn with_view<T>(&self, f: impl FnOnce(&FilmView) -> T) -> T {
        let layers: Vec<LayerView> = self
            .layers
            .iter()
            .map(|l| LayerView {
                name: l.name.as_ptr(),
                channels: l.channels,
                data: ptr_or_null(&l.data),
            })
            .collect();
        f(&FilmView {
            width: self.width,
            height: self.height,
            radiance: ptr_or_null(&self.radiance),
            display: ptr_or_null(&self.display),
            layer_count: layers.len() as u32,
            layers: layers.as_ptr(),
        })
    }

    /// Exports the film to `path` with `options` through the exporter `descriptor`
    /// describes: [`export_view`] of this film.
    pub fn export(
        &self,
        descriptor: &PluginDescriptor,
        path: &Path,
        options: &str,
    ) -> Result<(), String> {
        self.with_view(|view| export_view(descriptor, path, view, options))
    }
}

/// Exports `view` to `path` with `options` through the exporter `descriptor` describes
/// (after checking its ABI version): the error message the plugin wrote, if it failed.
pub fn export_view(
    descriptor: &PluginDescriptor,
    path: &Path,
    view: &FilmView,
    options: &str,
) -> Result<(), String> {
    assert_eq!(
        descriptor.abi_version, ABI_VERSION,
        "the plugin's ABI version"
    );
    let export = descriptor
        .export
        .expect("an exporter has an export function");
    let path = CString::new(path.to_string_lossy().as_bytes()).expect("no NUL in a path");
    let options = CString::new(options).expect("no NUL in options");
    let mut message = vec![0 as c_char; 4096];
    let mut error = ErrorBuffer {
        data: message.as_mut_ptr(),
        capacity: message.len(),
    };
    let status = unsafe { export(path.as_ptr(), view, options.as_ptr(), &mut error) };
    if status == STATUS_OK {
        Ok(())
    } else {
        Err(text(message.as_ptr()))
    }
}
