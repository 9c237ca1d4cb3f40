//! Saving a scene loses nothing: loading what `save_scene` wrote gives back an equal
//! `Scene`, compared exactly (`PartialEq`, floats bit for bit up to the sign of zero),
//! for every bundled scene, a hand-built scene using every attribute the format has, an
//! imported glTF file, and generated scenes.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use base64::Engine;
use glam::{Affine3A, EulerRot, Quat, Vec2, Vec3, Vec4};
use kiln::plugin::PluginHost;
use kiln::scene::{
    Camera, Clamp, EnvironmentMap, Light, LightObject, Material, Mesh, Scene, SceneSettings,
    load_scene, save_scene,
};
use kiln::shader::principled::Principled;
use kiln::shader::sampling::{FilterKind, MAX_FILTER_WIDTH, PixelFilter, Sampler, Sampling};
use kiln::shader::view::{Tonemap, ViewSettings};
use proptest::prelude::*;

/// Saves `scene` as `name` in `dir` and loads it back.
fn save_and_load(
    scene: &Scene,
    dir: &Path,
    name: &str,
    images: &[(String, Arc<Vec<u8>>)],
) -> Scene {
    let path = dir.join(name);
    save_scene(scene, &path, images).unwrap_or_else(|e| panic!("saving {name}: {e}"));
    load_scene(&path).unwrap_or_else(|e| panic!("loading the saved {name}: {e}"))
}

fn graph_material(name: &str, text: &str) -> Material {
    let (_, graph) = kiln::material::parse_material(text, name).unwrap();
    Material::from_graph(name, graph).unwrap()
}

#[test]
fn every_bundled_scene_reloads_equal_after_saving() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "kiln"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 3,
        "expected the three bundled scenes under {}, found {files:?}",
        folder.display()
    );
    let dir = tempfile::tempdir().unwrap();
    for file in &files {
        let scene = load_scene(file).unwrap();
        let name = file.file_name().unwrap().to_str().unwrap();
        let again = save_and_load(&scene, dir.path(), name, &[]);
        assert!(
            again == scene,
            "{name} changed by saving and loading:\n{}",
            first_difference(&scene, &again)
        );
    }
}

/// The first part of two scenes that differs, for a readable failure.
fn first_difference(a: &Scene, b: &Scene) -> String {
    if a.camera != b.camera {
        return format!("camera {:?} != {:?}", a.camera, b.camera);
    }
    if a.environment_map != b.environment_map {
        return "environment map".into();
    }
    if a.world != b.world {
        return format!("world {:?}\n!=\n{:?}", a.world, b.world);
    }
    for (i, (x, y)) in a.materials.iter().zip(&b.materials).enumerate() {
        if x != y {
            return format!("material {i}: {x:?}\n!=\n{y:?}");
        }
    }
    for (i, (x, y)) in a.meshes.iter().zip(&b.meshes).enumerate() {
        if x != y {
            return format!("mesh {i} (\"{}\" / \"{}\")", x.name, y.name);
        }
    }
    format!(
        "counts or other fields: {} / {} materials, {} / {} meshes, instances equal: {}, lights equal: {}, settings equal: {}",
        a.materials.len(),
        b.materials.len(),
        a.meshes.len(),
        b.meshes.len(),
        a.instances == b.instances,
        a.lights == b.lights,
        a.settings == b.settings
    )
}

#[test]
fn hand_built_scene_with_every_attribute_reloads_equal() {
    let dir = tempfile::tempdir().unwrap();
    // An image texture read from a file by a graph material.
    let texture = dir.path().join("tex.png");
    image::RgbaImage::from_fn(4, 2, |x, y| {
        image::Rgba([x as u8 * 60, y as u8 * 200, 7, 255])
    })
    .save(&texture)
    .unwrap();
    let camera = Camera {
        position: Vec3::new(0.25, 1.5, 7.125),
        look_at: Vec3::new(0.0, 1.0 / 3.0, 0.0),
        up: Vec3::new(0.1, 1.0, 0.0),
        fov_y_degrees: 37.5,
        aperture_radius: 0.05,
        focus_distance: 6.9,
    };
    let mut scene = Scene::empty(camera);
    scene.environment = Vec3::new(0.1, 0.2, 0.3);
    let mut sky = EnvironmentMap::constant(Vec3::ZERO, 3, 2);
    for (i, t) in sky.texels.iter_mut().enumerate() {
        *t = Vec3::new(i as f32 / 7.0, 1e-3 * i as f32, 123.456 + i as f32);
    }
    sky.strength = 2.5;
    sky.rotation_degrees = -30.25;
    scene.environment_map = Some(sky);
    // A world graph: a sky with its sun moved, mixed with an image looked up by direction.
    let world_graph = kiln::material::parse_material(
        r#"(version: 1, nodes: {
            "sky": (type: "sky_texture", params: { "sun_disc": false }, inputs: {
                "sun_elevation": 12.5, "sun_rotation": -40.0, "altitude": 300.0, "dust": 2.0,
            }),
            "image": (type: "environment_texture", params: { "file": "tex.png", "interpolation": "closest" }),
            "mix": (type: "mix_color", inputs: { "factor": 0.25, "a": "sky.color", "b": "image.color" }),
            "out": (type: "world_output", inputs: { "color": "mix.result", "strength": 0.75 }),
        })"#,
        "world",
    )
    .unwrap()
    .1;
    let mut world_graph = world_graph;
    kiln::material::resolve_files(&mut world_graph, dir.path());
    let mut world = kiln::scene::World::from_graph(world_graph).unwrap();
    world.resolution = 512;
    scene.world = Some(world);
    scene.settings = SceneSettings {
        width: 320,
        height: 180,
        samples_per_pixel: 17,
        max_bounces: 3,
        max_volume_bounces: 2,
        seed: 42,
        sampling: Sampling {
            sampler: Sampler::Independent,
            filter: PixelFilter {
                kind: FilterKind::Gaussian,
                width: 2.25,
            },
        },
        volume_resolution: 96,
        clamp: Clamp {
            direct: 4.5,
            indirect: 0.75,
        },
        noise_threshold: 0.025,
        denoiser: kiln::scene::Denoiser::Atrous,
        view: ViewSettings {
            exposure_ev: -1.25,
            tonemap: Tonemap::PbrNeutral,
        },
    };
    let plain = scene.add_material(Material {
        name: "plain".into(),
        principled: Principled {
            base_color: Vec3::new(0.8, 0.1, 0.1),
            roughness: 0.3,
            anisotropy: 0.5,
            anisotropy_rotation: 0.125,
            coat_weight: 0.7,
            sheen_weight: 0.2,
            transmission_weight: 0.4,
            transmission_depth: 2.0,
            emission_color: Vec3::new(3.0, 2.0, 1.0),
            emission_strength: 1.0,
            alpha: 0.9,
            thin_walled: true,
            ..Principled::default()
        },
        ..Material::default()
    });
    let textured = scene.add_material(graph_material(
        "textured",
        &format!(
            r#"(version: 1, nodes: {{
                "img": (type: "image_texture", params: {{ "file": {:?} }}),
                "s": (type: "principled_bsdf", inputs: {{ "base_color": "img.color" }}),
                "out": (type: "material_output", inputs: {{ "surface": "s.bsdf" }}),
            }})"#,
            texture.to_str().unwrap()
        ),
    ));
    let glowing = scene.add_material(graph_material(
        "glowing checker",
        r#"(version: 1, nodes: {
            "c": (type: "checker_texture", inputs: { "scale": 8.0 }),
            "s": (type: "principled_bsdf", inputs: {
                "base_color": "c.color", "emission_color": (1, 0.5, 0.25), "emission_strength": 4.0,
            }),
            "out": (type: "material_output", inputs: { "surface": "s.bsdf" }),
        })"#,
    ));
    // Names out of alphabetical order: the file keeps the scene's order.
    let full = scene.add_mesh(Mesh {
        name: "z every attribute".into(),
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.1, -0.0),
            Vec3::new(0.2, 1.0, 1e-9),
            Vec3::new(9.0, 9.0, 9.0),
        ],
        normals: vec![Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::Y, Vec3::X],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::new(0.1, 0.9), Vec2::ONE],
        uvs1: vec![
            Vec2::new(0.5, 0.25),
            Vec2::Y,
            Vec2::new(1.0 / 3.0, 0.0),
            Vec2::ZERO,
        ],
        colors: vec![
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 1.0, 0.0, 0.5),
            Vec4::new(0.0, 0.0, 1.0, 0.0),
            Vec4::ONE,
        ],
        // Out of first-use order, and vertex 3 unused.
        indices: vec![[2, 0, 1]],
    });
    let bare = scene.add_mesh(Mesh {
        name: "a bare".into(),
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        uvs1: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
        indices: vec![[0, 1, 2]],
        ..Mesh::default()
    });
    let transform = Affine3A::from_scale_rotation_translation(
        Vec3::new(1.5, 0.5, 2.0),
        Quat::from_euler(EulerRot::ZYX, 0.3, -1.1, 2.0),
        Vec3::new(-1.0, 0.25, 3.0),
    );
    scene.add_instance(full, plain, Affine3A::IDENTITY);
    scene.add_instance(full, textured, transform);
    scene.add_instance(bare, glowing, transform.inverse());
    scene.add_instance(bare, plain, Affine3A::from_translation(Vec3::Y));
    // Object names (quotes and all) and a hidden object.
    scene.instances[1].name = "Teapot \"one\"".into();
    scene.instances[3].name = "hidden".into();
    scene.instances[3].visible = false;
    scene.instances[2].shadow_catcher = true;
    scene.lights = vec![
        Light::Point {
            position: Vec3::new(0.0, 4.0, 0.0),
            intensity: Vec3::splat(50.0),
            radius: 0.0,
        },
        Light::Point {
            position: Vec3::new(2.0, 3.0, 1.0),
            intensity: Vec3::new(20.0, 18.0, 15.0),
            radius: 0.2,
        },
        Light::Spot {
            position: Vec3::new(0.0, 5.0, 3.0),
            direction: Vec3::new(0.0, -1.0, -0.5),
            intensity: Vec3::splat(100.0),
            cone_angle: 25.0,
            blend: 0.3,
            radius: 0.05,
        },
        Light::Distant {
            direction: Vec3::new(-0.3, -1.0, -0.2),
            irradiance: Vec3::new(3.0, 2.9, 2.7),
            angular_diameter: 0.53,
        },
    ]
    .into_iter()
    .map(LightObject::from)
    .collect();
    // Light names (quotes and all) and a hidden light.
    scene.lights[0].name = "Key \"left\"".into();
    scene.lights[2].visible = false;
    scene.validate().unwrap();

    let again = save_and_load(&scene, dir.path(), "every.kiln", &[]);
    assert!(
        again == scene,
        "changed by saving and loading:\n{}",
        first_difference(&scene, &again)
    );
    let text = std::fs::read_to_string(dir.path().join("every.kiln")).unwrap();
    assert!(text.contains("environment_map"), "{text}");

    // A pinhole keeps the focus distance `Camera::look_at` gives it.
    scene.camera = Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, 50.0);
    assert!(scene.camera.focus_distance > 0.0);
    let again = save_and_load(&scene, dir.path(), "pinhole.kiln", &[]);
    assert_eq!(again.camera, scene.camera);
}

/// A base64 data URI.
fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!(
        "data:{mime};base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// A glTF triangle with normals, two UV sets, RGBA vertex colours and a base-colour
/// texture embedded as a data URI, whose blue channel is `blue`.
fn write_gltf(path: &Path, blue: u8) {
    let mut bin: Vec<u8> = Vec::new();
    let mut push = |values: &[f32]| {
        let offset = bin.len();
        for v in values {
            bin.extend(v.to_le_bytes());
        }
        (offset, bin.len() - offset)
    };
    let positions = push(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let normals = push(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let uv0 = push(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let uv1 = push(&[0.25, 0.5, 0.75, 0.125, 1.0 / 3.0, 0.9]);
    let colors = push(&[1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.25]);
    let mut png = Vec::new();
    image::RgbaImage::from_fn(2, 2, |x, y| {
        image::Rgba([200 * x as u8, 100 * y as u8, blue, 255])
    })
    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
    .unwrap();
    let view = |(offset, length): (usize, usize)| {
        format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{length}}}"#)
    };
    let accessor = |view: usize, kind: &str, extra: &str| {
        format!(r#"{{"bufferView":{view},"componentType":5126,"count":3,"type":"{kind}"{extra}}}"#)
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0}}],
        "meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2,"TEXCOORD_1":3,"COLOR_0":4}},"material":0}}]}}],
        "materials":[{{"name":"painted","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}},"roughnessFactor":0.4}}}}],
        "textures":[{{"source":0}}],
        "images":[{{"uri":"{image}"}}],
        "buffers":[{{"byteLength":{length},"uri":"{buffer}"}}],
        "bufferViews":[{views}],
        "accessors":[{a0},{a1},{a2},{a3},{a4}]}}"#,
        image = data_uri("image/png", &png),
        length = bin.len(),
        buffer = data_uri("application/octet-stream", &bin),
        views = [positions, normals, uv0, uv1, colors].map(view).join(","),
        a0 = accessor(0, "VEC3", r#","min":[0,0,0],"max":[1,1,0]"#),
        a1 = accessor(1, "VEC3", ""),
        a2 = accessor(2, "VEC2", ""),
        a3 = accessor(3, "VEC2", ""),
        a4 = accessor(4, "VEC4", ""),
    );
    std::fs::write(path, json).unwrap();
}

#[test]
fn imported_gltf_with_two_uv_sets_colours_and_a_texture_survives_saving() {
    let exe = std::env::current_exe().unwrap();
    let mut host = PluginHost::default();
    host.load_dir(exe.parent().unwrap(), true);
    let dir = tempfile::tempdir().unwrap();
    let gltf = dir.path().join("tri.gltf");
    write_gltf(&gltf, 50);
    let imported = host
        .import(&gltf)
        .unwrap_or_else(|e| panic!("importing {}: {e}", gltf.display()));
    let scene = &imported.scene;
    let mesh = &scene.meshes[0];
    assert_eq!(mesh.uvs1.len(), 3, "TEXCOORD_1 imported");
    assert_eq!(mesh.colors.len(), 3, "COLOR_0 imported");
    assert_eq!(imported.images.len(), 1, "the embedded texture handed over");
    let textured = scene
        .materials
        .iter()
        .find(|m| m.graph.as_ref().is_some_and(|g| !g.images.is_empty()))
        .expect("a graph material reading the texture");

    let saved = save_and_load(scene, dir.path(), "imported.kiln", &imported.images);
    // The first save turns the embedded image into a file; everything else is equal.
    assert_eq!(saved.meshes.len(), scene.meshes.len());
    for (a, b) in scene.meshes.iter().zip(&saved.meshes) {
        assert_eq!(
            Mesh {
                name: String::new(),
                ..a.clone()
            },
            Mesh {
                name: String::new(),
                ..b.clone()
            }
        );
    }
    assert_eq!(saved.instances, scene.instances);
    assert_eq!(saved.camera, scene.camera);
    assert_eq!(saved.lights, scene.lights);
    assert_eq!(saved.environment, scene.environment);
    let reloaded = saved
        .materials
        .iter()
        .find(|m| m.name == textured.name)
        .expect("the textured material, by name");
    let images =
        |m: &Material| -> Vec<_> { m.graph.as_ref().unwrap().images.values().cloned().collect() };
    assert_eq!(images(reloaded), images(textured), "the texture's texels");
    // From then on, saving is a fixed point.
    let again = save_and_load(&saved, dir.path(), "again.kiln", &[]);
    assert!(
        again == saved,
        "changed by a second save:\n{}",
        first_difference(&saved, &again)
    );
}

#[test]
fn an_import_into_an_open_document_keeps_both_files_embedded_images_apart() {
    use kiln::editor::Document;
    let exe = std::env::current_exe().unwrap();
    let mut host = PluginHost::default();
    host.load_dir(exe.parent().unwrap(), true);
    let dir = tempfile::tempdir().unwrap();
    let import = |blue: u8| {
        let gltf = dir.path().join(format!("tri{blue}.gltf"));
        write_gltf(&gltf, blue);
        host.import(&gltf).unwrap()
    };
    let (first, second) = (import(50), import(150));
    let texels =
        |m: &Material| -> Vec<_> { m.graph.as_ref().unwrap().images.values().cloned().collect() };
    let textured = |scene: &Scene| -> Vec<Material> {
        let reads_images = |m: &&Material| m.graph.as_ref().is_some_and(|g| !g.images.is_empty());
        scene
            .materials
            .iter()
            .filter(reads_images)
            .cloned()
            .collect()
    };

    let mut document = Document::new(first.scene.clone(), None, first.images.clone());
    let opened = document.scene().clone();
    document
        .apply(
            document.append(second.scene.clone(), second.images.clone()),
            None,
        )
        .unwrap();
    assert_eq!(document.images().len(), 2, "both files' images held");
    let saved = save_and_load(document.scene(), dir.path(), "both.kiln", document.images());
    let [a, b] = <[Material; 2]>::try_from(textured(&saved)).expect("two textured materials");
    assert_eq!(
        texels(&a),
        texels(&textured(&first.scene)[0]),
        "the first file's texture"
    );
    assert_eq!(
        texels(&b),
        texels(&textured(&second.scene)[0]),
        "the second file's texture"
    );
    assert_ne!(texels(&a), texels(&b));

    assert!(document.undo());
    assert_eq!(
        document.images().len(),
        1,
        "undo takes the import's images back"
    );
    assert_eq!(*document.scene(), opened);
    assert!(document.redo());
    let redone = save_and_load(document.scene(), dir.path(), "redo.kiln", document.images());
    assert_eq!(
        texels(&textured(&redone)[1]),
        texels(&b),
        "redo renumbers the same way"
    );
}

// ---------------------------------------------------------------- generated scenes

fn any_finite() -> impl Strategy<Value = f32> {
    prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL | prop::num::f32::ZERO
}

fn vec2() -> impl Strategy<Value = Vec2> {
    (any_finite(), any_finite()).prop_map(|(x, y)| Vec2::new(x, y))
}

fn vec3(range: std::ops::Range<f32>) -> impl Strategy<Value = Vec3> + Clone {
    (range.clone(), range.clone(), range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn colour() -> impl Strategy<Value = Vec3> {
    (0.0f32..=1.0, 0.0f32..=1.0, 0.0f32..=1.0).prop_map(|(r, g, b)| Vec3::new(r, g, b))
}

/// A mesh of `n` vertices with each optional attribute present or not.
fn mesh() -> impl Strategy<Value = Mesh> {
    /// One value per vertex, or none.
    fn per_vertex<S: Strategy>(
        values: S,
        n: usize,
    ) -> impl Strategy<Value = Option<Vec<S::Value>>> {
        prop::option::of(prop::collection::vec(values, n))
    }
    (1usize..7).prop_flat_map(|n| {
        (
            prop::collection::vec(
                (any_finite(), any_finite(), any_finite()).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
                n,
            ),
            per_vertex(vec3(-1.0..1.0), n),
            per_vertex(vec2(), n),
            per_vertex(vec2(), n),
            per_vertex((colour(), 0.0f32..=1.0).prop_map(|(c, a)| c.extend(a)), n),
            prop::collection::vec(prop::array::uniform3(0..n as u32), 1..6),
        )
            .prop_map(|(positions, normals, uvs, uvs1, colors, indices)| Mesh {
                name: String::new(),
                positions,
                normals: normals.unwrap_or_default(),
                uvs: uvs.unwrap_or_default(),
                uvs1: uvs1.unwrap_or_default(),
                colors: colors.unwrap_or_default(),
                indices,
            })
    })
}

fn material() -> impl Strategy<Value = Material> {
    (
        prop::collection::vec(0.0f32..=1.0, 17),
        prop::collection::vec(colour(), 5),
        (
            -4.0f32..4.0,
            0.0f32..2.0,
            1.0f32..3.0,
            1.0f32..3.0,
            0.0f32..10.0,
        ),
        (vec3(0.0..100.0), any::<bool>()),
    )
        .prop_map(
            |(u, c, (rotation, specular, ior, coat_ior, depth), (emission, thin_walled))| {
                Material::with(
                    "",
                    Principled {
                        base_color: c[0],
                        base_weight: u[0],
                        diffuse_roughness: u[1],
                        metallic: u[2],
                        roughness: u[3],
                        anisotropy: u[4],
                        anisotropy_rotation: rotation,
                        specular_weight: specular,
                        specular_color: c[1],
                        ior,
                        transmission_weight: u[5],
                        transmission_color: c[2],
                        transmission_depth: depth,
                        subsurface_weight: u[13],
                        subsurface_radius: c[2] * 2.0,
                        subsurface_scale: u[15],
                        subsurface_anisotropy: u[14],
                        subsurface_ior: 1.0 + 2.0 * u[16],
                        coat_weight: u[6],
                        coat_roughness: u[7],
                        coat_ior,
                        coat_color: c[3],
                        sheen_weight: u[8],
                        sheen_color: c[4],
                        sheen_roughness: u[9],
                        emission_color: if u[10] < 0.3 { emission } else { Vec3::ONE },
                        emission_strength: if u[10] < 0.3 { 10.0 * u[12] } else { 0.0 },
                        alpha: u[11],
                        thin_walled,
                    },
                )
            },
        )
}

fn light() -> impl Strategy<Value = Light> {
    let position = vec3(-1e3..1e3);
    let direction = vec3(0.1..1.0);
    let power = vec3(0.0..1e3);
    prop_oneof![
        (position.clone(), power.clone(), 0.0f32..2.0).prop_map(|(position, intensity, radius)| {
            Light::Point {
                position,
                intensity,
                radius,
            }
        }),
        (
            position,
            direction.clone(),
            power.clone(),
            (0.01f32..=180.0, 0.0f32..=1.0, 0.0f32..2.0)
        )
            .prop_map(
                |(position, direction, intensity, (cone_angle, blend, radius))| Light::Spot {
                    position,
                    direction,
                    intensity,
                    cone_angle,
                    blend,
                    radius,
                }
            ),
        (direction, power, 0.0f32..89.9).prop_map(|(direction, irradiance, angular_diameter)| {
            Light::Distant {
                direction,
                irradiance,
                angular_diameter,
            }
        }),
    ]
}

fn camera() -> impl Strategy<Value = Camera> {
    (
        vec3(-1e3..1e3),
        // x ≥ 0.1 keeps the view off the up axis.
        (0.1f32..100.0, -100.0f32..100.0, -100.0f32..100.0),
        1.0f32..179.0,
        prop_oneof![Just(0.0f32), 0.0f32..1.0],
        prop_oneof![Just(0.0f32), 0.01f32..100.0],
    )
        .prop_map(|(position, (x, y, z), fov, aperture, focus)| Camera {
            position,
            look_at: position + Vec3::new(x, y, z),
            up: Vec3::Y,
            fov_y_degrees: fov,
            aperture_radius: if focus > 0.0 { aperture } else { 0.0 },
            focus_distance: focus,
        })
}

fn transform() -> impl Strategy<Value = Affine3A> {
    (vec3(0.1..10.0), vec3(-3.0..3.0), vec3(-1e3..1e3)).prop_map(|(scale, angles, translate)| {
        Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_euler(EulerRot::ZYX, angles.z, angles.y, angles.x),
            translate,
        )
    })
}

fn environment_map() -> impl Strategy<Value = EnvironmentMap> {
    (1u32..4, 1u32..4).prop_flat_map(|(w, h)| {
        (
            prop::collection::vec(vec3(0.0..1e4), (w * h) as usize),
            0.0f32..10.0,
            -360.0f32..360.0,
        )
            .prop_map(move |(texels, strength, rotation_degrees)| EnvironmentMap {
                width: w,
                height: h,
                texels,
                strength,
                rotation_degrees,
            })
    })
}

/// Names in no particular order (any printable text, quotes included), made distinct by
/// their index.
fn names(count: usize) -> impl Strategy<Value = Vec<String>> {
    prop::collection::vec("\\PC{0,6}", count).prop_map(|names| {
        names
            .into_iter()
            .enumerate()
            .map(|(i, n)| format!("{n}#{i}"))
            .collect()
    })
}

fn scene() -> impl Strategy<Value = Scene> {
    (
        prop::collection::vec(material(), 1..4),
        prop::collection::vec(mesh(), 1..4),
        camera(),
        prop::collection::vec((light(), "\\PC{0,6}", any::<bool>()), 0..4),
        (vec3(0.0..10.0), prop::option::of(environment_map())),
        (
            (1u32..=16384, 1u32..=16384, 1u32..100_000, 0u32..64),
            (
                any::<u32>(),
                -64f32..=64.0,
                prop::sample::select(Tonemap::ALL.to_vec()),
                prop_oneof![Just(kiln::scene::UNLIMITED_VOLUME_BOUNCES), 0u32..64],
            ),
            (
                prop::sample::select(Sampler::ALL.to_vec()),
                prop::sample::select(FilterKind::ALL.to_vec()),
                prop_oneof![
                    Just(PixelFilter::default().width),
                    0.01f32..=MAX_FILTER_WIDTH
                ],
                prop_oneof![
                    Just(kiln::scene::DEFAULT_VOLUME_RESOLUTION),
                    kiln::scene::VOLUME_RESOLUTIONS
                ],
                (
                    prop_oneof![Just(0.0f32), 0.0f32..1.0e6],
                    prop_oneof![Just(0.0f32), 0.0f32..1.0e6],
                    prop_oneof![Just(0.0f32), 0.0f32..1.0],
                    prop::sample::select(kiln::scene::Denoiser::ALL.to_vec()),
                ),
            ),
        ),
    )
        .prop_flat_map(|(materials, meshes, camera, lights, sky, settings)| {
            let (m, n) = (materials.len(), meshes.len());
            (
                Just((materials, meshes, camera, lights, sky, settings)),
                names(m),
                names(n),
                prop::collection::vec((0..n, 0..m, transform(), "\\PC{0,6}", any::<bool>()), 0..5),
            )
        })
        .prop_map(
            |(
                (materials, meshes, camera, lights, (environment, environment_map), settings),
                material_names,
                mesh_names,
                instances,
            )| {
                let mut scene = Scene::empty(camera);
                scene.environment = environment;
                scene.environment_map = environment_map;
                scene.lights = lights
                    .into_iter()
                    .map(|(light, name, visible)| LightObject {
                        light,
                        name,
                        visible,
                    })
                    .collect();
                let (
                    (width, height, samples_per_pixel, max_bounces),
                    (seed, ev, tonemap, max_volume_bounces),
                    (
                        sampler,
                        filter,
                        filter_width,
                        volume_resolution,
                        (direct, indirect, noise, denoiser),
                    ),
                ) = settings;
                scene.settings = SceneSettings {
                    width,
                    height,
                    samples_per_pixel,
                    max_bounces,
                    max_volume_bounces,
                    seed,
                    sampling: Sampling {
                        sampler,
                        filter: PixelFilter {
                            kind: filter,
                            width: filter_width,
                        },
                    },
                    volume_resolution,
                    clamp: Clamp { direct, indirect },
                    noise_threshold: noise,
                    denoiser,
                    view: ViewSettings {
                        exposure_ev: ev,
                        tonemap,
                    },
                };
                for (m, name) in materials.into_iter().zip(material_names) {
                    scene.add_material(Material { name, ..m });
                }
                for (mesh, name) in meshes.into_iter().zip(mesh_names) {
                    scene.add_mesh(Mesh { name, ..mesh });
                }
                for (mesh, material, transform, name, visible) in instances {
                    scene.add_instance(mesh, material, transform);
                    let added = scene.instances.last_mut().unwrap();
                    added.name = name;
                    added.visible = visible;
                }
                scene
            },
        )
}

proptest! {
    #[test]
    fn generated_scenes_reload_equal_after_saving(scene in scene()) {
        scene.validate().map_err(TestCaseError::fail)?;
        let dir = tempfile::tempdir().unwrap();
        let again = save_and_load(&scene, dir.path(), "generated.kiln", &[]);
        prop_assert!(
            again == scene,
            "changed by saving and loading:\n{}",
            first_difference(&scene, &again)
        );
    }
}
