//! `kiln bench --soak N`: N back-to-back renders of small scenes with varying material
//! graphs in one process, with the editor's interpreted kernel (a graph edit is a buffer
//! write, as in the viewport), watching for what a long session would accumulate: the
//! process's resident memory (on a CPU adapter the device's buffers are host memory
//! too, so a leaked GPU buffer shows there), the pipelines the context holds and those it
//! compiled.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::material::load_material;
use crate::render::{GpuContext, KernelKind, RenderControl, RenderSettings, Renderer};
use crate::scene::{self, Material, Scene};

/// Renders between two rows of the table.
const ROW_EVERY: u32 = 100;
/// Pixels along each side of a soak render, and its samples per pixel.
const SIZE: u32 = 32;
const SAMPLES: u32 = 2;
/// Cells along each side of the grid a heterogeneous volume is baked into.
const VOLUME_RESOLUTION: u32 = 16;

/// The bundled materials (assets/materials), when run from the source tree.
pub fn bundled_materials() -> Result<Vec<Material>> {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials");
    let mut files: Vec<_> = std::fs::read_dir(&folder)
        .with_context(|| format!("the soak's materials: {}", folder.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "kmat"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|file| {
            let (name, graph) = load_material(file)?;
            Ok(Material::from_graph(&name, graph)?)
        })
        .collect()
}

/// The Cornell box with each of its materials but the light's replaced by one of
/// `materials`, chosen by `render` (a different combination every render).
fn varied_scene(base: &Scene, materials: &[Material], render: u32) -> Scene {
    let mut scene = base.clone();
    let mut pick = render.wrapping_mul(0x9e37_79b9);
    for slot in scene.materials.iter_mut() {
        if slot.is_emissive() {
            continue;
        }
        pick = pick.rotate_left(7) ^ render;
        *slot = materials[pick as usize % materials.len()].clone();
    }
    scene
}

pub fn soak(ctx: &Arc<GpuContext>, renders: u32, out: &mut dyn std::io::Write) -> Result<()> {
    let base = scene::default_scene()?;
    let materials = bundled_materials()?;
    writeln!(
        out,
        "{renders} renders of the Cornell box at {SIZE}×{SIZE}, {SAMPLES} spp, its materials \
         drawn from the {} bundled graphs, interpreted kernel; adapter: {}\n",
        materials.len(),
        ctx.describe()
    )?;
    writeln!(
        out,
        "| renders | resident MiB | pipelines held | pipelines compiled | ms per render |"
    )?;
    writeln!(out, "|---:|---:|---:|---:|---:|")?;
    let mut since = (Instant::now(), 0);
    let mut first_row = None;
    let mut last_row = 0;
    for render in 0..renders {
        let scene = varied_scene(&base, &materials, render);
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            samples_per_pixel: SAMPLES,
            kernel: KernelKind::Interpreted,
            // The bundled volumes are baked into a grid per render: a small one.
            volume_resolution: VOLUME_RESOLUTION,
            ..RenderSettings::from_scene(&scene)
        };
        let mut renderer = Renderer::new(Arc::clone(ctx), &scene, settings)
            .with_context(|| format!("soak render {render}"))?;
        renderer.render(0..SAMPLES, RenderControl::default())?;
        let film = renderer.read_film()?;
        if film.radiance().iter().any(|p| !p.is_finite()) {
            anyhow::bail!("soak render {render}: a pixel is not finite");
        }
        let done = render + 1;
        if done % ROW_EVERY == 0 || done == renders {
            let resident = super::memory().map_or(0, |(now, _)| now);
            first_row.get_or_insert(resident);
            last_row = resident;
            let per_render = since.0.elapsed().as_secs_f64() * 1e3 / (done - since.1) as f64;
            writeln!(
                out,
                "| {done} | {:.0} | {} | {} | {per_render:.0} |",
                resident as f64 / (1 << 20) as f64,
                ctx.pipelines_cached(),
                ctx.pipelines_compiled(),
            )?;
            since = (Instant::now(), done);
        }
    }
    if let Some(first) = first_row {
        writeln!(
            out,
            "\nresident memory from the first row to the last: {:+.1} MiB",
            (last_row as f64 - first as f64) / (1 << 20) as f64
        )?;
    }
    Ok(())
}
