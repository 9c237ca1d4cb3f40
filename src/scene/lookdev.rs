//! The look-development default: how a model that brings no lights or camera is shown,
//! as Blender, the Khronos sample viewer and look-dev tools open one. Under a clear sky
//! with its sun 35° up and from the camera's front left, on a matte grey ground under
//! the model's bounds (so it casts a visible shadow), seen from a three-quarter view
//! above its front (glTF's +Z, with +Y up) that frames its bounds with a margin. The
//! exposure is chosen from the world's light (`render::world_bake::lookdev_exposure`) so
//! that neither a white nor a dark model clips or sinks.

use glam::{Affine3A, Vec3};

use super::{Camera, Material, Scene, World, shapes};

/// The sun's elevation, degrees.
pub const SUN_ELEVATION: f32 = 35.0;
/// The camera's direction from the model: azimuth from +Z toward +X and elevation,
/// degrees.
const CAMERA_AZIMUTH: f32 = 35.0;
const CAMERA_ELEVATION: f32 = 15.0;
/// Where the sun stands seen from above: this many degrees from the camera's azimuth
/// (negative: to its left), so the model is lit from the front left and its shadow
/// falls back right, in view.
const SUN_FROM_CAMERA: f32 = -70.0;
/// The exposure (stops) under [`world`]: log2(π / E) for its sky's horizontal irradiance
/// E, so that an 18% grey ground comes out at 0.18, a white model in the sun below
/// clipping and a dark one in view (`render::world_bake::lookdev_exposure` computes it
/// from a bake; `tests/world.rs` checks the two agree).
pub const EXPOSURE_EV: f32 = 1.89;
/// The camera's vertical field of view, degrees.
pub const FIELD_OF_VIEW: f32 = 40.0;
/// The share of the frame's height the model's bounding sphere spans.
pub const FRAME_FILL: f32 = 0.8;
/// The ground's side, in bounding-sphere radii: far enough that its edge lies within a
/// pixel of the horizon.
const GROUND_SIZE: f32 = 2000.0;
/// The ground's albedo: a neutral mid grey, matte.
const GROUND_ALBEDO: f32 = 0.4;

/// What the model stands on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Ground {
    /// Nothing: the model floats in the sky.
    None,
    /// A matte grey plane under the model's bounds.
    #[default]
    Plane,
    /// The plane as a shadow catcher: the camera sees the model, its shadow as alpha and
    /// a transparent background, for compositing (an EXR keeps the alpha).
    Catcher,
}

/// A camera that frames every instance of `scene` from the three-quarter view, the
/// bounding sphere spanning [`FRAME_FILL`] of the frame's height.
pub fn camera(scene: &Scene) -> Camera {
    let Some((lo, hi)) = scene.bounds() else {
        return Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, FIELD_OF_VIEW);
    };
    let centre = (lo + hi) * 0.5;
    // The smallest sphere about the box's centre that holds every vertex.
    let mut radius = 1e-6f32;
    for inst in &scene.instances {
        for p in &scene.meshes[inst.mesh].positions {
            radius = radius.max(inst.transform.transform_point3(*p).distance(centre));
        }
    }
    // The sphere's silhouette spans 2 asin(r / d) of the view.
    let half = (FIELD_OF_VIEW.to_radians() * 0.5 * FRAME_FILL).sin();
    let distance = radius / half;
    Camera::look_at(
        centre + direction(CAMERA_AZIMUTH, CAMERA_ELEVATION) * distance,
        centre,
        FIELD_OF_VIEW,
    )
}

/// The unit direction at `azimuth` degrees from +Z toward +X and `elevation` degrees up.
fn direction(azimuth: f32, elevation: f32) -> Vec3 {
    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

/// The clear sky with its sun placed for the three-quarter camera.
pub fn world() -> World {
    // The Sky Texture's rotation r puts the sun toward (sin r, −cos r) in x, z; the sun
    // should stand at azimuth b, toward (sin b, cos b): r = 180° − b.
    let azimuth = CAMERA_AZIMUTH + SUN_FROM_CAMERA;
    World::sky(SUN_ELEVATION, 180.0 - azimuth - 360.0, 1.0)
}

/// Puts `ground` under the bounds of `scene`'s instances (nothing for a scene without
/// geometry or with [`Ground::None`]).
pub fn add_ground(scene: &mut Scene, ground: Ground) {
    if ground != Ground::None
        && let Some((lo, hi)) = scene.bounds()
    {
        let radius = ((hi - lo).length() * 0.5).max(1e-6);
        let centre = (lo + hi) * 0.5;
        let mesh = scene.add_mesh(shapes::quad());
        let material = scene.add_material(Material {
            principled: crate::shader::principled::Principled {
                base_color: Vec3::splat(GROUND_ALBEDO),
                roughness: 0.9,
                specular_weight: 0.2,
                ..Default::default()
            },
            ..Material::diffuse("ground", Vec3::splat(GROUND_ALBEDO))
        });
        scene.meshes[mesh].name = "ground".into();
        scene.add_instance(
            mesh,
            material,
            Affine3A::from_scale_rotation_translation(
                Vec3::new(GROUND_SIZE * radius, 1.0, GROUND_SIZE * radius),
                glam::Quat::IDENTITY,
                Vec3::new(centre.x, lo.y, centre.z),
            ),
        );
        if let Some(i) = scene.instances.last_mut() {
            i.name = "ground".into();
            i.shadow_catcher = ground == Ground::Catcher;
        }
    }
}
