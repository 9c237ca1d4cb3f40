//! AOV layers: the albedo, normal and depth of the first surface camera rays meet, and
//! rendering them leaves the beauty image unchanged.

mod common;

use std::sync::Arc;

use common::{gpu, settings};
use glam::{Affine3A, Vec3};
use kiln::render::{RenderControl, Renderer};
use kiln::scene::{Camera, Material, Scene, shapes};

#[test]
fn aovs_describe_the_first_surface_and_leave_the_image_alone() {
    // A red plane filling the view 3 units in front of the camera, under a grey sky.
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, 20.0));
    scene.camera.up = Vec3::Z;
    scene.environment = Vec3::splat(0.5);
    let red = scene.add_material(Material::diffuse("red", Vec3::new(0.8, 0.1, 0.05)));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(quad, red, Affine3A::from_scale(Vec3::splat(50.0)));

    let mut s = settings(8, 8, 16);
    let render = |s| {
        let mut r = Renderer::new(Arc::clone(&gpu()), &scene, s).unwrap();
        r.render(0..16, RenderControl::default()).unwrap();
        let film = r.read_film().unwrap();
        (film.radiance(), r.read_aovs().unwrap())
    };
    let (plain, none) = render(s);
    // Without bounces the image holds only what camera rays see directly; the AOVs still
    // describe the first surface (checked below at every bounce limit).
    let mut no_bounces = s;
    no_bounces.max_bounces = 0;
    no_bounces.aovs = true;
    let (_, first_hit_only) = render(no_bounces);
    assert!(none.is_none(), "AOVs not asked for");
    s.aovs = true;
    let (beauty, aovs) = render(s);
    assert_eq!(plain, beauty, "rendering AOVs changed the image");
    let aovs = aovs.expect("AOVs asked for");
    let first_hit_only = first_hit_only.expect("AOVs asked for");
    assert_eq!(
        (&aovs.albedo, &aovs.normal, &aovs.depth),
        (
            &first_hit_only.albedo,
            &first_hit_only.normal,
            &first_hit_only.depth
        ),
        "the bounce limit changed the AOVs"
    );
    for i in 0..64 {
        let albedo = Vec3::from_slice(&aovs.albedo[3 * i..]);
        let normal = Vec3::from_slice(&aovs.normal[3 * i..]);
        assert!(
            (albedo - Vec3::new(0.8, 0.1, 0.05)).abs().max_element() < 1e-5,
            "albedo {albedo}"
        );
        assert!((normal - Vec3::Y).length() < 1e-4, "normal {normal}");
        // Straight down the middle the plane is 3 away; at the edge of a 20° view a little more.
        assert!(
            aovs.depth[i] > 3.0 && aovs.depth[i] < 3.0 / (10f32.to_radians().cos().powi(2)),
            "depth {}",
            aovs.depth[i]
        );
    }
}
