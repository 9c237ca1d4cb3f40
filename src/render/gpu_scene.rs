//! Scene upload: the meshes, their BVHs, instances, materials and lights, flattened into
//! the storage buffers of `shaders/scene.wgsl`, and the bind group over them.
//!
//! Not here: which light to sample with what probability (`light_distribution`) and the
//! environment map's sampling distribution (`environment_cdf`); this file packs and
//! uploads what they compute.

use glam::{Vec2, Vec3};
use thiserror::Error;
use wgpu::util::DeviceExt;

use super::context::GpuContext;
use super::environment_cdf::environment_data;
use super::light_distribution::{emissive_triangles, light_selection};
use super::volume_grid::{VolumeGrids, kernel_indices};
use crate::accel::{SceneAccel, rebase};
use crate::scene::{Scene, shapes};
use crate::shader::bindings::{
    Binding, INSTANCE_TEXELS, LIGHT_CDF_TEXELS, LIGHT_TRIANGLE_TEXELS, MATERIAL_PARAMS,
    MATERIAL_TEXELS, NODE_TEXELS, PAGES, Resource, Space, TRIANGLE_TEXELS, TRIANGLE_VERTEX_TEXELS,
    TexelLayout, TexelReads, VERTEX_TEXELS, bound, scene_layout_entries,
};
use crate::shader::gpu_types::{
    GpuAnalyticLight, GpuInstance, GpuLightTriangle, GpuMaterial, GpuTriangle,
    INSTANCE_HAS_NORMALS, INSTANCE_HAS_UV1, INSTANCE_HAS_UVS, INSTANCE_SHADOW_CATCHER, WideNode,
};
use crate::shader::{Ablation, KernelFeatures};

#[derive(Debug, Error)]
pub enum UploadError {
    #[error(
        "the scene's {buffer} need {bytes} bytes, more than this adapter allows in one buffer binding ({limit} bytes)"
    )]
    TooLarge {
        buffer: &'static str,
        bytes: u64,
        limit: u64,
    },
    #[error(
        "the scene's {table} need a texel table of {rows} rows, more than this adapter's {max_rows}"
    )]
    TooManyRows {
        table: &'static str,
        rows: u32,
        max_rows: u32,
    },
}

/// The scene's buffers on the device, plus the scalars the kernel's `Params` needs.
pub struct GpuScene {
    /// The BVH over instances and the instances in its leaf order, as texels
    /// ([`NODE_TEXELS`], [`INSTANCE_TEXELS`]); edits write them in place.
    pub tlas_texels: wgpu::Texture,
    pub instances: wgpu::Texture,
    /// `PAGES` buffers; unused pages hold one element.
    pub blas_nodes: Vec<wgpu::Buffer>,
    pub triangles: Vec<wgpu::Buffer>,
    /// All BLAS nodes and triangles as texels when `node_pages` and `triangle_pages` are
    /// 0, else one-texel placeholders.
    pub blas_nodes_texels: wgpu::Texture,
    pub triangles_texels: wgpu::Texture,
    /// log2 of the elements per page.
    pub node_page_shift: u32,
    pub triangle_page_shift: u32,
    /// Pages holding data (the rest are one-element placeholders); 0 when the array is
    /// read as texels.
    pub node_pages: u32,
    pub triangle_pages: u32,
    /// Each triangle's vertex indices and the vertex attributes, as texels
    /// ([`TRIANGLE_VERTEX_TEXELS`], [`VERTEX_TEXELS`]).
    pub triangle_vertices: wgpu::Texture,
    pub vertices: wgpu::Texture,
    pub uv1: wgpu::Buffer,
    pub has_uv1: bool,
    /// How kernels read the texel tables unless a render says otherwise: the context's
    /// choice ([`GpuContext::texel_reads`]).
    pub texel_reads: TexelReads,
    /// The materials, the emissive triangles and their CDF, as texels
    /// ([`MATERIAL_TEXELS`], [`LIGHT_TRIANGLE_TEXELS`], [`LIGHT_CDF_TEXELS`]).
    pub materials: wgpu::Texture,
    pub material_count: u32,
    pub light_triangles: wgpu::Texture,
    pub light_cdf: wgpu::Texture,
    pub analytic_lights: wgpu::Buffer,
    /// The BSDFs' energy tables (`tables::DIELECTRIC_ENERGY`), a uniform buffer.
    pub bsdf_tables: wgpu::Buffer,
    pub analytic_light_count: u32,
    pub environment_data: wgpu::Buffer,
    pub has_environment_map: bool,
    /// An instance is a shadow catcher.
    pub has_shadow_catcher: bool,
    /// Principled lobes the scene's instanced materials can reach.
    pub lobes: u32,
    /// The image textures (`material::texture::TextureTable::gpu_words`).
    pub textures: wgpu::Buffer,
    /// The graph materials' live constants (`bindings::MATERIAL_PARAMS` elements;
    /// zeros unless the renderer compiles its materials with live constants).
    pub material_params: wgpu::Buffer,
    pub texture_count: u32,
    /// Probability that next-event estimation samples an emissive triangle among the
    /// local lights.
    pub triangle_pick: f32,
    pub instance_count: u32,
    pub light_count: u32,
    /// Sum over emissive triangles of luminance × area.
    pub light_power: f32,
    /// Probability that next-event estimation samples the environment among the lights
    /// at infinity.
    pub environment_pick: f32,
    /// `Params.light_split` and `Params.local_lights` ([`LightSelection`]).
    pub light_split: [f32; 4],
    pub local_lights: [f32; 4],
    pub bytes: u64,
    /// Per mesh, as [`SceneArrays::meshes`].
    pub meshes: Vec<MeshEntry>,
    /// The heterogeneous volumes' grids: headers written, voxels zero until baked
    /// (`Renderer::bake_volume_grids`).
    pub volume_grid: wgpu::Buffer,
    pub volume_grids: VolumeGrids,
}

/// CPU-side arrays in upload order; separate from the upload so tests can inspect them.
#[derive(Default)]
pub struct SceneArrays {
    pub tlas_nodes: Vec<WideNode>,
    pub instances: Vec<GpuInstance>,
    pub blas_nodes: Vec<WideNode>,
    pub triangles: Vec<GpuTriangle>,
    /// Three global vertex indices per triangle and a word of padding.
    pub triangle_vertices: Vec<[u32; 4]>,
    pub vertices: Vec<[u32; 4]>,
    /// The second UV set per vertex (all vertices, zero where a mesh has none), or empty
    /// when no mesh has one.
    pub uv1: Vec<[f32; 2]>,
    pub materials: Vec<GpuMaterial>,
    pub light_triangles: Vec<GpuLightTriangle>,
    pub light_cdf: Vec<f32>,
    pub light_power: f32,
    pub analytic_lights: Vec<GpuAnalyticLight>,
    /// `env_data` of shaders/lights/environment.wgsl (empty without a map).
    pub environment_data: Vec<[f32; 4]>,
    /// Pick probabilities of the environment and of the emissive triangles, and where
    /// each shading point splits its light samples ([`LightSelection`]).
    pub environment_pick: f32,
    pub triangle_pick: f32,
    pub light_split: [f32; 4],
    pub local_lights: [f32; 4],
    /// Per mesh, what its instances' records hold of it. Kept so instances can be packed
    /// again without the meshes.
    pub meshes: Vec<MeshEntry>,
    /// Where the heterogeneous volumes' grids lie, and their headers.
    pub volume_grids: VolumeGrids,
    pub volume_grid_headers: Vec<(u32, [u32; 16])>,
}

/// What next-event estimation needs of a scene's lights, recomputed whenever a light, an
/// emissive material or an instance's transform changes.
#[derive(Clone, Debug, Default)]
pub struct LightArrays {
    pub light_triangles: Vec<GpuLightTriangle>,
    pub light_cdf: Vec<f32>,
    pub light_power: f32,
    pub analytic_lights: Vec<GpuAnalyticLight>,
    pub environment_pick: f32,
    pub triangle_pick: f32,
    pub light_split: [f32; 4],
    pub local_lights: [f32; 4],
}

/// The lights of `scene`.
pub fn light_arrays(scene: &Scene) -> LightArrays {
    let emissive = emissive_triangles(scene);
    let selection = light_selection(scene, &emissive);
    LightArrays {
        light_triangles: emissive.triangles,
        light_cdf: emissive.cdf,
        light_power: emissive.power,
        analytic_lights: selection.analytic_lights,
        environment_pick: selection.environment_pick,
        triangle_pick: selection.triangle_pick,
        light_split: selection.split,
        local_lights: selection.local_bounds,
    }
}

/// What an instance's record (`GpuInstance`) holds of its mesh.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeshEntry {
    /// Where traversal enters the mesh's BLAS in `blas_nodes`: its root's index, or the
    /// root's only child when that is a leaf (a mesh of a few triangles then costs no node
    /// fetch). 0 for meshes no instance uses.
    pub blas_root: u32,
    /// `INSTANCE_HAS_*`
    pub flags: u32,
    /// The mesh's bounds in object space (generated texture coordinates).
    pub bounds: [[f32; 4]; 2],
}

/// The instances of `scene` in the leaf order of `tlas`, given what their records hold of
/// each mesh (`SceneArrays::meshes`) and each instance's volume grid
/// (`VolumeGrids::offsets`).
pub fn instance_arrays(
    scene: &Scene,
    tlas: Option<&crate::accel::Bvh>,
    meshes: &[MeshEntry],
    grids: &[u32],
) -> Vec<GpuInstance> {
    let Some(tlas) = tlas else {
        return Vec::new();
    };
    tlas.primitive_order
        .iter()
        .map(|&i| {
            let inst = &scene.instances[i as usize];
            let mesh = meshes[inst.mesh];
            GpuInstance {
                to_world: rows(inst.transform),
                to_object: rows(inst.transform.inverse()),
                blas_root: mesh.blas_root,
                material: inst.material as u32,
                flags: mesh.flags
                    | if inst.shadow_catcher {
                        INSTANCE_SHADOW_CATCHER
                    } else {
                        0
                    },
                volume_grid: grids[i as usize],
                mesh_min: mesh.bounds[0],
                mesh_max: mesh.bounds[1],
            }
        })
        .collect()
}

fn rows(m: glam::Affine3A) -> [[f32; 4]; 3] {
    let c = glam::Mat4::from(m).transpose().to_cols_array_2d();
    [c[0], c[1], c[2]]
}

fn pack_snorm16(v: f32) -> u32 {
    ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16 as u16) as u32
}

/// Octahedral encoding into two snorm16s, the inverse of `decode_octahedral` in
/// `shaders/surface.wgsl` (WGSL `unpack2x16snorm`).
pub fn encode_octahedral(n: Vec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
    let e = if n.z >= 0.0 {
        Vec2::new(n.x, n.y)
    } else {
        Vec2::new((1.0 - n.y.abs()) * sign(n.x), (1.0 - n.x.abs()) * sign(n.y))
    };
    pack_snorm16(e.x) | (pack_snorm16(e.y) << 16)
}

/// The GPU form of a material (`Material` in shaders/scene.wgsl).
pub fn pack_material(m: &crate::scene::Material) -> GpuMaterial {
    let v = m.volume().unwrap_or_default();
    GpuMaterial {
        principled: m.principled.pack(),
        emission: m.emission().extend(0.0).into(),
        transmissive: m.is_transmissive() as u32,
        boundary_only: m.is_boundary_only() as u32,
        volume_majorant: m.volume_majorant().unwrap_or(0.0),
        cutout: (m.lobes() & crate::shader::lobes::CUTOUT != 0) as u32,
        volume_absorption: [v.absorption[0], v.absorption[1], v.absorption[2], v.g],
        volume_scattering: [v.scattering[0], v.scattering[1], v.scattering[2], 0.0],
        volume_emission: [v.emission[0], v.emission[1], v.emission[2], 0.0],
    }
}

impl SceneArrays {
    /// The arrays of `scene`, with its heterogeneous volumes' grids at `volume_resolution`
    /// points along their longest sides.
    pub fn build(scene: &Scene, accel: &SceneAccel, volume_resolution: u32) -> Self {
        let mut a = SceneArrays::default();
        // Meshes: BLAS nodes, triangles in leaf order, vertex attributes.
        let mut meshes = vec![MeshEntry::default(); scene.meshes.len()];
        for (m, (mesh, bvh)) in scene.meshes.iter().zip(&accel.blas).enumerate() {
            let Some(bvh) = bvh else { continue };
            let node_base = a.blas_nodes.len() as u32;
            let tri_base = a.triangles.len() as u32;
            let vertex_base = a.vertices.len() as u32;
            let (lo, hi) = bvh.nodes[0].bounds();
            meshes[m].bounds = [lo.extend(0.0).into(), hi.extend(0.0).into()];
            meshes[m].blas_root = rebase(bvh.wide.entry(), node_base, tri_base);
            a.blas_nodes.extend(bvh.wide.nodes.iter().map(|n| WideNode {
                child: n.child.map(|c| rebase(c, node_base, tri_base)),
                ..*n
            }));
            for &t in &bvh.primitive_order {
                let [p0, p1, p2] = mesh.triangle(t as usize);
                a.triangles.push(GpuTriangle {
                    p0: p0.extend(1.0).into(),
                    p1: p1.extend(1.0).into(),
                    p2: p2.extend(1.0).into(),
                });
                let [i0, i1, i2] = mesh.indices[t as usize].map(|i| vertex_base + i);
                a.triangle_vertices.push([i0, i1, i2, 0]);
            }
            let mut normals = mesh.normals.clone();
            if normals.iter().any(|n| n.length_squared() == 0.0) {
                normals = shapes::compute_vertex_normals(&mesh.positions, &mesh.indices);
            }
            for v in 0..mesh.positions.len() {
                let n = normals.get(v).map_or(0, |&n| encode_octahedral(n));
                let uv = mesh.uvs.get(v).copied().unwrap_or(Vec2::ZERO);
                // w: the vertex colour as RGBA8, white where the mesh has none.
                let colour = mesh.colors.get(v).map_or(u32::MAX, |c| {
                    u32::from_le_bytes(
                        c.to_array()
                            .map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8),
                    )
                });
                a.vertices.push([n, uv.x.to_bits(), uv.y.to_bits(), colour]);
            }
            meshes[m].flags = if mesh.normals.is_empty() {
                0
            } else {
                INSTANCE_HAS_NORMALS
            } | if mesh.uvs.is_empty() {
                0
            } else {
                INSTANCE_HAS_UVS
            } | if mesh.uvs1.is_empty() {
                0
            } else {
                INSTANCE_HAS_UV1
            };
        }
        if scene.meshes.iter().any(|m| !m.uvs1.is_empty()) {
            // Indexed like `vertices`: meshes in order, zeros for those without.
            for (mesh, bvh) in scene.meshes.iter().zip(&accel.blas) {
                if bvh.is_some() {
                    a.uv1.extend(
                        (0..mesh.positions.len())
                            .map(|v| mesh.uvs1.get(v).map_or([0.0; 2], |t| t.to_array())),
                    );
                }
            }
        }

        // Instances in TLAS leaf order.
        if let Some(tlas) = &accel.tlas {
            a.tlas_nodes = tlas.wide.nodes.clone();
        }
        a.volume_grids = VolumeGrids::plan(scene, &accel.blas, volume_resolution);
        a.instances = instance_arrays(scene, accel.tlas.as_ref(), &meshes, &a.volume_grids.offsets);
        let order = accel.tlas.as_ref().map_or(&[][..], |t| &t.primitive_order);
        a.volume_grid_headers = a
            .volume_grids
            .headers(scene, &kernel_indices(order, scene.instances.len()));
        a.meshes = meshes;

        a.materials = scene.materials.iter().map(pack_material).collect();

        let lights = light_arrays(scene);
        a.light_triangles = lights.light_triangles;
        a.light_cdf = lights.light_cdf;
        a.light_power = lights.light_power;
        a.analytic_lights = lights.analytic_lights;
        a.environment_pick = lights.environment_pick;
        a.triangle_pick = lights.triangle_pick;
        a.light_split = lights.light_split;
        a.local_lights = lights.local_lights;
        if let Some(map) = &scene.environment_map {
            a.environment_data = environment_data(map);
        }
        a
    }
}

/// The principled lobes the materials of `scene`'s instances can reach.
pub fn instanced_lobes(scene: &Scene) -> u32 {
    scene
        .instances
        .iter()
        .map(|i| scene.materials[i.material].lobes())
        .fold(0, |all, l| all | l)
}

/// The largest storage binding the adapter allows.
fn binding_limit(ctx: &GpuContext) -> u64 {
    let limits = ctx.limits();
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

fn storage_buffer<T: bytemuck::Pod + Default>(
    ctx: &GpuContext,
    name: &'static str,
    data: &[T],
    limit: u64,
    bytes_total: &mut u64,
) -> Result<wgpu::Buffer, UploadError> {
    // Bindings may not be empty: an unused array holds one zeroed element.
    let placeholder = [T::default()];
    let data = if data.is_empty() {
        &placeholder[..]
    } else {
        data
    };
    let bytes = std::mem::size_of_val(data) as u64;
    if bytes > limit {
        return Err(UploadError::TooLarge {
            buffer: name,
            bytes,
            limit,
        });
    }
    *bytes_total += bytes;
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(name),
            contents: bytemuck::cast_slice(data),
            // COPY_DST: edits write into the buffers in place (`Renderer::update`).
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        }))
}

/// Splits `data` into `PAGES` buffers of a power-of-two element count each, the largest
/// that fits a binding. Returns the buffers, log2 of the page length and the pages used.
fn paged_buffers<T: bytemuck::Pod + Default>(
    ctx: &GpuContext,
    name: &'static str,
    data: &[T],
    limit: u64,
    bytes_total: &mut u64,
) -> Result<(Vec<wgpu::Buffer>, u32, u32), UploadError> {
    let element = std::mem::size_of::<T>() as u64;
    let per_page = (limit / element).clamp(1, 1 << 31);
    let shift = 63 - per_page.leading_zeros();
    let page_len = 1usize << shift;
    let total = std::mem::size_of_val(data) as u64;
    if data.len().div_ceil(page_len) > PAGES {
        return Err(UploadError::TooLarge {
            buffer: name,
            bytes: total,
            limit: (page_len as u64 * element) * PAGES as u64,
        });
    }
    let mut pages: Vec<wgpu::Buffer> = Vec::with_capacity(PAGES);
    for chunk in data.chunks(page_len) {
        pages.push(storage_buffer(ctx, name, chunk, limit, bytes_total)?);
    }
    let used = pages.len().max(1) as u32;
    while pages.len() < PAGES {
        pages.push(storage_buffer::<T>(ctx, name, &[], limit, bytes_total)?);
    }
    Ok((pages, shift, used))
}

/// A texel table holding `data` laid out as `layout` says, with as many rows as it needs
/// (one for no data).
pub fn texel_table<T: bytemuck::Pod>(
    ctx: &GpuContext,
    name: &'static str,
    layout: TexelLayout,
    data: &[T],
    bytes_total: &mut u64,
) -> Result<wgpu::Texture, UploadError> {
    let rows = layout.rows(data.len());
    let max_rows = ctx.device.limits().max_texture_dimension_2d;
    if rows > max_rows {
        return Err(UploadError::TooManyRows {
            table: name,
            rows,
            max_rows,
        });
    }
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(name),
        size: wgpu::Extent3d {
            width: layout.width(),
            height: rows,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Uint,
        // COPY_DST: edits write the instances' tables in place (`Renderer::update`).
        // Kernels read a table either way the device can (`TexelReads`).
        usage: if ctx.storage_texels {
            wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_DST
        } else {
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST
        },
        view_formats: &[],
    });
    *bytes_total += u64::from(rows) * u64::from(layout.width()) * 16;
    write_texels(&ctx.queue, &texture, layout, data);
    Ok(texture)
}

/// `values` four to an element (the last padded with ones), for a table of four floats
/// to a texel such as the light CDF.
pub(super) fn in_fours(values: &[f32]) -> Vec<[f32; 4]> {
    values
        .chunks(4)
        .map(|c| std::array::from_fn(|k| c.get(k).copied().unwrap_or(1.0)))
        .collect()
}

/// Writes `data` into the first rows of a texel table laid out as `layout` says.
pub(super) fn write_texels<T: bytemuck::Pod>(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    layout: TexelLayout,
    data: &[T],
) {
    if data.is_empty() {
        return;
    }
    let rows = layout.rows(data.len());
    let row_bytes = layout.width() as usize * 16;
    let mut bytes = bytemuck::cast_slice::<T, u8>(data).to_vec();
    bytes.resize(rows as usize * row_bytes, 0);
    queue.write_texture(
        texture.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(row_bytes as u32),
            rows_per_image: Some(rows),
        },
        wgpu::Extent3d {
            width: layout.width(),
            height: rows,
            depth_or_array_layers: 1,
        },
    );
}

impl GpuScene {
    /// Uploads the scene. `page_bytes` sets the page size of the paged arrays below the
    /// adapter's binding limit (tests use it to exercise paging with small scenes);
    /// `volume_resolution` the heterogeneous volumes' grids
    /// ([`crate::scene::SceneSettings::volume_resolution`]).
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        accel: &SceneAccel,
        page_bytes: Option<u64>,
        volume_resolution: u32,
    ) -> Result<Self, UploadError> {
        let a = SceneArrays::build(scene, accel, volume_resolution);
        let texture_table = super::materials::scene_textures(scene);
        let limit = binding_limit(ctx);
        let page_limit = page_bytes.map_or(limit, |p| p.min(limit));
        let mut bytes = 0;
        // The meshes' BVHs and triangles as texels when both fit in a texture, unless a
        // page size asks for pages (tests of paging).
        let max_rows = ctx.device.limits().max_texture_dimension_2d;
        let in_texels = page_bytes.is_none()
            && NODE_TEXELS.rows(a.blas_nodes.len()) <= max_rows
            && TRIANGLE_TEXELS.rows(a.triangles.len()) <= max_rows;
        let (blas_nodes, node_page_shift, mut node_pages) = paged_buffers(
            ctx,
            "BLAS nodes",
            if in_texels { &[] } else { &a.blas_nodes },
            page_limit,
            &mut bytes,
        )?;
        let (triangles, triangle_page_shift, mut triangle_pages) = paged_buffers(
            ctx,
            "triangles",
            if in_texels { &[] } else { &a.triangles },
            page_limit,
            &mut bytes,
        )?;
        let (blas_nodes_texels, triangles_texels) = if in_texels {
            (node_pages, triangle_pages) = (0, 0);
            (
                texel_table(ctx, "BLAS nodes", NODE_TEXELS, &a.blas_nodes, &mut bytes)?,
                texel_table(ctx, "triangles", TRIANGLE_TEXELS, &a.triangles, &mut bytes)?,
            )
        } else {
            (
                texel_table::<WideNode>(ctx, "BLAS nodes", NODE_TEXELS, &[], &mut bytes)?,
                texel_table::<GpuTriangle>(ctx, "triangles", TRIANGLE_TEXELS, &[], &mut bytes)?,
            )
        };
        let volume_grid = volume_grid_buffer(ctx, &a, limit, &mut bytes)?;
        Ok(Self {
            tlas_texels: texel_table(ctx, "TLAS nodes", NODE_TEXELS, &a.tlas_nodes, &mut bytes)?,
            instances: texel_table(ctx, "instances", INSTANCE_TEXELS, &a.instances, &mut bytes)?,
            blas_nodes,
            triangles,
            blas_nodes_texels,
            triangles_texels,
            node_page_shift,
            triangle_page_shift,
            node_pages,
            triangle_pages,
            triangle_vertices: texel_table(
                ctx,
                "triangle vertex indices",
                TRIANGLE_VERTEX_TEXELS,
                &a.triangle_vertices,
                &mut bytes,
            )?,
            vertices: texel_table(
                ctx,
                "vertex attributes",
                VERTEX_TEXELS,
                &a.vertices,
                &mut bytes,
            )?,
            uv1: storage_buffer(ctx, "second UV set", &a.uv1, limit, &mut bytes)?,
            has_uv1: !a.uv1.is_empty(),
            texel_reads: ctx.texel_reads,
            materials: texel_table(ctx, "materials", MATERIAL_TEXELS, &a.materials, &mut bytes)?,
            material_count: a.materials.len() as u32,
            light_triangles: texel_table(
                ctx,
                "emissive triangles",
                LIGHT_TRIANGLE_TEXELS,
                &a.light_triangles,
                &mut bytes,
            )?,
            light_cdf: texel_table(
                ctx,
                "light CDF",
                LIGHT_CDF_TEXELS,
                &in_fours(&a.light_cdf),
                &mut bytes,
            )?,
            analytic_lights: storage_buffer(ctx, "lights", &a.analytic_lights, limit, &mut bytes)?,
            analytic_light_count: a.analytic_lights.len() as u32,
            bsdf_tables: bsdf_tables_buffer(ctx),
            environment_data: storage_buffer(
                ctx,
                "environment map",
                &a.environment_data,
                limit,
                &mut bytes,
            )?,
            has_environment_map: !a.environment_data.is_empty(),
            has_shadow_catcher: scene.instances.iter().any(|i| i.shadow_catcher),
            textures: storage_buffer(
                ctx,
                "textures",
                &texture_table.gpu_words(),
                limit,
                &mut bytes,
            )?,
            texture_count: texture_table.images.len() as u32,
            material_params: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("material parameters"),
                size: std::mem::size_of::<[[f32; 4]; MATERIAL_PARAMS]>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            lobes: instanced_lobes(scene),
            triangle_pick: a.triangle_pick,
            instance_count: a.instances.len() as u32,
            light_count: a.light_triangles.len() as u32,
            light_power: a.light_power,
            environment_pick: a.environment_pick,
            light_split: a.light_split,
            local_lights: a.local_lights,
            bytes,
            meshes: a.meshes,
            volume_grid,
            volume_grids: a.volume_grids,
        })
    }
}

/// The `volume_grid` buffer: the grids' headers, their voxels zero (baked by the
/// renderer); one word without grids.
fn volume_grid_buffer(
    ctx: &GpuContext,
    a: &SceneArrays,
    limit: u64,
    bytes_total: &mut u64,
) -> Result<wgpu::Buffer, UploadError> {
    let bytes = a.volume_grids.words.max(1) * 4;
    if bytes > limit {
        return Err(UploadError::TooLarge {
            buffer: "heterogeneous volumes' grids (lower the volume resolution)",
            bytes,
            limit,
        });
    }
    *bytes_total += bytes;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("volume grids"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    write_grid_headers(&ctx.queue, &buffer, &a.volume_grid_headers);
    Ok(buffer)
}

/// Writes the grids' headers (`VolumeGrids::headers`) into `buffer`.
pub fn write_grid_headers(
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    headers: &[(u32, [u32; 16])],
) {
    for (offset, header) in headers {
        queue.write_buffer(buffer, *offset as u64 * 4, bytemuck::cast_slice(header));
    }
}

/// The BSDF tables as a uniform buffer: uniform, not storage, so they take none of GL's
/// 16 storage-buffer slots, and 32 KiB fit well within every adapter's 64 KiB.
fn bsdf_tables_buffer(ctx: &GpuContext) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("BSDF tables"),
            contents: bytemuck::cast_slice(&super::tables::DIELECTRIC_ENERGY),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// Layout of group 0 (`bindings::SCENE_BINDINGS`): params, film, stats, then the scene,
/// with only the pages of the paged arrays that `features` uses.
pub fn scene_bind_group_layout(
    device: &wgpu::Device,
    features: &KernelFeatures,
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &scene_layout_entries(features),
    })
}

/// The per-render buffers group 0 binds next to the scene.
pub struct FrameBuffers<'a> {
    pub params: &'a wgpu::Buffer,
    pub film_sum: &'a wgpu::Buffer,
    pub film_high: &'a wgpu::Buffer,
    pub stats: &'a wgpu::Buffer,
    /// The AOV film, when AOVs are rendered.
    pub film_aov: Option<&'a wgpu::Buffer>,
    /// The noise estimate's film, when the noise is estimated.
    pub film_noise: Option<&'a wgpu::Buffer>,
}

impl GpuScene {
    /// The kernel features this scene needs.
    pub fn features(&self) -> KernelFeatures {
        KernelFeatures {
            node_pages: self.node_pages,
            triangle_pages: self.triangle_pages,
            lobes: self.lobes,
            environment_map: self.has_environment_map,
            analytic_lights: self.analytic_light_count > 0,
            infinite_lights: self.light_split[0] > 0.0,
            emissive_triangles: self.light_count > 0,
            shadow_catcher: self.has_shadow_catcher,
            textures: self.texture_count > 0,
            aovs: false,
            noise: false,
            uv1: self.has_uv1,
            ablation: Ablation::Full,
            texel_reads: self.texel_reads,
            sampler: None,
        }
    }

    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        frame: &FrameBuffers,
    ) -> wgpu::BindGroup {
        let features = KernelFeatures {
            aovs: frame.film_aov.is_some(),
            noise: frame.film_noise.is_some(),
            ..self.features()
        };
        // Every binding the layout for these features has (`bindings::bound`), and only
        // those: optional buffers exist exactly when their feature is on.
        let views: Vec<(u32, wgpu::TextureView)> = bound(&features)
            .filter_map(|b| {
                let texture = match b.resource {
                    Resource::TlasTexels => &self.tlas_texels,
                    Resource::Instances => &self.instances,
                    Resource::TriangleVertices => &self.triangle_vertices,
                    Resource::Vertices => &self.vertices,
                    Resource::Materials => &self.materials,
                    Resource::LightTriangles => &self.light_triangles,
                    Resource::LightCdf => &self.light_cdf,
                    Resource::NodeTexels => &self.blas_nodes_texels,
                    Resource::TriangleTexels => &self.triangles_texels,
                    _ => return None,
                };
                Some((b.binding, texture.create_view(&Default::default())))
            })
            .collect();
        let buffers: Vec<(&Binding, &wgpu::Buffer)> = bound(&features)
            .filter(|b| b.space != Space::Texels)
            .map(|b| {
                let buffer = match b.resource {
                    Resource::Params => frame.params,
                    Resource::FilmSum => frame.film_sum,
                    Resource::FilmHigh => frame.film_high,
                    Resource::Stats => frame.stats,
                    Resource::BlasNodes { page } => &self.blas_nodes[page as usize],
                    Resource::Triangles { page } => &self.triangles[page as usize],
                    Resource::AnalyticLights => &self.analytic_lights,
                    Resource::EnvironmentData => &self.environment_data,
                    Resource::DielectricEnergyTable => &self.bsdf_tables,
                    Resource::MaterialParams => &self.material_params,
                    Resource::Textures => &self.textures,
                    Resource::Uv1 => &self.uv1,
                    Resource::VolumeGrid => &self.volume_grid,
                    // Bound only when `features.aovs`, which is `film_aov.is_some()`.
                    Resource::FilmAov => frame.film_aov.expect("AOVs are bound with a film"),
                    Resource::FilmNoise => frame.film_noise.expect("noise is bound with a film"),
                    Resource::TlasTexels
                    | Resource::Instances
                    | Resource::TriangleVertices
                    | Resource::Vertices
                    | Resource::Materials
                    | Resource::LightTriangles
                    | Resource::LightCdf
                    | Resource::NodeTexels
                    | Resource::TriangleTexels => unreachable!("texel tables are views"),
                };
                (b, buffer)
            })
            .collect();
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .map(|(b, buffer)| wgpu::BindGroupEntry {
                binding: b.binding,
                // A slotted buffer is bound one slot wide; the dispatch picks the slot.
                resource: if b.space == Space::UniformSlots {
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset: 0,
                        size: wgpu::BufferSize::new(b.element_bytes),
                    })
                } else {
                    buffer.as_entire_binding()
                },
            })
            .chain(views.iter().map(|(binding, view)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: wgpu::BindingResource::TextureView(view),
            }))
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout,
            entries: &entries,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(packed: u32) -> Vec3 {
        let x = (packed & 0xffff) as u16 as i16 as f32 / 32767.0;
        let y = (packed >> 16) as u16 as i16 as f32 / 32767.0;
        let mut v = Vec3::new(x, y, 1.0 - x.abs() - y.abs());
        if v.z < 0.0 {
            let s = |a: f32| if a >= 0.0 { 1.0 } else { -1.0 };
            v = Vec3::new((1.0 - y.abs()) * s(x), (1.0 - x.abs()) * s(y), v.z);
        }
        v.normalize()
    }

    #[test]
    fn octahedral_normals_round_trip_within_a_thousandth() {
        let mut worst = 0.0f32;
        for i in 0..2000 {
            let t = i as f32 * 0.618_034;
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let r = (1.0 - z * z).sqrt();
            let n = Vec3::new(
                r * (t * std::f32::consts::TAU).cos(),
                r * (t * std::f32::consts::TAU).sin(),
                z,
            );
            worst = worst.max((decode(encode_octahedral(n)) - n).length());
        }
        for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            worst = worst.max((decode(encode_octahedral(n)) - n).length());
        }
        assert!(worst < 1e-3, "worst error {worst}");
    }
}
