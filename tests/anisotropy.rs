//! Anisotropic highlights follow the mesh's texture u direction, turned by the material's
//! anisotropy rotation: turning the tangent a quarter turn renders what a mesh whose UVs
//! are turned the same way renders without rotation, and differs plainly from no turn.

mod common;

use common::{gpu, mean, render, rmse, settings};
use glam::{Affine3A, Vec2, Vec3};
use kiln::scene::{Camera, Light, Material, Mesh, Scene, shapes};
use kiln::shader::principled::Principled;

/// A brushed-metal floor seen at a slant, with a small sphere light in its mirror
/// direction: the highlight stretches along the tangent.
fn brushed_floor(mesh: Mesh, anisotropy_rotation: f32) -> Vec<Vec3> {
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, 50.0));
    let m = scene.add_material(Material {
        name: "brushed".into(),
        principled: Principled {
            base_color: Vec3::splat(0.9),
            metallic: 1.0,
            roughness: 0.4,
            anisotropy: 1.0,
            anisotropy_rotation,
            ..Principled::default()
        },
        ..Material::default()
    });
    let floor = scene.add_mesh(mesh);
    scene.add_instance(floor, m, Affine3A::from_scale(Vec3::splat(6.0)));
    scene.add_light(Light::Point {
        position: Vec3::new(0.0, 1.5, -1.5),
        intensity: Vec3::splat(2.0),
        radius: 0.1,
    });
    render(&gpu(), &scene, settings(32, 32, 64)).radiance()
}

#[test]
fn anisotropy_rotation_turns_the_highlight_with_the_tangent() {
    // The quad's u runs along +x. Turned a quarter turn about +y, the tangent is y × x = -z.
    let along_x = brushed_floor(shapes::quad(), 0.0);
    let turned = brushed_floor(shapes::quad(), 0.25);
    // The same floor with u running along -z (vertices at z = -0.5, 0.5, 0.5, -0.5).
    let mut quad = shapes::quad();
    quad.uvs = vec![
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
    ];
    let uv_turned = brushed_floor(quad, 0.0);
    let scale = mean(&along_x).x as f64;
    let same = rmse(&turned, &uv_turned) / scale;
    let different = rmse(&along_x, &turned) / scale;
    eprintln!("relative RMSE: turned vs UVs turned {same}, turned vs not {different}");
    assert!(
        same < 0.02,
        "a quarter turn differs from turned UVs: {same}"
    );
    assert!(
        different > 0.2,
        "turning the tangent changes nothing: {different}"
    );
}

#[test]
fn anisotropy_without_uvs_turns_the_normal_frame_tangent() {
    // Without UVs there is no dp/du: the tangent is the first axis of the orthonormal frame
    // around the normal (Duff et al. 2017, `frame_from_normal`), which for the floor's +y
    // normal is +x, the direction the quad's u runs. So the floor without UVs renders
    // what it renders with them, at any rotation, and the rotation still turns it.
    let mut bare = shapes::quad();
    bare.uvs.clear();
    let without_uvs = brushed_floor(bare.clone(), 0.1);
    let with_uvs = brushed_floor(shapes::quad(), 0.1);
    let turned = brushed_floor(bare, 0.35);
    let scale = mean(&with_uvs).x as f64;
    assert!(scale > 0.0, "a black floor: the highlight is not in view");
    let same = rmse(&without_uvs, &with_uvs) / scale;
    let different = rmse(&without_uvs, &turned) / scale;
    eprintln!("relative RMSE: without vs with UVs {same}, turned a quarter more {different}");
    assert!(
        same < 0.02,
        "the fallback tangent is not the normal frame's: {same}"
    );
    assert!(
        different > 0.2,
        "turning the fallback tangent changes nothing: {different}"
    );
}
