//! Saving a [`Scene`] as a `.kiln` file: the scene file itself and
//! beside it a `<stem>.assets` folder with the meshes (OBJ) and the images the scene's
//! material graphs read.
//!
//! Not here: the schema ([`schema`](super::schema)), reading scenes ([`load`](super::load))
//! and the OBJ format itself ([`obj`](super::obj)).

use std::path::Path;

use glam::Mat4;
use kiln_plugin_api::atomic::write_atomically;
use std::io::Write;

use super::file::{SCENE_FORMAT_VERSION, SceneError};
use super::obj::write_obj;
use super::schema::*;
use super::{Light, Scene};

/// Writes `scene` as a `.kiln` file at `path`, and in the folder
/// `<stem>.assets` beside it its meshes as OBJ files, its environment map as an EXR and the
/// encoded `images` (those material graphs name `image:N`) as image files. Loading the
/// file gives `scene` back exactly (`tests/scene_round_trip.rs`), provided its materials
/// and meshes have distinct, non-empty names: others are renamed (`"unnamed"`, `"ball 2"`).
/// Every file is written atomically (complete or untouched).
pub fn save_scene(
    scene: &Scene,
    path: &Path,
    images: &[(String, std::sync::Arc<Vec<u8>>)],
) -> Result<(), SceneError> {
    let fail = |message: String| SceneError::Save {
        path: path.to_owned(),
        message,
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    let assets = format!("{stem}.assets");
    let assets_dir = dir.join(&assets);
    std::fs::create_dir_all(&assets_dir)
        .map_err(|e| fail(format!("cannot create {}: {e}", assets_dir.display())))?;

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
        write_atomically(&dir.join(&file), |w| {
            w.write_all(bytes.as_slice()).map_err(|e| e.to_string())
        })
        .map_err(fail)?;
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
    let mut materials = Vec::new();
    for m in &scene.materials {
        let name = unique(&mut taken, &m.name);
        let desc = match &m.graph {
            Some(g) => MaterialDesc::from_graph(saved_graph(&g.graph, &image_files)),
            None => MaterialDesc::from_params(m),
        };
        material_names.push(name.clone());
        materials.push((name, desc));
    }

    let mut taken = std::collections::BTreeSet::new();
    let mut mesh_names = Vec::new();
    let mut meshes = Vec::new();
    for (i, mesh) in scene.meshes.iter().enumerate() {
        let name = unique(&mut taken, &mesh.name);
        let file = format!("{assets}/mesh_{i}.obj");
        write_obj(mesh, &dir.join(&file)).map_err(fail)?;
        mesh_names.push(name.clone());
        meshes.push((name, MeshDesc::Obj(file)));
    }

    let instances = scene
        .instances
        .iter()
        .map(|inst| InstanceDesc {
            name: inst.name.clone(),
            visible: inst.visible,
            shadow_catcher: inst.shadow_catcher,
            mesh: mesh_names[inst.mesh].clone(),
            material: material_names[inst.material].clone(),
            transform: TransformDesc {
                matrix: Some(Mat4::from(inst.transform).transpose().to_cols_array_2d()),
                ..TransformDesc::default()
            },
        })
        .collect();
    let c = &scene.camera;
    // A pinhole keeps its focus distance too (`Camera::look_at` sets one, and the editor
    // may open a lens later): a thin lens of radius 0 is a pinhole that records it.
    let projection = if c.aperture_radius > 0.0 || c.focus_distance != 0.0 {
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
        .map(|object| {
            let name = object.name.clone();
            let visible = object.visible;
            match object.light {
                Light::Point {
                    position,
                    intensity,
                    radius,
                } => LightDesc::Point {
                    name,
                    position: position.into(),
                    intensity: intensity.into(),
                    radius,
                    visible,
                },
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    cone_angle,
                    blend,
                    radius,
                } => LightDesc::Spot {
                    name,
                    position: position.into(),
                    direction: direction.into(),
                    intensity: intensity.into(),
                    cone_angle,
                    blend,
                    radius,
                    visible,
                },
                Light::Distant {
                    direction,
                    irradiance,
                    angular_diameter,
                } => LightDesc::Distant {
                    name,
                    direction: direction.into(),
                    irradiance: irradiance.into(),
                    angular_diameter,
                    visible,
                },
            }
        })
        .collect();
    // The map is written as a 32-bit float EXR, which holds its texels exactly, by the
    // writer of the EXR exporter plugin (alpha 1).
    let environment_map = match &scene.environment_map {
        Some(map) => {
            let file = format!("{assets}/environment.exr");
            let radiance: Vec<f32> = map
                .texels
                .iter()
                .flat_map(|t| t.extend(1.0).to_array())
                .collect();
            let film = kiln_plugin_api::Film {
                width: map.width,
                height: map.height,
                radiance: &radiance,
                display: &[],
                layers: Vec::new(),
            };
            kiln_formats::exr::write(
                &dir.join(&file),
                &film,
                kiln_formats::exr::Compression::ZIP16,
            )
            .map_err(fail)?;
            Some(EnvironmentMapDesc {
                file,
                strength: map.strength,
                rotation: map.rotation_degrees,
            })
        }
        None => None,
    };
    let world = scene.world.as_ref().map(|w| WorldDesc {
        graph: Some(saved_graph(&w.graph, &image_files)),
        graph_file: None,
        resolution: w.resolution,
    });
    let file = SceneFile {
        version: SCENE_FORMAT_VERSION,
        render: RenderDesc {
            width: scene.settings.width,
            height: scene.settings.height,
            samples_per_pixel: scene.settings.samples_per_pixel,
            max_bounces: scene.settings.max_bounces,
            max_volume_bounces: scene.settings.max_volume_bounces,
            seed: scene.settings.seed,
            sampler: scene.settings.sampling.sampler.key().to_owned(),
            filter: scene.settings.sampling.filter.kind.key().to_owned(),
            filter_width: scene.settings.sampling.filter.width,
            volume_resolution: scene.settings.volume_resolution,
            clamp_direct: scene.settings.clamp.direct,
            clamp_indirect: scene.settings.clamp.indirect,
            noise_threshold: scene.settings.noise_threshold,
            denoise: scene.settings.denoiser.key().to_owned(),
            exposure: scene.settings.view.exposure_ev,
            view_transform: scene.settings.view.tonemap.key().to_owned(),
        },
        camera: CameraDesc {
            position: c.position.into(),
            look_at: c.look_at.into(),
            up: c.up.into(),
            projection,
        },
        environment: scene.environment.into(),
        environment_map,
        world,
        materials: Named(materials),
        meshes: Named(meshes),
        instances,
        lights,
    };
    let text = ron::ser::to_string_pretty(&file, ron::ser::PrettyConfig::default())
        .map_err(|e| fail(e.to_string()))?;
    write_atomically(path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(fail)
}

/// `graph` as a saved scene names its images: embedded ones (`image:N`) by the files
/// `image_files` they were written to, others by absolute path.
fn saved_graph(graph: &crate::material::Graph, image_files: &[String]) -> crate::material::Graph {
    let mut graph = graph.clone();
    for file in graph.image_files_mut() {
        if let Some(i) = file
            .strip_prefix("image:")
            .and_then(|n| n.parse::<usize>().ok())
        {
            if let Some(f) = image_files.get(i) {
                *file = f.clone();
            }
        } else if Path::new(file.as_str()).is_relative() {
            // Loading resolved it against the old scene's folder, as seen from the working
            // directory; the saved scene may live elsewhere.
            if let Ok(absolute) = std::path::absolute(file.as_str()) {
                *file = absolute.to_string_lossy().into_owned();
            }
        }
    }
    graph
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    #[test]
    fn a_folder_that_cannot_be_made_is_a_save_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let blocker = dir.path().join("a file");
        std::fs::write(&blocker, "not a folder").unwrap();
        let scene = Scene::empty(Camera::look_at(glam::Vec3::Z, glam::Vec3::ZERO, 40.0));
        let err = save_scene(&scene, &blocker.join("scene.kiln"), &[]).unwrap_err();
        let message = err.to_string();
        assert!(matches!(err, SceneError::Save { .. }), "{message}");
        assert!(
            message.starts_with("cannot save scene") && message.contains("scene.assets"),
            "{message}"
        );
    }
}
