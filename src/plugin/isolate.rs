//! Importers out of process (`--isolate-importers`, and always in the editor): the same
//! binary in its `import-worker` mode runs the importer and sends the calls it made to
//! the host's scene builder over its standard output; the host replays them into a
//! builder of its own, so the scene it gets is the one an import in process would give.
//! A plugin that crashes, aborts or hangs takes down the worker alone: the import fails
//! with a message naming the signal or the time limit, and Kiln keeps running.
//!
//! The stream: [`MAGIC`], then records (a tag byte, little-endian fields) of the calls the
//! worker's builder accepted, the warnings of those it refused (a refused call takes no
//! id, so the ids stay the ones the plugin saw), and last the plugin's status and message.

use std::ffi::{CStr, CString, c_char, c_void};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use kiln_plugin_api as api;

use super::builder::{self, ImportState, Imported};

/// How to run importers out of process.
#[derive(Clone, Debug)]
pub struct Isolation {
    /// The Kiln executable, run as `EXE [--plugin-dir DIR]… import-worker FILE`.
    pub exe: PathBuf,
    /// The `--plugin-dir` folders the worker is given, so that it loads the same plugins.
    pub plugin_dirs: Vec<PathBuf>,
    /// How long an import may take before the worker is stopped.
    pub timeout: Duration,
}

const MAGIC: &[u8; 8] = b"KILNIMP1";

const MESH: u8 = 1;
const MATERIAL: u8 = 2;
const IMAGE: u8 = 3;
const INSTANCE: u8 = 4;
const CAMERA: u8 = 5;
const LIGHT: u8 = 6;
const WARN: u8 = 7;
const END: u8 = 8;

/// The worker's builder: each call goes to a real [`ImportState`] (which decides the id
/// the plugin gets back) and is recorded when accepted.
pub(super) struct Recorder {
    state: ImportState,
    bytes: Vec<u8>,
}

/// Raw bytes of a C string, None for null.
unsafe fn c_bytes<'a>(p: *const c_char) -> Option<&'a [u8]> {
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_bytes())
}

impl Recorder {
    pub(super) fn new(file: &Path) -> Self {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(MAGIC);
        Self {
            state: ImportState::new(file),
            bytes,
        }
    }

    pub(super) fn raw_builder(&mut self) -> api::SceneBuilder {
        api::SceneBuilder {
            ctx: (self as *mut Self).cast(),
            add_mesh: record_mesh,
            add_material: record_material,
            add_image: record_image,
            add_instance: record_instance,
            set_camera: record_camera,
            add_light: record_light,
            warn: record_warn,
        }
    }

    /// The stream, ended by the plugin's outcome.
    pub(super) fn finish(mut self, outcome: Result<(), String>) -> Vec<u8> {
        self.bytes.push(END);
        let (ok, message) = match outcome {
            Ok(()) => (1u8, String::new()),
            Err(m) => (0, m),
        };
        self.bytes.push(ok);
        put_bytes(&mut self.bytes, message.as_bytes());
        self.bytes
    }

    /// Runs one call on the state; records it with `record` when it was accepted (an id
    /// other than `u32::MAX`), else the warnings it left.
    fn call(
        &mut self,
        id: impl FnOnce(*mut c_void) -> u32,
        record: impl FnOnce(&mut Vec<u8>),
    ) -> u32 {
        let warnings = self.state.warnings.len();
        let id = id((&mut self.state as *mut ImportState).cast());
        if id == u32::MAX {
            for w in &self.state.warnings[warnings..] {
                self.bytes.push(WARN);
                put_bytes(&mut self.bytes, w.as_bytes());
            }
        } else {
            record(&mut self.bytes);
        }
        id
    }
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_f32s(out: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn put_bytes(out: &mut Vec<u8>, bytes: &[u8]) {
    put_u64(out, bytes.len() as u64);
    out.extend_from_slice(bytes);
}

fn put_optional(out: &mut Vec<u8>, bytes: Option<&[u8]>) {
    out.push(bytes.is_some() as u8);
    if let Some(b) = bytes {
        put_bytes(out, b);
    }
}

/// `count × n` floats from `p`, or nothing for null.
fn put_array(out: &mut Vec<u8>, p: *const f32, count: usize, n: usize) {
    out.push(!p.is_null() as u8);
    if !p.is_null() {
        put_f32s(out, unsafe { std::slice::from_raw_parts(p, count * n) });
    }
}

fn recorder<'a>(ctx: *mut c_void) -> &'a mut Recorder {
    unsafe { &mut *ctx.cast::<Recorder>() }
}

// The recorded calls are the ones the state accepted: their pointers and counts were
// checked there before anything is read here.

unsafe extern "C" fn record_mesh(ctx: *mut c_void, mesh: *const api::MeshData) -> u32 {
    recorder(ctx).call(
        |state| unsafe { builder::add_mesh(state, mesh) },
        |out| {
            let m = unsafe { &*mesh };
            out.push(MESH);
            put_optional(out, unsafe { c_bytes(m.name) });
            put_u64(out, m.vertex_count as u64);
            put_u64(out, m.index_count as u64);
            let n = m.vertex_count;
            for (p, width) in [
                (m.positions, 3),
                (m.normals, 3),
                (m.uvs, 2),
                (m.uvs1, 2),
                (m.tangents, 4),
                (m.colors, 4),
            ] {
                put_array(out, p, n, width);
            }
            out.push(!m.indices.is_null() as u8);
            if !m.indices.is_null() {
                for i in unsafe { std::slice::from_raw_parts(m.indices, m.index_count) } {
                    put_u32(out, *i);
                }
            }
        },
    )
}

unsafe extern "C" fn record_material(
    ctx: *mut c_void,
    name: *const c_char,
    kmat: *const c_char,
) -> u32 {
    recorder(ctx).call(
        |state| unsafe { builder::add_material(state, name, kmat) },
        |out| {
            out.push(MATERIAL);
            put_optional(out, unsafe { c_bytes(name) });
            put_optional(out, unsafe { c_bytes(kmat) });
        },
    )
}

unsafe extern "C" fn record_image(
    ctx: *mut c_void,
    name: *const c_char,
    bytes: *const u8,
    len: usize,
) -> u32 {
    recorder(ctx).call(
        |state| unsafe { builder::add_image(state, name, bytes, len) },
        |out| {
            out.push(IMAGE);
            put_optional(out, unsafe { c_bytes(name) });
            put_bytes(out, unsafe { std::slice::from_raw_parts(bytes, len) });
        },
    )
}

unsafe extern "C" fn record_instance(
    ctx: *mut c_void,
    mesh: u32,
    material: u32,
    to_world: *const [f32; 16],
) -> u32 {
    recorder(ctx).call(
        |state| unsafe { builder::add_instance(state, mesh, material, to_world) },
        |out| {
            out.push(INSTANCE);
            put_u32(out, mesh);
            put_u32(out, material);
            put_f32s(out, unsafe { &*to_world });
        },
    )
}

unsafe extern "C" fn record_camera(ctx: *mut c_void, camera: *const api::CameraData) {
    let r = recorder(ctx);
    unsafe { builder::set_camera((&mut r.state as *mut ImportState).cast(), camera) };
    if !camera.is_null() {
        let c = unsafe { &*camera };
        r.bytes.push(CAMERA);
        put_f32s(&mut r.bytes, &c.to_world);
        put_f32s(
            &mut r.bytes,
            &[c.fov_y_degrees, c.aperture_radius, c.focus_distance],
        );
    }
}

unsafe extern "C" fn record_light(ctx: *mut c_void, light: *const api::LightData) -> u32 {
    recorder(ctx).call(
        |state| unsafe { builder::add_light(state, light) },
        |out| {
            let l = unsafe { &*light };
            out.push(LIGHT);
            put_u32(out, l.kind);
            put_f32s(out, &l.position);
            put_f32s(out, &l.direction);
            put_f32s(out, &l.intensity);
            put_f32s(out, &[l.cone_angle_degrees, l.blend, l.radius]);
        },
    )
}

unsafe extern "C" fn record_warn(ctx: *mut c_void, message: *const c_char) {
    let r = recorder(ctx);
    unsafe { builder::warn((&mut r.state as *mut ImportState).cast(), message) };
    if let Some(m) = unsafe { c_bytes(message) } {
        r.bytes.push(WARN);
        put_bytes(&mut r.bytes, m);
    }
}

/// Reads a worker's stream; every read is checked against its end.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.bytes.len() {
            return Err("the stream ends early".into());
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }

    fn u64(&mut self) -> Result<usize, String> {
        let v = u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"));
        usize::try_from(v).map_err(|_| "a length out of range".to_owned())
    }

    fn f32s(&mut self, count: usize) -> Result<Vec<f32>, String> {
        let bytes = self.take(count.checked_mul(4).ok_or("a length out of range")?)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes")))
            .collect())
    }

    fn array<const N: usize>(&mut self) -> Result<[f32; N], String> {
        Ok(self.f32s(N)?.try_into().expect("N floats"))
    }

    fn bytes(&mut self) -> Result<&'a [u8], String> {
        let n = self.u64()?;
        self.take(n)
    }

    /// A C string as it was given (its bytes hold no NUL).
    fn c_string(&mut self) -> Result<CString, String> {
        CString::new(self.bytes()?).map_err(|_| "a string with a NUL".to_owned())
    }

    fn optional_c_string(&mut self) -> Result<Option<CString>, String> {
        match self.u8()? {
            0 => Ok(None),
            _ => self.c_string().map(Some),
        }
    }

    fn optional_f32s(&mut self, count: usize) -> Result<Option<Vec<f32>>, String> {
        match self.u8()? {
            0 => Ok(None),
            _ => self.f32s(count).map(Some),
        }
    }
}

fn pointer<T>(v: &Option<Vec<T>>) -> *const T {
    v.as_ref().map_or(std::ptr::null(), |v| v.as_ptr())
}

fn c_pointer(s: &Option<CString>) -> *const c_char {
    s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr())
}

/// Replays a worker's stream into a new builder for `file`: the import, or the plugin's
/// own error message.
fn replay(file: &Path, stream: &[u8]) -> Result<Result<Imported, String>, String> {
    let mut r = Reader { bytes: stream };
    if r.take(MAGIC.len())? != MAGIC {
        return Err("the stream does not start as a worker's".into());
    }
    let mut state = ImportState::new(file);
    let b = state.raw_builder();
    loop {
        match r.u8()? {
            MESH => {
                let name = r.optional_c_string()?;
                let (n, index_count) = (r.u64()?, r.u64()?);
                let positions = r.optional_f32s(n.saturating_mul(3))?;
                let normals = r.optional_f32s(n.saturating_mul(3))?;
                let uvs = r.optional_f32s(n.saturating_mul(2))?;
                let uvs1 = r.optional_f32s(n.saturating_mul(2))?;
                let tangents = r.optional_f32s(n.saturating_mul(4))?;
                let colors = r.optional_f32s(n.saturating_mul(4))?;
                let indices = match r.u8()? {
                    0 => None,
                    _ => Some(
                        (0..index_count)
                            .map(|_| r.u32())
                            .collect::<Result<Vec<_>, _>>()?,
                    ),
                };
                let mesh = api::MeshData {
                    name: c_pointer(&name),
                    vertex_count: n,
                    positions: pointer(&positions),
                    normals: pointer(&normals),
                    uvs: pointer(&uvs),
                    uvs1: pointer(&uvs1),
                    tangents: pointer(&tangents),
                    colors: pointer(&colors),
                    indices: pointer(&indices),
                    index_count,
                };
                unsafe { (b.add_mesh)(b.ctx, &mesh) };
            }
            MATERIAL => {
                let (name, kmat) = (r.optional_c_string()?, r.optional_c_string()?);
                unsafe { (b.add_material)(b.ctx, c_pointer(&name), c_pointer(&kmat)) };
            }
            IMAGE => {
                let name = r.optional_c_string()?;
                let data = r.bytes()?;
                unsafe { (b.add_image)(b.ctx, c_pointer(&name), data.as_ptr(), data.len()) };
            }
            INSTANCE => {
                let (mesh, material) = (r.u32()?, r.u32()?);
                let to_world = r.array::<16>()?;
                unsafe { (b.add_instance)(b.ctx, mesh, material, &to_world) };
            }
            CAMERA => {
                let to_world = r.array::<16>()?;
                let [fov_y_degrees, aperture_radius, focus_distance] = r.array::<3>()?;
                let camera = api::CameraData {
                    to_world,
                    fov_y_degrees,
                    aperture_radius,
                    focus_distance,
                };
                unsafe { (b.set_camera)(b.ctx, &camera) };
            }
            LIGHT => {
                let kind = r.u32()?;
                let (position, direction, intensity) = (r.array()?, r.array()?, r.array()?);
                let [cone_angle_degrees, blend, radius] = r.array::<3>()?;
                let light = api::LightData {
                    kind,
                    position,
                    direction,
                    intensity,
                    cone_angle_degrees,
                    blend,
                    radius,
                };
                unsafe { (b.add_light)(b.ctx, &light) };
            }
            WARN => {
                let message = r.c_string()?;
                unsafe { (b.warn)(b.ctx, message.as_ptr()) };
            }
            END => {
                let ok = r.u8()? == 1;
                let message = String::from_utf8_lossy(r.bytes()?).into_owned();
                return Ok(if ok { Ok(state.finish()) } else { Err(message) });
            }
            tag => return Err(format!("an unknown record {tag}")),
        }
    }
}

/// The name of a signal that ends a crashed worker.
fn signal_name(signal: i32) -> &'static str {
    match signal {
        4 => "SIGILL",
        6 => "SIGABRT",
        7 => "SIGBUS",
        8 => "SIGFPE",
        9 => "SIGKILL",
        11 => "SIGSEGV",
        _ => "a signal",
    }
}

/// The last lines of a worker's standard error, to quote in an error.
fn tail(stderr: &[u8]) -> String {
    let text = String::from_utf8_lossy(stderr);
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(3)..].join(" / ")
}

/// Runs `file`'s import in a worker process: the import, or why not (the plugin's own
/// error, or how the worker ended).
pub(super) fn import(
    isolation: &Isolation,
    file: &Path,
) -> Result<Result<Imported, String>, String> {
    let mut command = Command::new(&isolation.exe);
    for dir in &isolation.plugin_dirs {
        command.arg("--plugin-dir").arg(dir);
    }
    // The worker's importer refuses counts past the same limit.
    let limits = crate::limits::current();
    command
        .arg("--max-triangles")
        .arg(limits.triangles.to_string());
    let mut child = command
        .arg("import-worker")
        .arg(file)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            format!(
                "cannot start the import worker {}: {e}",
                isolation.exe.display()
            )
        })?;
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            bytes
        })
    };
    let stdout = drain(Box::new(child.stdout.take().expect("piped")));
    let stderr = drain(Box::new(child.stderr.take().expect("piped")));
    let deadline = Instant::now() + isolation.timeout;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "it did not finish within {} s and was stopped (--import-timeout)",
                    isolation.timeout.as_secs_f64()
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(e) => return Err(format!("cannot wait for the import worker: {e}")),
        }
    };
    let stream = stdout.join().unwrap_or_default();
    let stderr = stderr.join().unwrap_or_default();
    if !status.success() {
        #[cfg(unix)]
        if let Some(signal) = std::os::unix::process::ExitStatusExt::signal(&status) {
            return Err(format!(
                "it crashed ({}, signal {signal}) in its own process; Kiln is unaffected",
                signal_name(signal)
            ));
        }
        return Err(format!(
            "the import worker failed ({status}): {}",
            tail(&stderr)
        ));
    }
    replay(file, &stream).map_err(|e| format!("the import worker's answer is broken: {e}"))
}
