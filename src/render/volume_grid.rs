//! Heterogeneous volumes baked into grids. A volume whose graph varies through space is
//! evaluated once per voxel of a grid over its object's bounds, by a small kernel of its
//! own (`bake_volume_grid`, shaders/integrator/volume_bake.wgsl), and the path tracer
//! reads the grid trilinearly wherever delta and ratio tracking land
//! (`volume_grid_at`, shaders/integrator/media.wgsl). This is how Mitsuba 3
//! (`gridvolume`) and pbrt-v4 (`uniformgrid`, `nanovdb`) hold heterogeneous media; Cycles
//! evaluates the shader at every step instead. On a driver that inlines every call
//! (lavapipe), evaluating the graph at each of the tracker's sites compiled it, and in the
//! editor the whole material interpreter, once per site into the megakernel: a procedural
//! cloud more than doubled the showcase's kernel build. Baked, the megakernel holds no
//! volume graph at all, and the graph is compiled once, into the bake kernel.
//!
//! Layout of the `volume_grid` buffer, in 32-bit words: per grid a header of
//! [`HEADER_WORDS`], then its voxels, [`VOXEL_WORDS`] each, x fastest. The grid's points
//! are the corners of its cells and span the object's bounds exactly, so a density that
//! varies linearly is reproduced exactly. A voxel holds σa and σs divided by the
//! material's majorant (so they lie in [0, 1] whatever the density), the phase function's
//! g and the emission, all as half floats (`pack2x16float`); the emission is clamped at
//! the half float's largest value, 65504 per unit length.
//!
//! The resolution ([`crate::scene::SceneSettings::volume_resolution`]) is the number of
//! grid points along the longest side of the object's bounds as placed in the world; the
//! other sides get as many as keep the cells cubic there, and at least two. So a change of
//! an object's scale can change its grid's size, which needs a new renderer.

use glam::Vec3;

use crate::accel::Bvh;
use crate::scene::Scene;

/// Words of a grid's header.
pub const HEADER_WORDS: u32 = 16;
/// Words of one voxel.
pub const VOXEL_WORDS: u32 = 5;
pub use crate::shader::gpu_types::NO_GRID;

/// One grid: over the bounds of scene instance `instance`'s mesh, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub instance: usize,
    /// The word its header starts at.
    pub offset: u32,
    /// Grid points per axis, each at least 2.
    pub dims: [u32; 3],
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Grid {
    pub fn voxels(&self) -> u32 {
        self.dims.iter().product()
    }
}

/// Where the grids of a scene's heterogeneous volumes lie in the `volume_grid` buffer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeGrids {
    pub grids: Vec<Grid>,
    /// Per scene instance: the word its grid's header starts at, or [`NO_GRID`].
    pub offsets: Vec<u32>,
    /// Words of the whole buffer.
    pub words: u64,
}

impl VolumeGrids {
    /// The grids of the instances of `scene` whose material is a heterogeneous volume,
    /// over their meshes' bounds (`blas`, per mesh), with `resolution` points along each
    /// one's longest side.
    pub fn plan(scene: &Scene, blas: &[Option<Bvh>], resolution: u32) -> Self {
        let mut grids = Vec::new();
        let mut offsets = vec![NO_GRID; scene.instances.len()];
        let mut words = 0u64;
        for (i, inst) in scene.instances.iter().enumerate() {
            if scene.materials[inst.material].volume_majorant().is_none() {
                continue;
            }
            let Some(root) = blas[inst.mesh].as_ref().and_then(|b| b.nodes.first()) else {
                continue;
            };
            let (lo, hi) = (Vec3::from(root.min), Vec3::from(root.max));
            // Proportioned by the bounds' sides in the world, so that a squashed sphere
            // (a cloud) gets cells cubic where it is seen, not in its object space.
            let m = inst.transform.matrix3;
            let world =
                (hi - lo) * Vec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
            let dims = grid_dims(world, resolution);
            let voxels = dims.iter().map(|&d| d as u64).product::<u64>();
            // Offsets are u32 words; a buffer past that is refused by its size anyway.
            offsets[i] = words.min(u32::MAX as u64 - 1) as u32;
            grids.push(Grid {
                instance: i,
                offset: offsets[i],
                dims,
                lo,
                hi,
            });
            words += HEADER_WORDS as u64 + voxels * VOXEL_WORDS as u64;
        }
        Self {
            grids,
            offsets,
            words,
        }
    }

    /// The header of each grid, with the scene's current majorants, given the kernel's
    /// index of each scene instance (`kernel_index`, the inverse of the TLAS leaf order).
    pub fn headers(&self, scene: &Scene, kernel_index: &[u32]) -> Vec<(u32, [u32; 16])> {
        self.grids
            .iter()
            .map(|g| {
                let material = scene.instances[g.instance].material;
                let majorant = scene.materials[material].volume_majorant().unwrap_or(0.0);
                let extent = g.hi - g.lo;
                let steps = Vec3::new(
                    (g.dims[0] - 1) as f32,
                    (g.dims[1] - 1) as f32,
                    (g.dims[2] - 1) as f32,
                );
                // A flat side (extent 0) keeps every point on its one plane.
                let to_grid = Vec3::select(extent.cmpgt(Vec3::ZERO), steps / extent, Vec3::ZERO);
                let cell = extent / steps;
                let f = |x: f32| x.to_bits();
                (
                    g.offset,
                    [
                        f(g.lo.x),
                        f(g.lo.y),
                        f(g.lo.z),
                        f(to_grid.x),
                        f(to_grid.y),
                        f(to_grid.z),
                        g.dims[0],
                        g.dims[1],
                        g.dims[2],
                        f(majorant),
                        material as u32,
                        kernel_index[g.instance],
                        f(cell.x),
                        f(cell.y),
                        f(cell.z),
                        0,
                    ],
                )
            })
            .collect()
    }
}

/// Grid points per axis for bounds of size `extent`: `resolution` along the longest side,
/// the others in proportion (cubic cells), each at least 2.
fn grid_dims(extent: Vec3, resolution: u32) -> [u32; 3] {
    let longest = extent.max_element();
    let resolution = resolution.max(2);
    extent.to_array().map(|e| {
        if longest > 0.0 {
            // Less a hair, so that a side of exactly half the longest is not rounded up.
            let cells = (e / longest * (resolution - 1) as f32 - 1e-4)
                .ceil()
                .max(0.0);
            (cells as u32 + 1).clamp(2, resolution)
        } else {
            2
        }
    })
}

/// The kernel's index of each scene instance, from the kernel's order of scene indices.
pub fn kernel_indices(gpu_order: &[u32], instances: usize) -> Vec<u32> {
    let mut index = vec![0u32; instances];
    for (k, &i) in gpu_order.iter().enumerate() {
        index[i as usize] = k as u32;
    }
    index
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_longest_side_gets_the_resolution_and_cells_stay_cubic() {
        assert_eq!(grid_dims(Vec3::new(2.0, 1.0, 0.5), 65), [65, 33, 17]);
        assert_eq!(grid_dims(Vec3::splat(1.0), 128), [128; 3]);
        // Thin sides keep two points; a point-like mesh too.
        assert_eq!(grid_dims(Vec3::new(1.0, 1e-6, 0.0), 64), [64, 2, 2]);
        assert_eq!(grid_dims(Vec3::ZERO, 64), [2, 2, 2]);
        assert_eq!(grid_dims(Vec3::ONE, 0), [2, 2, 2]);
    }
}

#[cfg(test)]
mod plan_tests {
    use glam::{Affine3A, Vec3};

    use super::*;
    use crate::accel::build_scene_accel;
    use crate::material::parse_material;
    use crate::scene::{Camera, Material, Scene, shapes};

    fn noise_volume() -> Material {
        let text = "(version: 1, name: \"v\", nodes: {
            \"noise\": (type: \"noise_texture\"),
            \"v\": (type: \"volume_scatter\", inputs: { \"density\": \"noise.fac\" }),
            \"out\": (type: \"material_output\", inputs: { \"volume\": \"v.volume\" }),
        })";
        let (_, graph) = parse_material(text, "v").expect("parses");
        Material::from_graph("v", graph).expect("compiles")
    }

    #[test]
    fn grids_follow_one_another_proportioned_as_placed_in_the_world() {
        let mut scene = Scene::empty(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, 40.0));
        let cloud = scene.add_material(noise_volume());
        let plain = scene.add_material(Material::default());
        let cube = scene.add_mesh(shapes::cube());
        // A squashed cloud, a plain cube (no grid), and an unscaled cloud.
        scene.add_instance(cube, cloud, Affine3A::from_scale(Vec3::new(4.0, 1.0, 2.0)));
        scene.add_instance(cube, plain, Affine3A::IDENTITY);
        scene.add_instance(cube, cloud, Affine3A::from_translation(Vec3::X * 3.0));
        let accel = build_scene_accel(&scene).expect("builds");
        let grids = VolumeGrids::plan(&scene, &accel.blas, 33);
        assert_eq!(grids.grids.len(), 2);
        assert_eq!(grids.grids[0].dims, [33, 9, 17], "cubic cells in the world");
        assert_eq!(grids.grids[1].dims, [33; 3]);
        let first = HEADER_WORDS as u64 + 33 * 9 * 17 * VOXEL_WORDS as u64;
        assert_eq!(grids.offsets, [0, NO_GRID, first as u32]);
        assert_eq!(
            grids.words,
            first * 2 + (33u64.pow(3) - 33 * 9 * 17) * VOXEL_WORDS as u64
        );
        // The headers carry the majorant and the kernel's index of each instance.
        let headers = grids.headers(&scene, &[2, 0, 1]);
        assert_eq!(headers[0].0, 0);
        // Noise within [0, 1] times the default colour, 0.8.
        assert_eq!(
            f32::from_bits(headers[0].1[9]),
            0.8,
            "the volume's majorant"
        );
        assert_eq!((headers[0].1[11], headers[1].1[11]), (2, 1));
    }
}
