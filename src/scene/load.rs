//! Loading a `.kiln` scene file: parse the RON text into the [`schema`](super::schema)
//! types, check the version, resolve names and relative paths, and build a validated
//! [`Scene`].
//!
//! Not here: the schema itself, writing scenes ([`save`](super::save)), and reading OBJ
//! files ([`obj`](super::obj)).

use std::collections::BTreeMap;
use std::path::Path;

use glam::{Affine3A, EulerRot, Mat4, Vec2, Vec3, Vec4};
use kiln_plugin_api::read::{MAX_FILE_BYTES, read_text_bounded};
use serde::Deserialize;

use super::file::{SCENE_FORMAT_VERSION, SceneError};
use super::obj::load_obj;
use super::schema::*;
use super::{
    Camera, Clamp, EnvironmentMap, Light, LightObject, Material, Mesh, Scene, SceneSettings, World,
    shapes,
};
use crate::shader::sampling::{FilterKind, PixelFilter, Sampler, Sampling};
use crate::shader::view::{Tonemap, ViewSettings};

impl LightDesc {
    fn object(&self) -> LightObject {
        let (name, visible, light) = match *self {
            LightDesc::Point {
                ref name,
                position,
                intensity,
                radius,
                visible,
            } => (
                name,
                visible,
                Light::Point {
                    position: position.into(),
                    intensity: intensity.into(),
                    radius,
                },
            ),
            LightDesc::Spot {
                ref name,
                position,
                direction,
                intensity,
                cone_angle,
                blend,
                radius,
                visible,
            } => (
                name,
                visible,
                Light::Spot {
                    position: position.into(),
                    direction: direction.into(),
                    intensity: intensity.into(),
                    cone_angle,
                    blend,
                    radius,
                },
            ),
            LightDesc::Distant {
                ref name,
                direction,
                irradiance,
                angular_diameter,
                visible,
            } => (
                name,
                visible,
                Light::Distant {
                    direction: direction.into(),
                    irradiance: irradiance.into(),
                    angular_diameter,
                },
            ),
        };
        LightObject {
            light,
            name: name.clone(),
            visible,
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
            if let Some(first) = self.given.first() {
                return Err(format!(
                    "a material with a graph takes its parameters from the graph: remove `{first}`"
                ));
            }
            return Material::from_graph(name, graph).map_err(|e| e.to_string());
        }
        let material = Material::with(name, self.principled);
        material.validate()?;
        Ok(material)
    }
}

impl WorldDesc {
    fn to_world(&self, base_dir: &Path) -> Result<World, String> {
        let graph = match (&self.graph, &self.graph_file) {
            (Some(_), Some(_)) => return Err("give `graph` or `graph_file`, not both".into()),
            (None, None) => return Err("give a `graph` or a `graph_file`".into()),
            (Some(g), None) => {
                let mut g = g.clone();
                crate::material::resolve_files(&mut g, base_dir);
                g
            }
            (None, Some(file)) => {
                crate::material::load_material(&base_dir.join(file))
                    .map_err(|e| e.to_string())?
                    .1
            }
        };
        let mut world = World::from_graph(graph).map_err(|e| e.to_string())?;
        world.resolution = self.resolution;
        world.validate()?;
        Ok(world)
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

/// Reads and validates a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let text = read_text_bounded(path, MAX_FILE_BYTES).map_err(|cause| SceneError::Io {
        path: path.to_owned(),
        cause,
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
    if let Some(desc) = &file.world {
        scene.world = Some(
            desc.to_world(base_dir)
                .map_err(|e| invalid(format!("world: {e}")))?,
        );
    }
    let render = &file.render;
    let tonemap = render_key(
        "view_transform",
        &render.view_transform,
        &Tonemap::ALL,
        |t| t.key(),
    )
    .map_err(invalid)?;
    let sampler =
        render_key("sampler", &render.sampler, &Sampler::ALL, |s| s.key()).map_err(invalid)?;
    let filter =
        render_key("filter", &render.filter, &FilterKind::ALL, |f| f.key()).map_err(invalid)?;
    let denoiser = render_key("denoise", &render.denoise, &super::Denoiser::ALL, |d| {
        d.key()
    })
    .map_err(invalid)?;
    scene.settings = SceneSettings {
        width: render.width,
        height: render.height,
        samples_per_pixel: render.samples_per_pixel,
        max_bounces: render.max_bounces,
        max_volume_bounces: render.max_volume_bounces,
        seed: render.seed,
        sampling: Sampling {
            sampler,
            filter: PixelFilter {
                kind: filter,
                width: render.filter_width,
            },
        },
        volume_resolution: render.volume_resolution,
        clamp: Clamp {
            direct: render.clamp_direct,
            indirect: render.clamp_indirect,
        },
        noise_threshold: render.noise_threshold,
        denoiser,
        view: ViewSettings {
            exposure_ev: render.exposure,
            tonemap,
        },
    };

    let mut material_ids = BTreeMap::new();
    for (name, m) in &file.materials.0 {
        let material = m
            .to_material(name, base_dir)
            .map_err(|e| invalid(format!("material \"{name}\": {e}")))?;
        let id = scene.add_material(material);
        material_ids.insert(name.as_str(), id);
    }

    let mut mesh_ids = BTreeMap::new();
    // Vertices and triangles of the meshes so far, against --max-triangles as an import's are.
    let (mut vertices, mut triangles) = (0usize, 0usize);
    let limit = usize::try_from(crate::limits::current().triangles).unwrap_or(usize::MAX);
    for (name, desc) in file.meshes.0 {
        let mut mesh = match desc {
            MeshDesc::Inline {
                positions,
                normals,
                uvs,
                uvs1,
                colors,
                indices,
            } => Mesh {
                name: String::new(),
                positions: positions.into_iter().map(Vec3::from).collect(),
                normals: normals.into_iter().map(Vec3::from).collect(),
                uvs: uvs.into_iter().map(Vec2::from).collect(),
                uvs1: uvs1.into_iter().map(Vec2::from).collect(),
                colors: colors.into_iter().map(Vec4::from).collect(),
                indices,
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
        vertices = vertices.saturating_add(mesh.positions.len());
        triangles = triangles.saturating_add(mesh.indices.len());
        if vertices > limit || triangles > limit {
            return Err(invalid(format!(
                "mesh \"{name}\": the scene's meshes would exceed {limit} vertices or {limit} \
                 triangles (--max-triangles raises the limit)"
            )));
        }
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
        let added = scene.instances.last_mut().expect("just added");
        added.name = inst.name.clone();
        added.visible = inst.visible;
        added.shadow_catcher = inst.shadow_catcher;
    }
    scene.lights = file.lights.iter().map(LightDesc::object).collect();
    Ok(scene)
}

/// The one of `all` whose key is `key`, the value of the render setting `field`; an error
/// naming the known keys otherwise.
fn render_key<T: Copy>(
    field: &str,
    key: &str,
    all: &[T],
    key_of: fn(T) -> &'static str,
) -> Result<T, String> {
    all.iter()
        .copied()
        .find(|t| key_of(*t) == key)
        .ok_or_else(|| {
            format!(
                "render: unknown {field} \"{key}\" (known: {})",
                names(all.iter().map(|t| key_of(*t)))
            )
        })
}

fn names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let list: Vec<String> = names.map(|n| format!("\"{n}\"")).collect();
    if list.is_empty() {
        "none".into()
    } else {
        list.join(", ")
    }
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
        assert!(matches!(scene.lights[0].light, Light::Point { radius, .. } if radius == 0.0));
        let bad = text.replace("cone_angle: 30", "cone_angle: 300");
        assert!(parse(&bad).unwrap_err().to_string().contains("cone_angle"));
    }

    #[test]
    fn a_name_given_twice_is_an_error() {
        let text = MINIMAL.replace(
            "meshes: { \"ball\": Sphere(segments: 8, rings: 4) }",
            "meshes: { \"ball\": Quad, \"ball\": Cube }",
        );
        let err = parse(&text).unwrap_err().to_string();
        assert!(err.contains("\"ball\" is defined twice"), "{err}");
    }

    #[test]
    fn materials_and_meshes_keep_the_order_of_the_file() {
        let text = MINIMAL
            .replace(
                "materials: { \"grey\": (base_color: (0.5, 0.5, 0.5)) }",
                "materials: { \"zinc\": (metallic: 1), \"grey\": (), \"amber\": () }",
            )
            .replace(
                "meshes: { \"ball\": Sphere(segments: 8, rings: 4) }",
                "meshes: { \"ball\": Quad, \"a box\": Cube }",
            );
        let scene = parse(&text).unwrap();
        let materials: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(materials, ["zinc", "grey", "amber"]);
        let meshes: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(meshes, ["ball", "a box"]);
        assert_eq!(
            scene.instances[0].material, 1,
            "\"grey\" is the second material"
        );
    }

    #[test]
    fn inline_mesh_takes_a_second_uv_set_and_rgba_colours() {
        let text = MINIMAL.replace(
            "Sphere(segments: 8, rings: 4)",
            "Inline(positions: [(0, 0, 0), (1, 0, 0), (0, 1, 0)], \
             uvs1: [(0, 0), (1, 0), (0.5, 0.25)], \
             colors: [(1, 0, 0, 1), (0, 1, 0, 0.5), (0, 0, 1, 0)], indices: [(0, 1, 2)])",
        );
        let scene = parse(&text).unwrap();
        let mesh = &scene.meshes[0];
        assert_eq!(mesh.uvs1[2], Vec2::new(0.5, 0.25));
        assert_eq!(mesh.colors[1], Vec4::new(0.0, 1.0, 0.0, 0.5));
        assert!(mesh.uvs.is_empty() && mesh.normals.is_empty());
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
