//! The pipeline cache of a `GpuContext` (`KernelSource::create_pipeline`): a renderer
//! for a kernel source the context has compiled before reuses its pipeline, and only a
//! different kernel source compiles a new one.

mod common;

use std::sync::Arc;

use common::{fresh_gpu, furnace_scene, render, settings};
use kiln::render::Renderer;

#[test]
fn a_kernel_source_is_compiled_once_per_context() {
    let ctx = fresh_gpu();
    let compiled = |expected: usize, what: &str| {
        assert_eq!(ctx.pipelines_compiled(), expected, "{what}");
    };
    compiled(0, "a fresh context has compiled nothing");

    let diffuse = furnace_scene(0.5, 1.0);
    let first = render(&ctx, &diffuse, settings(8, 8, 4));
    compiled(1, "the first scene compiles its kernel");
    let again = render(&ctx, &diffuse, settings(8, 8, 4));
    compiled(1, "the same scene again reuses the pipeline");
    // The cached pipeline is the same kernel: the same samples come out.
    assert_eq!(first.radiance(), again.radiance());

    // Settings that are uniforms, not kernel source (size, seed, samples, bounces),
    // and a scene of other geometry and colours but the same features and material
    // code, keep the pipeline.
    let mut other_settings = settings(16, 4, 2);
    other_settings.seed = 9;
    other_settings.max_bounces = 3;
    Renderer::new(Arc::clone(&ctx), &diffuse, other_settings).unwrap();
    Renderer::new(
        Arc::clone(&ctx),
        &furnace_scene(0.8, 0.3),
        settings(8, 8, 1),
    )
    .unwrap();
    compiled(1, "uniform-only changes reuse the pipeline");

    // A scene with emissive triangles and other materials specialises another kernel.
    let cornell = kiln::scene::default_scene().unwrap();
    Renderer::new(Arc::clone(&ctx), &cornell, settings(8, 8, 1)).unwrap();
    compiled(2, "a scene of other features compiles its kernel");
    Renderer::new(Arc::clone(&ctx), &cornell, settings(8, 8, 1)).unwrap();
    compiled(2, "and reuses it after");

    // AOVs are a kernel feature, and bring the noise estimate: the render kernel and
    // adaptive sampling's two check entry points.
    let mut aovs = settings(8, 8, 1);
    aovs.aovs = true;
    Renderer::new(Arc::clone(&ctx), &diffuse, aovs).unwrap();
    compiled(5, "AOVs compile a kernel that writes them");

    // The cache belongs to the context: another one compiles its own.
    let other = fresh_gpu();
    Renderer::new(Arc::clone(&other), &diffuse, settings(8, 8, 1)).unwrap();
    assert_eq!(other.pipelines_compiled(), 1);
    compiled(5, "another context's compile is not counted here");
}
