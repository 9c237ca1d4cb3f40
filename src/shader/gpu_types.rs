//! Rust mirrors of the structs in `shaders/scene.wgsl`, byte for byte.

use bytemuck::{Pod, Zeroable};

/// `Params.flags`: next-event estimation with MIS on.
pub const FLAG_LIGHT_SAMPLING: u32 = 1;
/// `Params.flags`: the environment is a map in `env_data`.
pub const FLAG_ENVIRONMENT_MAP: u32 = 2;
/// `Params.flags`: the scene has a shadow catcher, and the camera sees a transparent
/// background (`shaders/integrator/path.wgsl`, `catcher_shadow`).
pub const FLAG_SHADOW_CATCHER: u32 = 4;
/// `Params.sampler`: independent random numbers, or Owen-scrambled Sobol' points
/// (`shaders/rng.wgsl`).
pub const SAMPLER_INDEPENDENT: u32 = 0;
pub const SAMPLER_SOBOL: u32 = 1;
/// Entries of `Params.filter_quantiles`.
pub const FILTER_TABLE_SIZE: u32 = 128;
/// `Instance.flags`
pub const INSTANCE_HAS_NORMALS: u32 = 1;
pub const INSTANCE_HAS_UVS: u32 = 2;
pub const INSTANCE_HAS_UV1: u32 = 4;
/// The instance is a shadow catcher ([`crate::scene::Instance::shadow_catcher`]).
pub const INSTANCE_SHADOW_CATCHER: u32 = 8;
/// `Instance.volume_grid` of an instance without a grid ([`crate::render::volume_grid`]).
pub const NO_GRID: u32 = u32::MAX;
/// `AnalyticLight.kind`
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DISTANT: u32 = 2;

/// `WideNode.child`: a leaf's primitive count sits above this shift (0 for an inner
/// node), its first primitive (or an inner node's index) below it.
pub const WIDE_COUNT_SHIFT: u32 = 28;
/// `WideNode.child` of a slot without a child.
pub const WIDE_EMPTY: u32 = u32::MAX;

/// Every constant above with its WGSL name, for the test that compares them with
/// `shaders/scene.wgsl`.
pub const MIRRORED_CONSTANTS: [(&str, u32); 17] = [
    ("FLAG_LIGHT_SAMPLING", FLAG_LIGHT_SAMPLING),
    ("FLAG_ENVIRONMENT_MAP", FLAG_ENVIRONMENT_MAP),
    ("FLAG_SHADOW_CATCHER", FLAG_SHADOW_CATCHER),
    ("SAMPLER_INDEPENDENT", SAMPLER_INDEPENDENT),
    ("SAMPLER_SOBOL", SAMPLER_SOBOL),
    ("FILTER_TABLE_SIZE", FILTER_TABLE_SIZE),
    ("INSTANCE_HAS_NORMALS", INSTANCE_HAS_NORMALS),
    ("INSTANCE_HAS_UVS", INSTANCE_HAS_UVS),
    ("INSTANCE_HAS_UV1", INSTANCE_HAS_UV1),
    ("INSTANCE_SHADOW_CATCHER", INSTANCE_SHADOW_CATCHER),
    ("NO_GRID", NO_GRID),
    ("LIGHT_POINT", LIGHT_POINT),
    ("LIGHT_SPOT", LIGHT_SPOT),
    ("LIGHT_DISTANT", LIGHT_DISTANT),
    ("PRINCIPLED_VEC4S", super::principled::PACKED_VEC4S as u32),
    ("WIDE_COUNT_SHIFT", WIDE_COUNT_SHIFT),
    ("WIDE_EMPTY", WIDE_EMPTY),
];

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuParams {
    pub film_size: [u32; 2],
    pub tile_origin: [u32; 2],
    pub tile_size: [u32; 2],
    /// The one sample a dispatch adds to each pixel of its tile.
    pub sample_index: u32,
    /// Keeps the camera's vectors 16-byte aligned.
    pub padding: u32,
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
    /// Total power of the emissive triangles (sum of luminance × area).
    pub light_power: f32,
    /// Probability that next-event estimation picks an emissive triangle.
    pub triangle_pick: f32,
    pub analytic_light_count: u32,
    /// Index of the first pixel of the film piece bound to this dispatch.
    pub film_piece_start: u32,
    /// The kernel's indices of the instances around the camera whose insides hold media,
    /// outermost first ([`crate::accel::query::Enclosures::around`]); the first
    /// `camera_media_count` count.
    pub camera_media: [u32; 4],
    pub camera_media_count: u32,
    /// Volume scattering events per path; past them media only absorb.
    pub max_volume_bounces: u32,
    /// [`SAMPLER_INDEPENDENT`] or [`SAMPLER_SOBOL`].
    pub sampler: u32,
    /// A bake dispatch's grid (the word its header starts at) and first voxel
    /// (`bake_volume_grid`); unused by the path tracer.
    pub bake_grid: u32,
    pub bake_first: u32,
    /// The firefly clamp ([`crate::scene::Clamp`]): the most a sample's direct and indirect
    /// light may add, per contribution; 0 for no limit.
    pub clamp_direct: f32,
    pub clamp_indirect: f32,
    /// Adaptive sampling's noise threshold (`adaptive_converge`): a pixel whose estimated
    /// error is below it takes no more samples; 0 for none.
    pub noise_threshold: f32,
    /// Where next-event estimation splits its samples between the lights at infinity and
    /// the local ones ([`crate::render::light_distribution::LightSelection`]): x the
    /// irradiance at infinity, y the local intensity; the local lights' bounding sphere
    /// (centre, squared radius).
    pub light_split: [f32; 4],
    pub local_lights: [f32; 4],
    /// The pixel filter's quantile function at [`FILTER_TABLE_SIZE`] evenly spaced
    /// probabilities, in pixels ([`crate::shader::filter::PixelFilter::quantiles`]).
    pub filter_quantiles: [[f32; 4]; FILTER_TABLE_SIZE as usize / 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuInstance {
    pub to_world: [[f32; 4]; 3],
    pub to_object: [[f32; 4]; 3],
    pub blas_root: u32,
    pub material: u32,
    pub flags: u32,
    /// The word of `volume_grid` its heterogeneous volume's grid starts at
    /// ([`crate::render::volume_grid`]), or `NO_GRID`.
    pub volume_grid: u32,
    /// Its mesh's bounds in object space (w unused).
    pub mesh_min: [f32; 4],
    pub mesh_max: [f32; 4],
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
    /// The principled parameters, [`super::principled::Principled::pack`]ed.
    pub principled: [[f32; 4]; super::principled::PACKED_VEC4S],
    /// rgb: the emitted radiance light sampling knows in advance (0 where a graph varies
    /// it).
    pub emission: [f32; 4],
    /// 1 if light passes through (the surface keeps its geometric orientation).
    pub transmissive: u32,
    /// 1 for a volume's boundary without a surface: light crosses it unchanged.
    pub boundary_only: u32,
    /// A heterogeneous volume's majorant: the extinction per unit length no point of it
    /// exceeds; 0 for a homogeneous one.
    pub volume_majorant: f32,
    /// 1 if its alpha can be below 1 somewhere ([`super::lobes::CUTOUT`]): shadow rays
    /// evaluate its opacity instead of stopping at it.
    pub cutout: u32,
    /// The homogeneous volume inside: absorption per unit length (w: the phase
    /// function's g), scattering, emission per unit length; zero without one.
    pub volume_absorption: [f32; 4],
    pub volume_scattering: [f32; 4],
    pub volume_emission: [f32; 4],
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
    /// Position (point, spot) or the direction light travels (distant).
    pub position: [f32; 3],
    /// [`LIGHT_POINT`], [`LIGHT_SPOT`] or [`LIGHT_DISTANT`].
    pub kind: u32,
    pub axis: [f32; 4],
    pub intensity: [f32; 4],
    pub shape: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuStats {
    pub rays: u32,
    pub non_finite: u32,
    /// Pixels adaptive sampling has not found converged (`adaptive_converge` counts them).
    pub active_pixels: u32,
    /// Pixel samples the render kernel skipped because their pixel had converged.
    pub skipped_samples: u32,
}

/// A node of the four-wide BVH the kernel walks, as `WideNode` in `shaders/scene.wgsl`
/// ([`crate::accel::widen`] collapses a binary BVH into them): its four children's boxes
/// quantised to a byte per bound and axis against the node's own box (Ylitie et al.,
/// "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", 2017), and
/// per child a leaf (`count << WIDE_COUNT_SHIFT | first`), an inner node's index, or
/// [`WIDE_EMPTY`]. Four texels: a software rasteriser's traversal step costs about what
/// the texels it fetches cost.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WideNode {
    /// The lower corner the children's bounds count steps from.
    pub origin: [f32; 3],
    /// Per axis a byte (x lowest): the exponent of its step, a power of two, biased by 127.
    pub exponents: u32,
    pub child: [u32; 4],
    /// Per bound and axis, a byte per child (child 0 lowest): its bound in steps from the
    /// origin, rounded outwards. `[[lo x, lo y, lo z, hi x], [hi y, hi z, 0, 0]]`.
    pub steps: [[u32; 4]; 2],
}

#[cfg(test)]
mod tests {
    use super::*;
    use naga::proc::Layouter;

    /// The struct `name` of `module`: its size and, per member, (name, offset, size), as
    /// naga's layouter computes them for the WGSL.
    fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32, u32)>) {
        let mut layouter = Layouter::default();
        layouter
            .update(module.to_ctx())
            .expect("scene.wgsl lays out");
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no struct {name} in shaders/scene.wgsl"));
        let naga::TypeInner::Struct { members, .. } = &ty.inner else {
            panic!("{name} is not a struct");
        };
        let fields = members
            .iter()
            .map(|m| {
                (
                    m.name.clone().unwrap_or_default(),
                    m.offset,
                    layouter[m.ty].size,
                )
            })
            .collect();
        (layouter[handle].size, fields)
    }

    /// Asserts that the Rust struct has the WGSL struct's size and, field by field (every
    /// field of both, in order), the same names, offsets and sizes.
    macro_rules! assert_same_layout {
        ($module:expr, $rust:ident, $wgsl:literal, [$($field:ident),+ $(,)?]) => {{
            // Naming every field in a pattern makes a field missing from the list a compile
            // error, so no Rust field goes unchecked.
            let $rust { $($field: _),+ } = <$rust as bytemuck::Zeroable>::zeroed();
            let (size, wgsl) = wgsl_layout($module, $wgsl);
            let rust: Vec<(String, u32, u32)> = vec![$((
                stringify!($field).to_owned(),
                std::mem::offset_of!($rust, $field) as u32,
                {
                    fn size_of_field<T, F>(_: impl Fn(&T) -> &F) -> usize {
                        std::mem::size_of::<F>()
                    }
                    size_of_field(|s: &$rust| &s.$field) as u32
                },
            )),+];
            assert_eq!(
                std::mem::size_of::<$rust>() as u32,
                size,
                "size of {} vs WGSL {}",
                stringify!($rust),
                $wgsl
            );
            assert_eq!(rust, wgsl, "fields of {} vs WGSL {} (name, offset, size)", stringify!($rust), $wgsl);
        }};
    }

    /// `shaders/scene.wgsl` with the generated principled declarations it uses.
    fn scene_wgsl_module() -> naga::Module {
        let text = format!(
            "{}{}",
            super::super::principled::wgsl(),
            include_str!("../../shaders/scene.wgsl")
        );
        naga::front::wgsl::parse_str(&text).expect("scene.wgsl parses")
    }

    #[test]
    fn every_gpu_struct_matches_the_wgsl_layout_field_by_field() {
        let module = scene_wgsl_module();
        assert_same_layout!(
            &module,
            GpuParams,
            "Params",
            [
                film_size,
                tile_origin,
                tile_size,
                sample_index,
                padding,
                seed,
                max_bounces,
                flags,
                light_count,
                instance_count,
                opaque_one,
                triangle_page_shift,
                node_page_shift,
                cam_position,
                cam_right,
                cam_up,
                cam_forward,
                cam_lens,
                environment,
                light_power,
                triangle_pick,
                analytic_light_count,
                film_piece_start,
                camera_media,
                camera_media_count,
                max_volume_bounces,
                sampler,
                bake_grid,
                bake_first,
                clamp_direct,
                clamp_indirect,
                noise_threshold,
                light_split,
                local_lights,
                filter_quantiles,
            ]
        );
        assert_same_layout!(
            &module,
            WideNode,
            "WideNode",
            [origin, exponents, child, steps]
        );
        assert_same_layout!(&module, GpuTriangle, "Triangle", [p0, p1, p2]);
        assert_same_layout!(
            &module,
            GpuInstance,
            "Instance",
            [
                to_world,
                to_object,
                blas_root,
                material,
                flags,
                volume_grid,
                mesh_min,
                mesh_max
            ]
        );
        assert_same_layout!(
            &module,
            GpuMaterial,
            "Material",
            [
                principled,
                emission,
                transmissive,
                boundary_only,
                volume_majorant,
                cutout,
                volume_absorption,
                volume_scattering,
                volume_emission
            ]
        );
        assert_same_layout!(
            &module,
            GpuLightTriangle,
            "LightTriangle",
            [p0, p1, p2, emission]
        );
        assert_same_layout!(
            &module,
            GpuAnalyticLight,
            "AnalyticLight",
            [position, kind, axis, intensity, shape]
        );
        assert_same_layout!(
            &module,
            GpuStats,
            "Stats",
            [rays, non_finite, active_pixels, skipped_samples]
        );
    }

    #[test]
    fn every_mirrored_constant_has_its_wgsl_value() {
        let module = scene_wgsl_module();
        let wgsl: Vec<(String, naga::Literal)> = module
            .constants
            .iter()
            .filter_map(|(_, c)| match module.global_expressions[c.init] {
                naga::Expression::Literal(l) => Some((c.name.clone()?, l)),
                _ => None,
            })
            .collect();
        for (name, value) in MIRRORED_CONSTANTS {
            let found = wgsl.iter().find(|(n, _)| n == name);
            assert_eq!(
                found.map(|(_, l)| *l),
                Some(naga::Literal::U32(value)),
                "{name} in shaders/scene.wgsl vs Rust"
            );
        }
        // Every u32 constant of scene.wgsl is mirrored.
        for (name, literal) in &wgsl {
            if matches!(literal, naga::Literal::U32(_)) {
                assert!(
                    MIRRORED_CONSTANTS.iter().any(|(n, _)| n == name),
                    "{name} of shaders/scene.wgsl has no Rust mirror in MIRRORED_CONSTANTS"
                );
            }
        }
    }
}
