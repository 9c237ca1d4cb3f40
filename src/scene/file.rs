//! The `.kiln` scene file: a versioned, human-editable description of a [`Scene`].
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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Mat4, Vec2, Vec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{Camera, EnvironmentMap, Light, Material, Mesh, Scene, SceneSettings, shapes};

/// The version this build reads and writes. Older versions are upgraded on load where
/// possible; newer ones are refused with a message saying so.
pub const SCENE_FORMAT_VERSION: u32 = 1;

#[derive(Debug, Error)]
pub enum SceneError {
    #[error("cannot read scene file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
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
    #[error("{path}: mesh \"{mesh}\": cannot load {file}: {message}")]
    MeshFile {
        path: PathBuf,
        mesh: String,
        file: PathBuf,
        message: String,
    },
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    version: u32,
    #[serde(default)]
    render: RenderDesc,
    camera: CameraDesc,
    #[serde(default)]
    environment: [f32; 3],
    #[serde(default)]
    environment_map: Option<EnvironmentMapDesc>,
    #[serde(default)]
    materials: BTreeMap<String, MaterialDesc>,
    #[serde(default)]
    meshes: BTreeMap<String, MeshDesc>,
    #[serde(default)]
    instances: Vec<InstanceDesc>,
    #[serde(default)]
    lights: Vec<LightDesc>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentMapDesc {
    /// An equirectangular `.hdr` or `.exr`, relative to the scene file.
    file: String,
    #[serde(default = "unit_strength")]
    strength: f32,
    /// Degrees about +Y.
    #[serde(default)]
    rotation: f32,
}

fn unit_strength() -> f32 {
    1.0
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
enum LightDesc {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
        #[serde(default)]
        radius: f32,
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        cone_angle: f32,
        #[serde(default)]
        blend: f32,
        #[serde(default)]
        radius: f32,
    },
    Distant {
        direction: [f32; 3],
        irradiance: [f32; 3],
        #[serde(default)]
        angular_diameter: f32,
    },
}

impl LightDesc {
    fn to_light(&self) -> Light {
        match *self {
            LightDesc::Point {
                position,
                intensity,
                radius,
            } => Light::Point {
                position: position.into(),
                intensity: intensity.into(),
                radius,
            },
            LightDesc::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                blend,
                radius,
            } => Light::Spot {
                position: position.into(),
                direction: direction.into(),
                intensity: intensity.into(),
                cone_angle,
                blend,
                radius,
            },
            LightDesc::Distant {
                direction,
                irradiance,
                angular_diameter,
            } => Light::Distant {
                direction: direction.into(),
                irradiance: irradiance.into(),
                angular_diameter,
            },
        }
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct RenderDesc {
    width: u32,
    height: u32,
    samples_per_pixel: u32,
    max_bounces: u32,
}

impl Default for RenderDesc {
    fn default() -> Self {
        let s = SceneSettings::default();
        Self {
            width: s.width,
            height: s.height,
            samples_per_pixel: s.samples_per_pixel,
            max_bounces: s.max_bounces,
        }
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    position: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    projection: Projection,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
enum Projection {
    Perspective {
        fov_y: f32,
    },
    ThinLens {
        fov_y: f32,
        aperture_radius: f32,
        focus_distance: f32,
    },
}

/// The principled material's parameters (docs/SCENE_FORMAT.md lists them); any left out
/// take Blender's defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct MaterialDesc {
    base_color: [f32; 3],
    base_weight: f32,
    diffuse_roughness: f32,
    metallic: f32,
    roughness: f32,
    anisotropy: f32,
    anisotropy_rotation: f32,
    specular_weight: f32,
    specular_color: [f32; 3],
    ior: f32,
    transmission_weight: f32,
    transmission_color: [f32; 3],
    transmission_depth: f32,
    coat_weight: f32,
    coat_roughness: f32,
    coat_ior: f32,
    coat_color: [f32; 3],
    sheen_weight: f32,
    sheen_color: [f32; 3],
    sheen_roughness: f32,
    emission: [f32; 3],
    emission_strength: f32,
    opacity: f32,
    thin_walled: bool,
    /// A node graph (docs/NODES.md) computing the parameters instead of the fields above.
    graph: Option<crate::material::Graph>,
    /// A `.kmat` material file, relative to the scene file, instead of the fields above.
    graph_file: Option<String>,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        Self::from_params(&Material::default())
    }
}

impl MaterialDesc {
    /// The fixed parameters of `m` (its graph, if any, aside).
    fn from_params(m: &Material) -> Self {
        Self {
            base_color: m.base_color.into(),
            base_weight: m.base_weight,
            diffuse_roughness: m.diffuse_roughness,
            metallic: m.metallic,
            roughness: m.roughness,
            anisotropy: m.anisotropy,
            anisotropy_rotation: m.anisotropy_rotation,
            specular_weight: m.specular_weight,
            specular_color: m.specular_color.into(),
            ior: m.ior,
            transmission_weight: m.transmission_weight,
            transmission_color: m.transmission_color.into(),
            transmission_depth: m.transmission_depth,
            coat_weight: m.coat_weight,
            coat_roughness: m.coat_roughness,
            coat_ior: m.coat_ior,
            coat_color: m.coat_color.into(),
            sheen_weight: m.sheen_weight,
            sheen_color: m.sheen_color.into(),
            sheen_roughness: m.sheen_roughness,
            emission: m.emission.into(),
            emission_strength: 1.0,
            opacity: m.opacity,
            thin_walled: m.thin_walled,
            graph: None,
            graph_file: None,
        }
    }
}

impl MaterialDesc {
    fn to_material(&self, name: &str, base_dir: &Path) -> Result<Material, String> {
        let graph = match (&self.graph, &self.graph_file) {
            (Some(_), Some(_)) => return Err("give `graph` or `graph_file`, not both".into()),
            (Some(g), None) => {
                let mut g = g.clone();
                crate::material::resolve_files(&mut g, base_dir);
                Some(g)
            }
            (None, Some(file)) => {
                let (_, g) = crate::material::load_material(&base_dir.join(file))
                    .map_err(|e| e.to_string())?;
                Some(g)
            }
            (None, None) => None,
        };
        if let Some(graph) = graph {
            let plain = MaterialDesc {
                graph: None,
                graph_file: None,
                ..MaterialDesc::default()
            };
            let rest = MaterialDesc {
                graph: None,
                graph_file: None,
                ..self.clone()
            };
            if rest != plain {
                return Err("a material with a graph takes its parameters from the graph:                             remove the other fields"
                    .into());
            }
            return Material::from_graph(name, graph).map_err(|e| e.to_string());
        }
        let strength = self.emission_strength;
        if !strength.is_finite() || strength < 0.0 {
            return Err(format!(
                "emission_strength {strength} must be finite and non-negative"
            ));
        }
        let material = Material {
            name: name.to_owned(),
            base_color: self.base_color.into(),
            base_weight: self.base_weight,
            diffuse_roughness: self.diffuse_roughness,
            metallic: self.metallic,
            roughness: self.roughness,
            anisotropy: self.anisotropy,
            anisotropy_rotation: self.anisotropy_rotation,
            specular_weight: self.specular_weight,
            specular_color: self.specular_color.into(),
            ior: self.ior,
            transmission_weight: self.transmission_weight,
            transmission_color: self.transmission_color.into(),
            transmission_depth: self.transmission_depth,
            coat_weight: self.coat_weight,
            coat_roughness: self.coat_roughness,
            coat_ior: self.coat_ior,
            coat_color: self.coat_color.into(),
            sheen_weight: self.sheen_weight,
            sheen_color: self.sheen_color.into(),
            sheen_roughness: self.sheen_roughness,
            emission: Vec3::from(self.emission) * strength,
            opacity: self.opacity,
            thin_walled: self.thin_walled,
            graph: None,
        };
        material.validate()?;
        Ok(material)
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
enum MeshDesc {
    /// Vertices listed in the file.
    Inline {
        positions: Vec<[f32; 3]>,
        #[serde(default)]
        normals: Vec<[f32; 3]>,
        #[serde(default)]
        uvs: Vec<[f32; 2]>,
        indices: Vec<[u32; 3]>,
    },
    /// A Wavefront OBJ file, relative to the scene file; all its shapes become one mesh.
    Obj(String),
    Quad,
    Cube,
    Sphere {
        #[serde(default = "default_segments")]
        segments: u32,
        #[serde(default = "default_rings")]
        rings: u32,
        #[serde(default = "yes")]
        smooth: bool,
    },
}

fn default_segments() -> u32 {
    64
}

fn default_rings() -> u32 {
    32
}

fn yes() -> bool {
    true
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceDesc {
    mesh: String,
    material: String,
    #[serde(default)]
    transform: TransformDesc,
}

/// Scale, then rotate (Euler angles in degrees, about X, then Y, then Z), then translate;
/// or a full row-major 4x4 `matrix`, which then must be the only field.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformDesc {
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate: [f32; 3],
    #[serde(default = "unit_scale")]
    scale: [f32; 3],
    #[serde(default)]
    matrix: Option<[[f32; 4]; 4]>,
}

fn unit_scale() -> [f32; 3] {
    [1.0; 3]
}

impl Default for TransformDesc {
    fn default() -> Self {
        Self {
            translate: [0.0; 3],
            rotate: [0.0; 3],
            scale: unit_scale(),
            matrix: None,
        }
    }
}

impl TransformDesc {
    fn to_affine(&self) -> Result<Affine3A, String> {
        if let Some(m) = self.matrix {
            let trs_given =
                self.translate != [0.0; 3] || self.rotate != [0.0; 3] || self.scale != unit_scale();
            if trs_given {
                return Err("give either matrix or translate/rotate/scale, not both".into());
            }
            if m[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err("matrix: the last row must be (0, 0, 0, 1)".into());
            }
            let cols = Mat4::from_cols_array_2d(&m).transpose();
            return Ok(Affine3A::from_mat4(cols));
        }
        let [rx, ry, rz] = self.rotate.map(f32::to_radians);
        let rotation = glam::Quat::from_euler(EulerRot::ZYX, rz, ry, rx);
        Ok(Affine3A::from_scale_rotation_translation(
            Vec3::from(self.scale),
            rotation,
            Vec3::from(self.translate),
        ))
    }
}

/// Writes `scene` as a `.kiln` file at `path` (atomically), its meshes as OBJ files and
/// the encoded `images` (those material graphs name `image:N`) as image files in the
/// folder `<stem>.assets` beside it.
pub fn save_scene(
    scene: &Scene,
    path: &Path,
    images: &[(String, std::sync::Arc<Vec<u8>>)],
) -> Result<(), SceneError> {
    let fail = |message: String| SceneError::Io {
        path: path.to_owned(),
        source: std::io::Error::other(message),
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    let assets = format!("{stem}.assets");
    std::fs::create_dir_all(dir.join(&assets)).map_err(|e| fail(e.to_string()))?;

    // Embedded images become files; graphs name them by their new relative path.
    let mut image_files = Vec::new();
    for (i, (name, bytes)) in images.iter().enumerate() {
        let ext = image::guess_format(bytes)
            .ok()
            .and_then(|f| f.extensions_str().first().copied())
            .unwrap_or("bin");
        let clean: String = name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .take(40)
            .collect();
        let file = format!("{assets}/{i}_{clean}.{ext}");
        std::fs::write(dir.join(&file), bytes.as_slice()).map_err(|e| fail(e.to_string()))?;
        image_files.push(file);
    }

    let unique = |names: &mut std::collections::BTreeSet<String>, base: &str| {
        let base = if base.is_empty() { "unnamed" } else { base };
        let mut name = base.to_owned();
        let mut n = 1;
        while !names.insert(name.clone()) {
            n += 1;
            name = format!("{base} {n}");
        }
        name
    };
    let mut taken = std::collections::BTreeSet::new();
    let mut material_names = Vec::new();
    let mut materials = BTreeMap::new();
    for m in &scene.materials {
        let name = unique(&mut taken, &m.name);
        let desc = match &m.graph {
            Some(g) => {
                let mut graph = g.graph.clone();
                let rename = |nodes: &mut BTreeMap<String, crate::material::Node>| {
                    for node in nodes.values_mut() {
                        if let Some(crate::material::Param::Text(file)) =
                            node.params.get_mut("file")
                        {
                            if let Some(i) = file
                                .strip_prefix("image:")
                                .and_then(|n| n.parse::<usize>().ok())
                            {
                                if let Some(f) = image_files.get(i) {
                                    *file = f.clone();
                                }
                            }
                        }
                    }
                };
                rename(&mut graph.nodes);
                for group in graph.groups.values_mut() {
                    rename(&mut group.nodes);
                }
                MaterialDesc {
                    graph: Some(graph),
                    ..MaterialDesc::default()
                }
            }
            None => MaterialDesc::from_params(m),
        };
        material_names.push(name.clone());
        materials.insert(name, desc);
    }

    let mut taken = std::collections::BTreeSet::new();
    let mut mesh_names = Vec::new();
    let mut meshes = BTreeMap::new();
    for (i, mesh) in scene.meshes.iter().enumerate() {
        let name = unique(&mut taken, &mesh.name);
        let file = format!("{assets}/mesh_{i}.obj");
        write_obj(mesh, &dir.join(&file)).map_err(|e| fail(format!("{file}: {e}")))?;
        mesh_names.push(name.clone());
        meshes.insert(name, MeshDesc::Obj(file));
    }

    let instances = scene
        .instances
        .iter()
        .map(|inst| InstanceDesc {
            mesh: mesh_names[inst.mesh].clone(),
            material: material_names[inst.material].clone(),
            transform: TransformDesc {
                matrix: Some(Mat4::from(inst.transform).transpose().to_cols_array_2d()),
                ..TransformDesc::default()
            },
        })
        .collect();
    let c = &scene.camera;
    let projection = if c.aperture_radius > 0.0 {
        Projection::ThinLens {
            fov_y: c.fov_y_degrees,
            aperture_radius: c.aperture_radius,
            focus_distance: c.focus_distance,
        }
    } else {
        Projection::Perspective {
            fov_y: c.fov_y_degrees,
        }
    };
    let lights = scene
        .lights
        .iter()
        .map(|l| match *l {
            Light::Point {
                position,
                intensity,
                radius,
            } => LightDesc::Point {
                position: position.into(),
                intensity: intensity.into(),
                radius,
            },
            Light::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                blend,
                radius,
            } => LightDesc::Spot {
                position: position.into(),
                direction: direction.into(),
                intensity: intensity.into(),
                cone_angle,
                blend,
                radius,
            },
            Light::Distant {
                direction,
                irradiance,
                angular_diameter,
            } => LightDesc::Distant {
                direction: direction.into(),
                irradiance: irradiance.into(),
                angular_diameter,
            },
        })
        .collect();
    let file = SceneFile {
        version: SCENE_FORMAT_VERSION,
        render: RenderDesc {
            width: scene.settings.width,
            height: scene.settings.height,
            samples_per_pixel: scene.settings.samples_per_pixel,
            max_bounces: scene.settings.max_bounces,
        },
        camera: CameraDesc {
            position: c.position.into(),
            look_at: c.look_at.into(),
            up: c.up.into(),
            projection,
        },
        environment: scene.environment.into(),
        environment_map: None,
        materials,
        meshes,
        instances,
        lights,
    };
    let text = ron::ser::to_string_pretty(&file, ron::ser::PrettyConfig::default())
        .map_err(|e| fail(e.to_string()))?;
    let mut temp = tempfile::NamedTempFile::new_in(dir).map_err(|e| fail(e.to_string()))?;
    std::io::Write::write_all(&mut temp, text.as_bytes()).map_err(|e| fail(e.to_string()))?;
    temp.persist(path).map_err(|e| fail(e.error.to_string()))?;
    Ok(())
}

/// A mesh as an OBJ file (positions, UVs, normals, triangles).
fn write_obj(mesh: &crate::scene::Mesh, path: &Path) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "# {} (written by Kiln)", mesh.name)?;
    for (i, p) in mesh.positions.iter().enumerate() {
        match mesh.colors.get(i) {
            Some(c) => writeln!(out, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z)?,
            None => writeln!(out, "v {} {} {}", p.x, p.y, p.z)?,
        }
    }
    for t in &mesh.uvs {
        writeln!(out, "vt {} {}", t.x, t.y)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let (uv, n) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    for t in &mesh.indices {
        let v = |i: u32| {
            let i = i + 1;
            match (uv, n) {
                (true, true) => format!("{i}/{i}/{i}"),
                (true, false) => format!("{i}/{i}"),
                (false, true) => format!("{i}//{i}"),
                (false, false) => format!("{i}"),
            }
        };
        writeln!(out, "f {} {} {}", v(t[0]), v(t[1]), v(t[2]))?;
    }
    out.flush()
}

/// Reads and validates a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse_scene(&text, path, base)
}

/// Parses scene text. `path` is only used in messages; `base_dir` resolves relative paths.
pub fn parse_scene(text: &str, path: &Path, base_dir: &Path) -> Result<Scene, SceneError> {
    let parse_error = |e: ron::error::SpannedError| SceneError::Parse {
        path: path.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    };
    // Read the version alone first, so an old or new file gets a version message rather
    // than a confusing complaint about a field that moved.
    #[derive(Deserialize)]
    struct VersionOnly {
        version: u32,
    }
    // `matrix: (...)` rather than `matrix: Some((...))` for optional fields.
    let ron =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let version = ron
        .from_str::<VersionOnly>(text)
        .map_err(parse_error)?
        .version;
    if version != SCENE_FORMAT_VERSION {
        return Err(SceneError::Version {
            path: path.to_owned(),
            found: version,
        });
    }
    let file: SceneFile = ron.from_str(text).map_err(parse_error)?;
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_owned(),
        message,
    };
    let scene = build_scene(file, path, base_dir, &invalid)?;
    scene.validate().map_err(invalid)?;
    Ok(scene)
}

fn build_scene(
    file: SceneFile,
    path: &Path,
    base_dir: &Path,
    invalid: &dyn Fn(String) -> SceneError,
) -> Result<Scene, SceneError> {
    let (fov_y, aperture_radius, focus_distance) = match file.camera.projection {
        Projection::Perspective { fov_y } => (fov_y, 0.0, 0.0),
        Projection::ThinLens {
            fov_y,
            aperture_radius,
            focus_distance,
        } => (fov_y, aperture_radius, focus_distance),
    };
    let camera = Camera {
        position: file.camera.position.into(),
        look_at: file.camera.look_at.into(),
        up: file.camera.up.into(),
        fov_y_degrees: fov_y,
        aperture_radius,
        focus_distance,
    };
    let mut scene = Scene::empty(camera);
    scene.environment = file.environment.into();
    if let Some(desc) = &file.environment_map {
        let path_of_map = base_dir.join(&desc.file);
        let mut map = EnvironmentMap::load(&path_of_map)
            .map_err(|e| invalid(format!("environment map {}: {e}", path_of_map.display())))?;
        map.strength = desc.strength;
        map.rotation_degrees = desc.rotation;
        scene.environment_map = Some(map);
    }
    scene.settings = SceneSettings {
        width: file.render.width,
        height: file.render.height,
        samples_per_pixel: file.render.samples_per_pixel,
        max_bounces: file.render.max_bounces,
    };

    let mut material_ids = BTreeMap::new();
    for (name, m) in &file.materials {
        let material = m
            .to_material(name, base_dir)
            .map_err(|e| invalid(format!("material \"{name}\": {e}")))?;
        let id = scene.add_material(material);
        material_ids.insert(name.as_str(), id);
    }

    let mut mesh_ids = BTreeMap::new();
    for (name, desc) in file.meshes {
        let mut mesh = match desc {
            MeshDesc::Inline {
                positions,
                normals,
                uvs,
                indices,
            } => Mesh {
                name: String::new(),
                positions: positions.into_iter().map(Vec3::from).collect(),
                normals: normals.into_iter().map(Vec3::from).collect(),
                uvs: uvs.into_iter().map(Vec2::from).collect(),
                indices,
                ..Mesh::default()
            },
            MeshDesc::Obj(file) => {
                let file = base_dir.join(file);
                load_obj(&file).map_err(|message| SceneError::MeshFile {
                    path: path.to_owned(),
                    mesh: name.clone(),
                    file,
                    message,
                })?
            }
            MeshDesc::Quad => shapes::quad(),
            MeshDesc::Cube => shapes::cube(),
            MeshDesc::Sphere {
                segments,
                rings,
                smooth,
            } => {
                if segments > 1 << 14 || rings > 1 << 14 {
                    return Err(invalid(format!(
                        "mesh \"{name}\": at most 16384 segments and rings"
                    )));
                }
                shapes::uv_sphere(segments, rings, smooth)
            }
        };
        mesh.name = name.clone();
        let id = scene.add_mesh(mesh);
        mesh_ids.insert(name, id);
    }

    for (i, inst) in file.instances.iter().enumerate() {
        let mesh = *mesh_ids.get(&inst.mesh).ok_or_else(|| {
            invalid(format!(
                "instance {i}: unknown mesh \"{}\" (defined: {})",
                inst.mesh,
                names(mesh_ids.keys().map(String::as_str))
            ))
        })?;
        let material = *material_ids.get(inst.material.as_str()).ok_or_else(|| {
            invalid(format!(
                "instance {i}: unknown material \"{}\" (defined: {})",
                inst.material,
                names(material_ids.keys().copied())
            ))
        })?;
        let transform = inst
            .transform
            .to_affine()
            .map_err(|e| invalid(format!("instance {i}: transform: {e}")))?;
        scene.add_instance(mesh, material, transform);
    }
    scene.lights = file.lights.iter().map(LightDesc::to_light).collect();
    Ok(scene)
}

fn names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let list: Vec<String> = names.map(|n| format!("\"{n}\"")).collect();
    if list.is_empty() {
        "none".into()
    } else {
        list.join(", ")
    }
}

/// Loads every shape of an OBJ file into one mesh (materials are ignored for now).
fn load_obj(path: &Path) -> Result<Mesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
    let mut mesh = Mesh::default();
    let mut all_have_normals = true;
    let mut all_have_uvs = true;
    let mut all_have_colors = true;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        all_have_normals &= m.normals.len() == count * 3;
        all_have_uvs &= m.texcoords.len() == count * 2;
        if all_have_normals {
            mesh.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        if all_have_uvs {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        }
        // Colours after the position (`v x y z r g b`), an extension many tools write.
        all_have_colors &= m.vertex_color.len() == count * 3;
        if all_have_colors {
            mesh.colors.extend(
                m.vertex_color
                    .chunks_exact(3)
                    .map(|c| glam::Vec4::new(c[0], c[1], c[2], 1.0)),
            );
        }
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if !all_have_normals {
        mesh.normals.clear();
    }
    if !all_have_uvs {
        mesh.uvs.clear();
    }
    if !all_have_colors {
        mesh.colors.clear();
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        parse_scene(text, Path::new("test.kiln"), Path::new("."))
    }

    const MINIMAL: &str = r#"(
        version: 1,
        camera: (position: (0, 0, 5), look_at: (0, 0, 0), projection: Perspective(fov_y: 40)),
        materials: { "grey": (base_color: (0.5, 0.5, 0.5)) },
        meshes: { "ball": Sphere(segments: 8, rings: 4) },
        instances: [(mesh: "ball", material: "grey", transform: (translate: (1, 2, 3), scale: (2, 2, 2)))],
    )"#;

    #[test]
    fn minimal_scene_loads_with_defaults() {
        let scene = parse(MINIMAL).unwrap();
        assert_eq!(scene.instances.len(), 1);
        assert_eq!(scene.settings, SceneSettings::default());
        let t = scene.instances[0].transform;
        assert!((t.transform_point3(Vec3::ZERO) - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
        assert!((t.transform_vector3(Vec3::X) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
    }

    #[test]
    fn syntax_error_names_line_and_column() {
        let err = parse("(\n  version: 1,\n  camera: (position: (0, 0 0)),\n)").unwrap_err();
        match err {
            // The third `0` of `(0, 0 0)`, where a comma or `)` belongs.
            SceneError::Parse { line, column, .. } => assert_eq!((line, column), (3, 28)),
            other => panic!("expected a parse error, got {other}"),
        }
    }

    #[test]
    fn newer_version_is_refused_by_name() {
        let err = parse(&MINIMAL.replace("version: 1", "version: 7")).unwrap_err();
        assert!(err.to_string().contains("version 7"), "{err}");
        assert!(err.to_string().contains("newer"), "{err}");
    }

    #[test]
    fn unknown_mesh_lists_the_defined_ones() {
        let err = parse(&MINIMAL.replace("mesh: \"ball\"", "mesh: \"bal\"")).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("unknown mesh \"bal\"") && msg.contains("\"ball\""),
            "{msg}"
        );
    }

    #[test]
    fn misspelt_field_is_an_error() {
        let err = parse(&MINIMAL.replace("base_color", "base_colour")).unwrap_err();
        assert!(err.to_string().contains("base_colour"), "{err}");
    }

    #[test]
    fn out_of_range_index_is_rejected() {
        let text = MINIMAL.replace(
            "Sphere(segments: 8, rings: 4)",
            "Inline(positions: [(0, 0, 0), (1, 0, 0), (0, 1, 0)], indices: [(0, 1, 3)])",
        );
        let err = parse(&text).unwrap_err();
        assert!(err.to_string().contains("index"), "{err}");
    }

    #[test]
    fn lights_load_with_defaults() {
        let text = MINIMAL.replace(
            "instances: [",
            "lights: [Point(position: (0, 1, 0), intensity: (1, 1, 1)), \
             Spot(position: (0, 1, 0), direction: (0, -1, 0), intensity: (1, 1, 1), cone_angle: 30), \
             Distant(direction: (0, -1, 0), irradiance: (2, 2, 2))],\n        instances: [",
        );
        let scene = parse(&text).unwrap();
        assert_eq!(scene.lights.len(), 3);
        assert!(matches!(scene.lights[0], Light::Point { radius, .. } if radius == 0.0));
        let bad = text.replace("cone_angle: 30", "cone_angle: 300");
        assert!(parse(&bad).unwrap_err().to_string().contains("cone_angle"));
    }

    #[test]
    fn matrix_transform_is_row_major() {
        let text = MINIMAL.replace(
            "transform: (translate: (1, 2, 3), scale: (2, 2, 2))",
            "transform: (matrix: ((1, 0, 0, 5), (0, 1, 0, 6), (0, 0, 1, 7), (0, 0, 0, 1)))",
        );
        let scene = parse(&text).unwrap();
        let p = scene.instances[0].transform.transform_point3(Vec3::ZERO);
        assert_eq!(p, Vec3::new(5.0, 6.0, 7.0));
    }
}
