//! The host side of `SceneBuilder`: callbacks that check everything an importer hands
//! over (null pointers, counts, indices out of range, non-finite numbers, memory budgets)
//! and build a [`Scene`]. A callback never unwinds into the plugin: panics are caught and
//! become warnings.

use std::ffi::{CStr, c_char, c_void};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4Swizzles};
use kiln_plugin_api as api;

use crate::material::texture::{decode_texture, load_texture};
use crate::scene::{Camera, Light, Material, Mesh, Scene, lookdev};

// Vertices and triangles one import may hand over, in total
// ([`crate::limits::Limits::triangles`]): malformed files that claim billions of elements
// are refused before they exhaust memory.
/// Bytes of embedded images one import may hand over.
pub const MAX_IMAGE_BYTES: usize = 1 << 30;

/// What an import produced.
pub struct Imported {
    pub scene: Scene,
    /// Whether the file had a camera (otherwise `scene` has one framing it).
    pub has_camera: bool,
    /// Whether the file had lights or emissive materials (otherwise `scene` has a white
    /// sky).
    pub has_lights: bool,
    /// Things the file holds that Kiln could not use, and data it refused.
    pub warnings: Vec<String>,
    /// Images embedded in the file (`image:N` in material graphs), encoded.
    pub images: Vec<(String, Arc<Vec<u8>>)>,
}

pub(super) struct ImportState {
    file: PathBuf,
    scene: Scene,
    has_camera: bool,
    pub(super) warnings: Vec<String>,
    images: Vec<(String, Arc<Vec<u8>>)>,
    image_bytes: usize,
    vertices: usize,
    triangles: usize,
    default_material: Option<usize>,
}

unsafe fn text(p: *const c_char) -> Option<String> {
    if p.is_null() {
        return None;
    }
    Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

/// `count` items of `n` floats from `p`, or None for null.
unsafe fn floats<'a>(p: *const f32, count: usize, n: usize) -> Option<&'a [f32]> {
    if p.is_null() {
        return None;
    }
    Some(unsafe { std::slice::from_raw_parts(p, count * n) })
}

/// Runs a callback body, turning a panic into a warning and `fallback`.
fn guard<T>(ctx: *mut c_void, fallback: T, f: impl FnOnce(&mut ImportState) -> T) -> T {
    if ctx.is_null() {
        return fallback;
    }
    let state = unsafe { &mut *ctx.cast::<ImportState>() };
    let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| f(&mut *state)));
    match outcome {
        Ok(v) => v,
        Err(payload) => {
            state.warnings.push(format!(
                "internal error while taking data from the plugin: {}",
                api::panic_message(payload)
            ));
            fallback
        }
    }
}

impl ImportState {
    pub(super) fn new(file: &Path) -> Self {
        Self {
            file: file.to_owned(),
            scene: Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0)),
            has_camera: false,
            warnings: Vec::new(),
            images: Vec::new(),
            image_bytes: 0,
            vertices: 0,
            triangles: 0,
            default_material: None,
        }
    }

    pub(super) fn raw_builder(&mut self) -> api::SceneBuilder {
        api::SceneBuilder {
            ctx: (self as *mut Self).cast(),
            add_mesh,
            add_material,
            add_image,
            add_instance,
            set_camera,
            add_light,
            warn,
        }
    }

    fn refuse(&mut self, message: String) -> u32 {
        self.warnings.push(message);
        u32::MAX
    }

    fn mesh(&mut self, m: &api::MeshData) -> u32 {
        let name =
            unsafe { text(m.name) }.unwrap_or_else(|| format!("mesh {}", self.scene.meshes.len()));
        let (n, index_count) = (m.vertex_count, m.index_count);
        if m.positions.is_null() || (index_count > 0 && m.indices.is_null()) {
            return self.refuse(format!("mesh \"{name}\": no positions or indices"));
        }
        if index_count % 3 != 0 {
            return self.refuse(format!(
                "mesh \"{name}\": {index_count} indices is not a whole number of triangles"
            ));
        }
        let limit = usize::try_from(crate::limits::current().triangles).unwrap_or(usize::MAX);
        if self.vertices.saturating_add(n) > limit
            || self.triangles.saturating_add(index_count / 3) > limit
        {
            return self.refuse(format!(
                "mesh \"{name}\": the import would exceed {limit} vertices or {limit} triangles \
                 (--max-triangles raises the limit)"
            ));
        }
        let positions = unsafe { floats(m.positions, n, 3) }.expect("checked above");
        if positions.iter().any(|v| !v.is_finite()) {
            return self.refuse(format!("mesh \"{name}\": non-finite vertex positions"));
        }
        let indices = if index_count == 0 {
            &[][..]
        } else {
            unsafe { std::slice::from_raw_parts(m.indices, index_count) }
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return self.refuse(format!(
                "mesh \"{name}\": index {bad} is out of range for {n} vertices"
            ));
        }
        let mut mesh = Mesh {
            name: name.clone(),
            positions: positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            indices: indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            ..Mesh::default()
        };
        if let Some(normals) = unsafe { floats(m.normals, n, 3) } {
            let normals: Vec<Vec3> = normals
                .chunks_exact(3)
                .map(|v| Vec3::new(v[0], v[1], v[2]))
                .collect();
            if normals
                .iter()
                .all(|v| v.is_finite() && v.length_squared() > 0.0)
            {
                mesh.normals = normals.iter().map(|v| v.normalize()).collect();
            } else {
                self.warnings.push(format!(
                    "mesh \"{name}\": invalid normals dropped (rendered faceted)"
                ));
            }
        }
        mesh.uvs = self.uv_set(m.uvs, n, &name, "UVs");
        mesh.uvs1 = self.uv_set(m.uvs1, n, &name, "second-set UVs");
        if let Some(colors) = unsafe { floats(m.colors, n, 4) } {
            if colors.iter().all(|v| v.is_finite()) {
                mesh.colors = colors
                    .chunks_exact(4)
                    .map(|c| glam::Vec4::new(c[0], c[1], c[2], c[3]))
                    .collect();
            } else {
                self.warnings.push(format!(
                    "mesh \"{name}\": non-finite vertex colours dropped"
                ));
            }
        }
        self.vertices += n;
        self.triangles += mesh.indices.len();
        self.scene.meshes.push(mesh);
        (self.scene.meshes.len() - 1) as u32
    }

    /// `n` UVs from `p`, or none (with a warning when they are not finite).
    fn uv_set(&mut self, p: *const f32, n: usize, mesh: &str, what: &str) -> Vec<Vec2> {
        let Some(uvs) = (unsafe { floats(p, n, 2) }) else {
            return Vec::new();
        };
        if uvs.iter().all(|v| v.is_finite()) {
            uvs.chunks_exact(2).map(|v| Vec2::new(v[0], v[1])).collect()
        } else {
            self.warnings
                .push(format!("mesh \"{mesh}\": non-finite {what} dropped"));
            Vec::new()
        }
    }

    fn material(&mut self, name: Option<String>, kmat: Option<String>) -> u32 {
        let name = name.unwrap_or_else(|| format!("material {}", self.scene.materials.len()));
        let Some(kmat) = kmat else {
            return self.refuse(format!("material \"{name}\": no graph"));
        };
        let graph = match crate::material::parse_material(&kmat, &self.file.display().to_string()) {
            Ok((_, g)) => g,
            Err(e) => return self.refuse(format!("material \"{name}\": {e}")),
        };
        let images = &self.images;
        let load = |file: &str| match file.strip_prefix("image:") {
            Some(n) => {
                let (image_name, bytes) = n
                    .parse::<usize>()
                    .ok()
                    .and_then(|i| images.get(i))
                    .ok_or_else(|| format!("no embedded image {file}"))?;
                decode_texture(bytes, image_name)
            }
            None => load_texture(Path::new(file)),
        };
        match Material::from_graph_with(&name, graph, &load) {
            Ok(m) => {
                self.scene.materials.push(m);
                (self.scene.materials.len() - 1) as u32
            }
            Err(e) => self.refuse(e.to_string()),
        }
    }

    fn instance(&mut self, mesh: u32, material: u32, m: &[f32; 16]) -> u32 {
        if mesh as usize >= self.scene.meshes.len() {
            return self.refuse(format!("instance of mesh {mesh}, which does not exist"));
        }
        if m.iter().any(|v| !v.is_finite()) {
            return self.refuse(format!("instance of mesh {mesh}: non-finite transform"));
        }
        let material = if (material as usize) < self.scene.materials.len() {
            material as usize
        } else {
            if material != u32::MAX {
                self.warnings.push(format!(
                    "instance of mesh {mesh}: material {material} does not exist; grey used"
                ));
            }
            *self
                .default_material
                .get_or_insert(self.scene.materials.len())
        };
        if material == self.scene.materials.len() {
            self.scene.materials.push(Material {
                name: "default".into(),
                ..Material::default()
            });
        }
        let transform = Affine3A::from_mat4(Mat4::from_cols_array(m));
        self.scene.add_instance(mesh as usize, material, transform);
        (self.scene.instances.len() - 1) as u32
    }

    fn camera(&mut self, c: &api::CameraData) {
        let m = Mat4::from_cols_array(&c.to_world);
        if !(m.is_finite() && c.fov_y_degrees > 0.0 && c.fov_y_degrees < 180.0) {
            self.warnings
                .push("camera with a non-finite transform or field of view ignored".into());
            return;
        }
        let position = m.w_axis.xyz();
        let forward = -m.z_axis.xyz();
        if forward.length_squared() == 0.0 {
            self.warnings
                .push("camera with a degenerate orientation ignored".into());
            return;
        }
        self.scene.camera = Camera {
            position,
            look_at: position + forward.normalize(),
            up: m.y_axis.xyz().normalize_or(Vec3::Y),
            fov_y_degrees: c.fov_y_degrees,
            aperture_radius: c.aperture_radius.max(0.0),
            focus_distance: c.focus_distance.max(0.0),
        };
        self.has_camera = true;
    }

    fn light(&mut self, l: &api::LightData) -> u32 {
        let v = |a: [f32; 3]| Vec3::from_array(a);
        let light = match l.kind {
            api::LIGHT_POINT => Light::Point {
                position: v(l.position),
                intensity: v(l.intensity),
                radius: l.radius.max(0.0),
            },
            api::LIGHT_SPOT => Light::Spot {
                position: v(l.position),
                direction: v(l.direction),
                intensity: v(l.intensity),
                cone_angle: l.cone_angle_degrees,
                blend: l.blend.clamp(0.0, 1.0),
                radius: l.radius.max(0.0),
            },
            api::LIGHT_DISTANT => Light::Distant {
                direction: v(l.direction),
                irradiance: v(l.intensity),
                angular_diameter: 0.0,
            },
            k => return self.refuse(format!("light of unknown kind {k}")),
        };
        if let Err(e) = light.validate() {
            return self.refuse(format!("light refused: {e}"));
        }
        self.scene.add_light(light);
        (self.scene.lights.len() - 1) as u32
    }

    /// The import, made renderable: a file without a camera gets the look-dev default's
    /// three-quarter view that frames it, and one without lights its sky with a sun
    /// ([`lookdev`]; the ground is the caller's choice, [`lookdev::add_ground`]).
    pub(super) fn finish(mut self) -> Imported {
        let has_lights = !self.scene.lights.is_empty()
            || self
                .scene
                .instances
                .iter()
                .any(|i| self.scene.materials[i.material].is_emissive());
        if !self.has_camera {
            self.scene.camera = lookdev::camera(&self.scene);
        }
        if !has_lights && self.scene.environment == Vec3::ZERO {
            self.scene.world = Some(lookdev::world());
            self.scene.settings.view.exposure_ev = lookdev::EXPOSURE_EV;
        }
        Imported {
            scene: self.scene,
            has_camera: self.has_camera,
            has_lights,
            warnings: self.warnings,
            images: self.images,
        }
    }
}

pub(super) unsafe extern "C" fn add_mesh(ctx: *mut c_void, mesh: *const api::MeshData) -> u32 {
    guard(ctx, u32::MAX, |s| {
        if mesh.is_null() {
            return s.refuse("null mesh".into());
        }
        s.mesh(unsafe { &*mesh })
    })
}

pub(super) unsafe extern "C" fn add_material(
    ctx: *mut c_void,
    name: *const c_char,
    kmat: *const c_char,
) -> u32 {
    guard(ctx, u32::MAX, |s| {
        let (name, kmat) = unsafe { (text(name), text(kmat)) };
        s.material(name, kmat)
    })
}

pub(super) unsafe extern "C" fn add_image(
    ctx: *mut c_void,
    name: *const c_char,
    bytes: *const u8,
    len: usize,
) -> u32 {
    guard(ctx, u32::MAX, |s| {
        let name = unsafe { text(name) }.unwrap_or_else(|| format!("image {}", s.images.len()));
        if bytes.is_null() || len == 0 {
            return s.refuse(format!("image \"{name}\": no data"));
        }
        if s.image_bytes.saturating_add(len) > MAX_IMAGE_BYTES {
            return s.refuse(format!(
                "image \"{name}\": embedded images exceed {MAX_IMAGE_BYTES} bytes"
            ));
        }
        s.image_bytes += len;
        let data = unsafe { std::slice::from_raw_parts(bytes, len) }.to_vec();
        s.images.push((name, Arc::new(data)));
        (s.images.len() - 1) as u32
    })
}

pub(super) unsafe extern "C" fn add_instance(
    ctx: *mut c_void,
    mesh: u32,
    material: u32,
    to_world: *const [f32; 16],
) -> u32 {
    guard(ctx, u32::MAX, |s| {
        if to_world.is_null() {
            return s.refuse("instance without a transform".into());
        }
        s.instance(mesh, material, unsafe { &*to_world })
    })
}

pub(super) unsafe extern "C" fn set_camera(ctx: *mut c_void, camera: *const api::CameraData) {
    guard(ctx, (), |s| {
        if !camera.is_null() {
            s.camera(unsafe { &*camera });
        }
    })
}

pub(super) unsafe extern "C" fn add_light(ctx: *mut c_void, light: *const api::LightData) -> u32 {
    guard(ctx, u32::MAX, |s| {
        if light.is_null() {
            return s.refuse("null light".into());
        }
        s.light(unsafe { &*light })
    })
}

pub(super) unsafe extern "C" fn warn(ctx: *mut c_void, message: *const c_char) {
    guard(ctx, (), |s| {
        if let Some(m) = unsafe { text(message) } {
            s.warnings.push(m);
        }
    })
}
