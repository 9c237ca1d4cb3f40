//! Kernel probes: run a small compute entry point, written against the shipped shader
//! library and an uploaded scene, over an input buffer, and read its output back.
//!
//! This is how tests check the WGSL itself (BVH traversal, sampling routines) instead of
//! a CPU copy of it. A probe kernel declares [`PROBE_BINDINGS`] in [`PROBE_GROUP`]:
//! `@group(1) @binding(0) var<storage, read> probe_in: array<T>;` and
//! `@group(1) @binding(1) var<storage, read_write> probe_out: array<U>;`
//! and runs with `@workgroup_size(64)`, one invocation per index.

use wgpu::util::DeviceExt;

use super::context::GpuContext;
use super::gpu_scene::{FrameBuffers, GpuScene, scene_bind_group_layout};
use super::kernel::KernelSource;
use super::readback::read_buffer;
use super::renderer::{RenderError, RenderSettings, base_params};
use crate::accel::build_scene_accel;
use crate::scene::Scene;
use crate::shader::bindings::{PROBE_BINDINGS, PROBE_GROUP, SCENE_GROUP, probe_layout_entries};

pub const PROBE_WORKGROUP_SIZE: u32 = 64;

/// One probe run: `entry` of the shader library (specialised for the scene) followed by
/// the probe's own WGSL `parts` (path, source), for `invocations` indices, reading `input`
/// and returning `output_bytes` of output.
pub struct Probe<'a> {
    pub name: &'a str,
    pub parts: &'a [(&'a str, &'a str)],
    pub entry: &'a str,
    pub input: &'a [u8],
    pub output_bytes: u64,
    pub invocations: u32,
    /// The contents of `material_params` (graph materials' live constants or programs,
    /// [`super::materials::SceneMaterials::parameters`]); zeros when empty.
    pub material_params: &'a [[f32; 4]],
}

/// Runs a probe with `scene` bound as group 0.
pub fn run_probe(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &RenderSettings,
    probe: &Probe,
) -> Result<Vec<u8>, RenderError> {
    let Probe {
        name,
        parts,
        entry,
        input,
        output_bytes,
        invocations,
        material_params,
    } = *probe;
    let device = &ctx.device;
    // A binding over the limit would not fail loudly everywhere: refuse it here.
    let limit = ctx.limits().max_storage_buffer_binding_size;
    if input.len() as u64 > limit || output_bytes > limit {
        return Err(RenderError::Scene(format!(
            "probe \"{name}\": {} bytes in, {output_bytes} out, over the adapter's {limit}-byte binding limit",
            input.len()
        )));
    }
    let accel = build_scene_accel(scene)?;
    let gpu_scene = GpuScene::upload(
        ctx,
        scene,
        &accel,
        settings.page_bytes,
        settings.volume_resolution,
    )?;
    if !material_params.is_empty() {
        let bytes: &[u8] = bytemuck::cast_slice(material_params);
        if bytes.len() as u64 > gpu_scene.material_params.size() {
            return Err(RenderError::Scene(format!(
                "probe \"{name}\": {} material parameters, over the buffer's {}",
                material_params.len(),
                crate::shader::bindings::MATERIAL_PARAMS
            )));
        }
        ctx.queue.write_buffer(&gpu_scene.material_params, 0, bytes);
    }
    let scene_layout = scene_bind_group_layout(device, &gpu_scene.features());
    let probe_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("probe"),
        entries: &probe_layout_entries(),
    });
    // Test kernels call every lobe and light type, whatever the scene holds.
    let mut source = KernelSource::with_library(name, &gpu_scene.features().everything());
    for (path, wgsl) in parts {
        source.push(path, wgsl);
    }
    // A pipeline layout lists the groups' layouts by group number.
    const _: () = assert!(SCENE_GROUP == 0 && PROBE_GROUP == 1);
    let pipeline = source.create_pipeline(ctx, &[&scene_layout, &probe_layout], entry)?;

    let params = base_params(scene, &gpu_scene, settings);
    let buffer = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let params_buffer = buffer(
        "params",
        bytemuck::bytes_of(&params),
        wgpu::BufferUsages::UNIFORM,
    );
    let film = buffer("film", &[0u8; 16], storage);
    let film_high = buffer("film high words", &[0u8; 16], storage);
    let stats = buffer(
        "stats",
        bytemuck::bytes_of(&crate::shader::gpu_types::GpuStats::default()),
        storage,
    );
    let scene_group = gpu_scene.bind_group(
        device,
        &scene_layout,
        &FrameBuffers {
            params: &params_buffer,
            film_sum: &film,
            film_high: &film_high,
            stats: &stats,
            film_aov: None,
            film_noise: None,
        },
    );
    let padded_input = if input.is_empty() {
        &[0u8; 16][..]
    } else {
        input
    };
    let input_buffer = buffer("probe input", padded_input, storage);
    let output_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe output"),
        size: output_bytes.max(16),
        usage: storage,
        mapped_at_creation: false,
    });
    let probe_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe"),
        layout: &probe_layout,
        entries: &[&input_buffer, &output_buffer]
            .iter()
            .zip(PROBE_BINDINGS)
            .map(|(buffer, b)| wgpu::BindGroupEntry {
                binding: b.binding,
                resource: buffer.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(SCENE_GROUP, &scene_group, &[0]);
        pass.set_bind_group(PROBE_GROUP, &probe_group, &[]);
        // Large probes are cut along y so no dimension exceeds the dispatch limit.
        let groups = invocations.div_ceil(PROBE_WORKGROUP_SIZE);
        let max = ctx.limits().max_compute_workgroups_per_dimension;
        pass.dispatch_workgroups(groups.min(max), groups.div_ceil(max).max(1), 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let mut out = read_buffer(ctx, &output_buffer, output_buffer.size())?;
    out.truncate(output_bytes as usize);
    Ok(out)
}
