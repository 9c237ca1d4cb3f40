//! Pixel filters as renders see them: the image of a straight edge between an emitter and
//! black is the filter's distribution, pixel by pixel. Each pixel across the edge reads
//! the fraction of its filter's mass on the lit side, and pixels beyond the filter's
//! reach read exactly the emitter's radiance (each filter integrates to one).

mod common;

use std::sync::Arc;

use common::{gpu, settings};
use glam::{Affine3A, Vec3};
use kiln::render::{RenderControl, Renderer};
use kiln::scene::{Camera, Material, Scene, shapes};
use kiln::shader::sampling::{FilterKind, PixelFilter, Sampler, Sampling};

const SIZE: u32 = 16;
const SPP: u32 = 256;

/// A camera straight above an emitter of radiance 1 that covers world x < 0 under a black
/// sky. The image of a plane parallel to the film is affine, so the edge is the film's
/// middle column boundary; film x grows towards world -x (the camera's right), so the
/// right half is lit.
fn edge_scene() -> Scene {
    let mut scene = Scene::empty(Camera {
        position: Vec3::new(0.0, 1.0, 0.0),
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        fov_y_degrees: 40.0,
        aperture_radius: 0.0,
        focus_distance: 1.0,
    });
    let light = scene.add_material(Material::emitter("light", Vec3::ONE));
    let quad = scene.add_mesh(shapes::quad());
    scene.add_instance(
        quad,
        light,
        Affine3A::from_translation(Vec3::new(-50.0, 0.0, 0.0))
            * Affine3A::from_scale(Vec3::new(100.0, 1.0, 100.0)),
    );
    scene
}

/// The filter's mass beyond `d` pixels from its centre on one side: the fraction of a pixel
/// whose centre is `d` past the edge that its samples see lit. By a midpoint rule over the
/// shape, apart from the table the kernel samples.
fn lit_fraction(filter: &PixelFilter, d: f64) -> f64 {
    let w = filter.width as f64;
    let n = 20_000;
    let h = w / n as f64;
    let (mut lit, mut total) = (0.0, 0.0);
    for i in 0..n {
        let x = -w / 2.0 + (i as f64 + 0.5) * h;
        let f = filter.shape(x);
        total += f;
        if x > -d {
            lit += f;
        }
    }
    lit / total
}

#[test]
fn the_image_of_an_edge_is_each_filters_distribution() {
    let ctx = gpu();
    let scene = edge_scene();
    let filters = [
        (FilterKind::Box, 1.0),
        (FilterKind::Tent, 2.0),
        (FilterKind::Gaussian, 1.5),
        (FilterKind::BlackmanHarris, 1.5),
        (FilterKind::BlackmanHarris, 4.0),
    ];
    for (kind, width) in filters {
        let filter = PixelFilter { kind, width };
        let mut s = settings(SIZE, SIZE, SPP);
        s.max_bounces = 0;
        s.sampling = Sampling {
            sampler: Sampler::Sobol,
            filter,
        };
        let mut renderer = Renderer::new(Arc::clone(&ctx), &scene, s).expect("renderer");
        renderer
            .render(0..SPP, RenderControl::default())
            .expect("render");
        let image = renderer.read_film().expect("film").radiance();
        for column in 0..SIZE {
            let d = column as f64 + 0.5 - SIZE as f64 / 2.0;
            let expected = lit_fraction(&filter, d);
            let values: Vec<f32> = (0..SIZE)
                .map(|row| image[(row * SIZE + column) as usize].x)
                .collect();
            let mean = values.iter().map(|&v| v as f64).sum::<f64>() / SIZE as f64;
            if expected == 0.0 || expected == 1.0 {
                // Out of the filter's reach every sample lands on one side: exact.
                assert!(
                    values.iter().all(|&v| v as f64 == expected),
                    "{kind:?} {width}: column {column} ({d} px past the edge) should read \
                     {expected} everywhere: {values:?}"
                );
            } else {
                // 256 stratified samples place the edge to about 1/256 of a pixel's mass;
                // the mean over 16 rows (independent scrambles) to a quarter of that.
                assert!(
                    (mean - expected).abs() < 3e-3,
                    "{kind:?} {width}: column {column} ({d} px past the edge) reads \
                     {mean:.5}, the filter's lit mass is {expected:.5}"
                );
            }
        }
    }
}
