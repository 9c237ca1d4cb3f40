//! A million-triangle mesh loads, builds its BVH, uploads and renders.

mod common;

use common::{gpu, render, settings};
use kiln::bench::large_scene;

#[test]
fn million_triangle_mesh_renders() {
    let ctx = gpu();
    let scene = large_scene(1_000_000);
    assert!(scene.triangle_count() >= 990_000);
    let mut s = settings(32, 32, 4);
    s.max_bounces = 2;
    let film = render(&ctx, &scene, s);
    // The orange sphere fills the middle of the frame: red clearly above blue there, while
    // the sky above it reads the environment.
    let centre = film.pixel(16, 18);
    assert!(
        centre.x > 1.5 * centre.z && centre.x > 0.05,
        "centre pixel {centre}"
    );
    // A camera ray that escapes reads the environment exactly: the top row is sky.
    let sky = film.pixel(16, 0);
    assert!(
        (sky - scene.environment).abs().max_element() < 1e-5,
        "sky pixel {sky}, environment {}",
        scene.environment
    );
}
