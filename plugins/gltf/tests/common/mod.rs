//! A mock host: drives the importer through its C ABI (the exported descriptor), records
//! what it adds, and checks it as strictly as Kiln's host does — material graphs are
//! parsed and compiled by `kiln::material`, meshes must be whole and in range.

#![allow(dead_code)] // each test file uses a different part

use std::ffi::{CStr, CString, c_char, c_void};
use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use kiln_plugin_api as api;

/// Finding resources outside the repository (fails under CI when one is missing): the
/// workspace's own test helper, shared by path rather than copied.
#[path = "../../../../tests/common/resource.rs"]
pub mod resource;

#[derive(Clone, Debug, Default)]
pub struct RecordedMesh {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
    pub colors: Option<Vec<[f32; 4]>>,
    pub indices: Vec<u32>,
}

#[derive(Clone, Debug)]
pub struct RecordedLight {
    pub kind: u32,
    pub position: [f32; 3],
    pub direction: [f32; 3],
    pub intensity: [f32; 3],
    pub cone_angle_degrees: f32,
    pub blend: f32,
}

#[derive(Clone, Debug, Default)]
pub struct Recorded {
    pub meshes: Vec<RecordedMesh>,
    /// (name, .kmat text)
    pub materials: Vec<(String, String)>,
    pub images: Vec<(String, Vec<u8>)>,
    /// (mesh, material, column-major transform)
    pub instances: Vec<(u32, u32, [f32; 16])>,
    /// (to_world, fov_y_degrees) of every set_camera call.
    pub cameras: Vec<([f32; 16], f32)>,
    pub lights: Vec<RecordedLight>,
    pub warnings: Vec<String>,
    /// Data the host would have refused: the importer should never send it.
    pub violations: Vec<String>,
}

impl Recorded {
    pub fn material(&self, id: u32) -> &str {
        &self.materials[id as usize].1
    }
}

fn state<'a>(ctx: *mut c_void) -> &'a mut Recorded {
    unsafe { &mut *ctx.cast::<Recorded>() }
}

fn text(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

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

unsafe extern "C" fn add_mesh(ctx: *mut c_void, m: *const api::MeshData) -> u32 {
    let s = state(ctx);
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

/// Parses and compiles `kmat` as Kiln's host does; the error if it does not compile.
pub fn compile_kmat(name: &str, kmat: &str) -> Result<(), String> {
    let (_, graph) =
        kiln::material::parse_material(kmat, "test.gltf").map_err(|e| format!("{e}\n{kmat}"))?;
    kiln::material::compile(name, &graph, "material").map_err(|e| format!("{e}\n{kmat}"))?;
    Ok(())
}

unsafe extern "C" fn add_material(
    ctx: *mut c_void,
    name: *const c_char,
    kmat: *const c_char,
) -> u32 {
    let s = state(ctx);
    let (name, kmat) = (text(name), text(kmat));
    if let Err(e) = compile_kmat(&name, &kmat) {
        s.violations.push(format!("material {name}: {e}"));
        return u32::MAX;
    }
    s.materials.push((name, kmat));
    (s.materials.len() - 1) as u32
}

unsafe extern "C" fn add_image(
    ctx: *mut c_void,
    name: *const c_char,
    bytes: *const u8,
    len: usize,
) -> u32 {
    let s = state(ctx);
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
    let s = state(ctx);
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

unsafe extern "C" fn set_camera(ctx: *mut c_void, c: *const api::CameraData) {
    let c = unsafe { &*c };
    state(ctx).cameras.push((c.to_world, c.fov_y_degrees));
}

unsafe extern "C" fn add_light(ctx: *mut c_void, l: *const api::LightData) -> u32 {
    let s = state(ctx);
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
    s.lights.push(RecordedLight {
        kind: l.kind,
        position: l.position,
        direction: l.direction,
        intensity: l.intensity,
        cone_angle_degrees: l.cone_angle_degrees,
        blend: l.blend,
    });
    (s.lights.len() - 1) as u32
}

unsafe extern "C" fn warn(ctx: *mut c_void, message: *const c_char) {
    state(ctx).warnings.push(text(message));
}

/// Imports `path` through the plugin's exported C entry point.
pub fn import(path: &Path) -> (Result<(), String>, Recorded) {
    let descriptor = unsafe { &*kiln_gltf::kiln_plugin_descriptor() };
    assert_eq!(descriptor.abi_version, api::ABI_VERSION);
    let import = descriptor.import.expect("an importer");
    let mut recorded = Recorded::default();
    let builder = api::SceneBuilder {
        ctx: (&mut recorded as *mut Recorded).cast(),
        add_mesh,
        add_material,
        add_image,
        add_instance,
        set_camera,
        add_light,
        warn,
    };
    let c_path = CString::new(path.to_string_lossy().as_bytes()).expect("no NUL in test paths");
    let mut message = vec![0 as c_char; 4096];
    let mut error = api::ErrorBuffer {
        data: message.as_mut_ptr(),
        capacity: message.len(),
    };
    let status = unsafe { import(c_path.as_ptr(), &builder, &mut error) };
    // The plugin API installs a hook that silences panics (they come back as errors);
    // in this process it would also silence the tests' own assertion messages.
    drop(std::panic::take_hook());
    let result = if status == api::STATUS_OK {
        Ok(())
    } else {
        Err(text(message.as_ptr()))
    };
    (result, recorded)
}

/// [`import`] on another thread, with the time it took; an error saying whether it did not
/// finish within `limit` or the thread panicked.
pub fn import_with_timeout(
    path: &Path,
    limit: Duration,
) -> Result<(Result<(), String>, Recorded, Duration), String> {
    let (tx, rx) = mpsc::channel();
    let path = path.to_owned();
    std::thread::spawn(move || {
        let start = Instant::now();
        let (result, recorded) = import(&path);
        let _ = tx.send((result, recorded, start.elapsed()));
    });
    rx.recv_timeout(limit).map_err(|e| match e {
        mpsc::RecvTimeoutError::Timeout => format!("no result within {limit:?}"),
        mpsc::RecvTimeoutError::Disconnected => "the importing thread panicked".to_owned(),
    })
}

/// A scratch folder of its own for files a test writes, removed when dropped.
pub fn scratch_dir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("kiln-gltf-test-")
        .tempdir()
        .expect("temp dir")
}
