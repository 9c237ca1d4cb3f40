//! Rust mirrors of the structs in `shaders/scene.wgsl`, byte for byte.

use bytemuck::{Pod, Zeroable};

/// `Params.flags`: next-event estimation with MIS on.
pub const FLAG_LIGHT_SAMPLING: u32 = 1;
/// `Params.flags`: the environment is a map in `env_data`.
pub const FLAG_ENVIRONMENT_MAP: u32 = 2;
/// `Instance.flags`
pub const INSTANCE_HAS_NORMALS: u32 = 1;
pub const INSTANCE_HAS_UVS: u32 = 2;
pub const INSTANCE_HAS_UV1: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuParams {
    pub film_size: [u32; 2],
    pub tile_origin: [u32; 2],
    pub tile_size: [u32; 2],
    pub sample_start: u32,
    pub sample_count: u32,
    pub seed: u32,
    pub max_bounces: u32,
    pub flags: u32,
    pub light_count: u32,
    pub instance_count: u32,
    /// Always 1.0; see `opaque_one` in `shaders/scene.wgsl`.
    pub opaque_one: f32,
    pub triangle_page_shift: u32,
    pub node_page_shift: u32,
    pub cam_position: [f32; 4],
    pub cam_right: [f32; 4],
    pub cam_up: [f32; 4],
    pub cam_forward: [f32; 4],
    pub cam_lens: [f32; 4],
    pub environment: [f32; 4],
    pub light_totals: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuInstance {
    pub to_world: [[f32; 4]; 3],
    pub to_object: [[f32; 4]; 3],
    pub blas_root: u32,
    pub material: u32,
    pub flags: u32,
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuTriangle {
    pub p0: [f32; 4],
    pub p1: [f32; 4],
    pub p2: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    /// The seven vec4s `principled_unpack` reads (shaders/bsdf/principled.wgsl).
    pub principled: [[f32; 4]; 7],
    /// rgb: emitted radiance; w: opacity.
    pub emission: [f32; 4],
    /// x: 1 if thin-walled; y: 1 if light passes through (keeps geometric orientation);
    /// z: diffuse roughness (f32 bits).
    pub flags: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLightTriangle {
    pub p0: [f32; 4],
    pub p1: [f32; 4],
    pub p2: [f32; 4],
    pub emission: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuAnalyticLight {
    pub position: [f32; 4],
    pub axis: [f32; 4],
    pub intensity: [f32; 4],
    pub shape: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuStats {
    pub rays: u32,
    pub non_finite: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_match_the_wgsl_layout() {
        assert_eq!(std::mem::size_of::<GpuParams>(), 176);
        assert_eq!(std::mem::size_of::<GpuInstance>(), 112);
        assert_eq!(std::mem::size_of::<GpuTriangle>(), 48);
        assert_eq!(std::mem::size_of::<GpuMaterial>(), 144);
        assert_eq!(std::mem::size_of::<GpuLightTriangle>(), 64);
        assert_eq!(std::mem::size_of::<crate::accel::BvhNode>(), 32);
    }
}
