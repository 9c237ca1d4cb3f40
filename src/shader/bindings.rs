//! The kernel's bindings, declared once. [`SCENE_BINDINGS`] (group 0) is the one list
//! from which kernel assembly writes the `@group(0) @binding(N) var…` declarations
//! ([`bindings_wgsl`]), and from which the renderer builds the bind group layout
//! ([`scene_layout_entries`]) and the bind group (`GpuScene::bind_group`). The structs the
//! bindings hold stay in `shaders/scene.wgsl`, mirrored in [`super::gpu_types`].
//!
//! It is not a general shader-interface description: every binding is a buffer or a
//! table of rgba32uint texels (read as [`TexelReads`] says), and a probe's group 1
//! ([`PROBE_BINDINGS`]) keeps its element types in its own test kernel.

use std::num::NonZeroU64;

use super::KernelFeatures;
use super::gpu_types::{
    GpuAnalyticLight, GpuInstance, GpuLightTriangle, GpuMaterial, GpuParams, GpuStats, GpuTriangle,
    WideNode,
};

/// How the kernel sees a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    /// `var<uniform>`: takes none of GL's 16 storage-buffer slots.
    Uniform,
    /// `var<uniform>` bound at a dynamic offset: the buffer holds a slot per dispatch of a
    /// submission, and each dispatch picks its own with `set_bind_group`'s offsets.
    UniformSlots,
    /// `var<storage, read>`
    ReadOnly,
    /// `var<storage, read_write>`
    ReadWrite,
    /// A texture of rgba32uint texels holding an array of fixed-size elements
    /// ([`TexelLayout`]), read with `textureLoad` as [`TexelReads`] says. The traversal
    /// reads the BVHs, the triangles and the instances' placements this way: on a
    /// software rasteriser (llvmpipe) a texel read is a vector load per lane, where a
    /// storage-buffer load that differs between lanes was a loop over the lanes for every
    /// word (`kiln bench --fetch` measures both).
    Texels,
}

impl Space {
    /// What is written between `var` and the name: `<uniform>`, `<storage, read>`, …
    pub fn wgsl(self) -> &'static str {
        match self {
            Space::Uniform | Space::UniformSlots => "<uniform>",
            Space::ReadOnly => "<storage, read>",
            Space::ReadWrite => "<storage, read_write>",
            Space::Texels => "",
        }
    }

    fn binding_type(self, min_bytes: u64) -> wgpu::BindingType {
        let ty = match self {
            Space::Uniform | Space::UniformSlots => wgpu::BufferBindingType::Uniform,
            Space::ReadOnly => wgpu::BufferBindingType::Storage { read_only: true },
            Space::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            Space::Texels => return TexelReads::Sampled.binding_type(),
        };
        wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: self == Space::UniformSlots,
            min_binding_size: NonZeroU64::new(min_bytes),
        }
    }
}

/// How a kernel reads its texel tables ([`Space::Texels`]). Both read the same values;
/// they differ in what the driver builds. Each kernel declares the tables as
/// `TexelTable` and reads them with `texel_load` ([`TexelReads::wgsl`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TexelReads {
    /// `texture_2d<u32>`, read with `textureLoad` at level 0: every adapter has it.
    #[default]
    Sampled,
    /// `texture_storage_2d<rgba32uint, read>`: needs wgpu's
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` and read-only storage of rgba32uint
    /// ([`GpuContext::storage_texels`](crate::render::GpuContext::storage_texels)).
    /// llvmpipe builds every sampled texel fetch as a call to one function that takes
    /// the mip level per lane and looks up each lane's row stride and offset; a storage
    /// texture has no levels, and its read is address arithmetic and a load per lane.
    /// The Cornell box renders 1.5× as fast so (docs/BENCHMARKS.md).
    Storage,
}

impl TexelReads {
    /// The WGSL of the `TexelTable` type the tables are declared with and of
    /// `texel_load`, which reads the texel at `at`.
    pub fn wgsl(self) -> &'static str {
        match self {
            TexelReads::Sampled => {
                "alias TexelTable = texture_2d<u32>;\n\
                 fn texel_load(t: TexelTable, at: vec2<u32>) -> vec4<u32> {\n    \
                 return textureLoad(t, at, 0);\n}\n"
            }
            TexelReads::Storage => {
                "alias TexelTable = texture_storage_2d<rgba32uint, read>;\n\
                 fn texel_load(t: TexelTable, at: vec2<u32>) -> vec4<u32> {\n    \
                 return textureLoad(t, at);\n}\n"
            }
        }
    }

    /// The layout's binding type of a texel table read this way.
    pub fn binding_type(self) -> wgpu::BindingType {
        match self {
            TexelReads::Sampled => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            TexelReads::Storage => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::ReadOnly,
                format: wgpu::TextureFormat::Rgba32Uint,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
        }
    }
}

/// How an array of fixed-size elements lies in a [`Space::Texels`] binding: `texels`
/// rgba32uint texels per element, `per_row` elements per row of the texture, so that no
/// element straddles two rows. The rows are 4096 texels wide or less, within every
/// adapter's limit; the rows a table may have are the adapter's
/// `max_texture_dimension_2d`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TexelLayout {
    pub texels: u32,
    pub per_row: u32,
}

impl TexelLayout {
    pub const fn width(self) -> u32 {
        self.texels * self.per_row
    }

    /// Rows holding `count` elements (at least one).
    pub fn rows(self, count: usize) -> u32 {
        (count.div_ceil(self.per_row as usize) as u32).max(1)
    }
}

/// BVH nodes (TLAS and BLAS, [`WideNode`]): 64 bytes, four texels.
pub const NODE_TEXELS: TexelLayout = TexelLayout {
    texels: 4,
    per_row: 1024,
};
/// Triangles: 48 bytes, three texels.
pub const TRIANGLE_TEXELS: TexelLayout = TexelLayout {
    texels: 3,
    per_row: 1365,
};
/// Instances (`GpuInstance`): 144 bytes, nine texels. Traversal reads texels 3–6 of one
/// (the world-to-object rows and the BVH root, `fetch_placement`).
pub const INSTANCE_TEXELS: TexelLayout = TexelLayout {
    texels: 9,
    per_row: 455,
};
/// Vertex attributes: one texel each (see the `vertex_texels` binding).
pub const VERTEX_TEXELS: TexelLayout = TexelLayout {
    texels: 1,
    per_row: 4096,
};
/// A triangle's three global vertex indices and a word of padding: one texel.
pub const TRIANGLE_VERTEX_TEXELS: TexelLayout = TexelLayout {
    texels: 1,
    per_row: 4096,
};

/// Materials (`GpuMaterial`): the packed principled parameters and five texels more.
pub const MATERIAL_TEXELS: TexelLayout = TexelLayout {
    texels: super::principled::PACKED_VEC4S as u32 + 5,
    per_row: 4096 / (super::principled::PACKED_VEC4S as u32 + 5),
};
/// Emissive triangles (`GpuLightTriangle`): four texels.
pub const LIGHT_TRIANGLE_TEXELS: TexelLayout = TexelLayout {
    texels: 4,
    per_row: 1024,
};
/// The light CDF, four floats to a texel.
pub const LIGHT_CDF_TEXELS: TexelLayout = TexelLayout {
    texels: 1,
    per_row: 4096,
};

/// Every texel table's shape, by the names the generated WGSL gives it:
/// `TEXELS_PER_{singular}` and `{plural}_PER_TEXEL_ROW` (shaders/texels.wgsl).
pub const TEXEL_LAYOUTS: [(&str, &str, TexelLayout); 8] = [
    ("NODE", "NODES", NODE_TEXELS),
    ("TRIANGLE", "TRIANGLES", TRIANGLE_TEXELS),
    ("INSTANCE", "INSTANCES", INSTANCE_TEXELS),
    ("VERTEX", "VERTICES", VERTEX_TEXELS),
    (
        "TRIANGLE_VERTEX",
        "TRIANGLE_VERTICES",
        TRIANGLE_VERTEX_TEXELS,
    ),
    ("MATERIAL", "MATERIALS", MATERIAL_TEXELS),
    ("LIGHT_TRIANGLE", "LIGHT_TRIANGLES", LIGHT_TRIANGLE_TEXELS),
    ("LIGHT_CDF", "LIGHT_CDFS", LIGHT_CDF_TEXELS),
];

// The Rust elements uploaded to each table fill its texels exactly.
const _: () = {
    assert!(bytes::<WideNode>() == NODE_TEXELS.texels as u64 * 16);
    assert!(bytes::<GpuTriangle>() == TRIANGLE_TEXELS.texels as u64 * 16);
    assert!(bytes::<GpuInstance>() == INSTANCE_TEXELS.texels as u64 * 16);
    assert!(bytes::<[u32; 4]>() == VERTEX_TEXELS.texels as u64 * 16);
    assert!(bytes::<[u32; 4]>() == TRIANGLE_VERTEX_TEXELS.texels as u64 * 16);
    assert!(bytes::<GpuMaterial>() == MATERIAL_TEXELS.texels as u64 * 16);
    assert!(bytes::<GpuLightTriangle>() == LIGHT_TRIANGLE_TEXELS.texels as u64 * 16);
    assert!(bytes::<[f32; 4]>() == LIGHT_CDF_TEXELS.texels as u64 * 16);
};

/// The buffer a binding holds; `GpuScene::bind_group` names one buffer for each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    Params,
    FilmSum,
    FilmHigh,
    Stats,
    /// The BVH over instances, in texels ([`NODE_TEXELS`]).
    TlasTexels,
    /// The instances in TLAS leaf order, in texels ([`INSTANCE_TEXELS`]).
    Instances,
    /// Page `page` of the BLAS nodes (see [`PAGES`]).
    BlasNodes {
        page: u32,
    },
    /// Page `page` of the triangles.
    Triangles {
        page: u32,
    },
    /// All BLAS nodes in texels, instead of the pages (a scene's `node_pages` is 0).
    NodeTexels,
    /// All triangles in texels, instead of the pages (`triangle_pages` is 0).
    TriangleTexels,
    /// Each triangle's vertex indices, in texels ([`TRIANGLE_VERTEX_TEXELS`]).
    TriangleVertices,
    /// The vertex attributes, in texels ([`VERTEX_TEXELS`]).
    Vertices,
    /// The materials, in texels ([`MATERIAL_TEXELS`]).
    Materials,
    /// The emissive triangles, in texels ([`LIGHT_TRIANGLE_TEXELS`]).
    LightTriangles,
    /// The light CDF, in texels ([`LIGHT_CDF_TEXELS`]).
    LightCdf,
    AnalyticLights,
    EnvironmentData,
    DielectricEnergyTable,
    Textures,
    FilmAov,
    FilmNoise,
    Uv1,
    MaterialParams,
    VolumeGrid,
}

/// One binding of group 0.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub resource: Resource,
    /// The WGSL variable.
    pub name: &'static str,
    pub binding: u32,
    pub space: Space,
    pub wgsl_type: &'static str,
    /// Bytes of one element of the Rust data uploaded to it (of the whole buffer when the
    /// type is not a runtime-sized array): the layout's minimum binding size, and what the
    /// contract test compares with naga's stride of `wgsl_type`.
    pub element_bytes: u64,
    /// The type of a `var<private>` that stands in for the binding in kernels built
    /// without it, so code behind a false `FEATURE_*` constant still names a variable.
    pub stand_in: Option<&'static str>,
    /// A comment written above the declaration.
    pub doc: &'static str,
}

impl Binding {
    /// Whether a kernel with `features` binds this buffer.
    pub fn is_bound(&self, features: &KernelFeatures) -> bool {
        match self.resource {
            Resource::BlasNodes { page } => page < features.node_pages,
            Resource::Triangles { page } => page < features.triangle_pages,
            Resource::NodeTexels => features.node_pages == 0,
            Resource::TriangleTexels => features.triangle_pages == 0,
            Resource::Textures => features.textures,
            Resource::FilmAov => features.aovs,
            Resource::Uv1 => features.uv1,
            Resource::FilmNoise => features.noise,
            Resource::VolumeGrid => features.lobes & super::lobes::HETEROGENEOUS != 0,
            _ => true,
        }
    }
}

/// Pages of the paged arrays (`blas_nodes_*`, `triangles_*`): the two largest arrays are
/// split into up to four bindings, so a scene is not limited by the per-binding size
/// (128 MiB on lavapipe). Pages a scene does not use take no binding slot, which keeps
/// ordinary scenes within GL's 16 storage buffers per stage. A scene whose nodes and
/// triangles fit in one texture each reads them as texels instead, with no page bound
/// (`GpuScene::upload`).
pub const PAGES: usize = 4;

const fn bytes<T>() -> u64 {
    std::mem::size_of::<T>() as u64
}

/// Binding `binding` holding page `page` of the BLAS nodes.
const fn blas_page(name: &'static str, binding: u32, page: u32) -> Binding {
    Binding {
        resource: Resource::BlasNodes { page },
        name,
        binding,
        space: Space::ReadOnly,
        wgsl_type: "array<WideNode>",
        element_bytes: bytes::<WideNode>(),
        stand_in: None,
        doc: "",
    }
}

/// Binding `binding` holding page `page` of the triangles.
const fn triangle_page(name: &'static str, binding: u32, page: u32) -> Binding {
    Binding {
        resource: Resource::Triangles { page },
        name,
        binding,
        space: Space::ReadOnly,
        wgsl_type: "array<Triangle>",
        element_bytes: bytes::<GpuTriangle>(),
        stand_in: None,
        doc: "",
    }
}

/// A read-only storage array that every kernel binds.
const fn read_only(
    resource: Resource,
    name: &'static str,
    binding: u32,
    wgsl_type: &'static str,
    element_bytes: u64,
    doc: &'static str,
) -> Binding {
    Binding {
        resource,
        name,
        binding,
        space: Space::ReadOnly,
        wgsl_type,
        element_bytes,
        stand_in: None,
        doc,
    }
}

/// A texel table ([`Space::Texels`]) holding elements of `element_bytes`.
const fn texels(
    resource: Resource,
    name: &'static str,
    binding: u32,
    element_bytes: u64,
    doc: &'static str,
) -> Binding {
    Binding {
        space: Space::Texels,
        ..read_only(resource, name, binding, "TexelTable", element_bytes, doc)
    }
}

/// The group of the scene's bindings.
pub const SCENE_GROUP: u32 = 0;

/// Group 0: params, film, stats, then the scene, in binding order.
pub const SCENE_BINDINGS: &[Binding] = &[
    Binding {
        resource: Resource::Params,
        name: "params",
        binding: 0,
        space: Space::UniformSlots,
        wgsl_type: "Params",
        element_bytes: bytes::<GpuParams>(),
        stand_in: None,
        doc: "",
    },
    Binding {
        resource: Resource::FilmSum,
        name: "film_sum",
        binding: 1,
        space: Space::ReadWrite,
        wgsl_type: "array<vec4<u32>>",
        element_bytes: bytes::<[u32; 4]>(),
        stand_in: None,
        doc: "",
    },
    Binding {
        resource: Resource::FilmHigh,
        name: "film_high",
        binding: 2,
        space: Space::ReadWrite,
        wgsl_type: "array<vec4<u32>>",
        element_bytes: bytes::<[u32; 4]>(),
        stand_in: None,
        doc: "",
    },
    Binding {
        resource: Resource::Stats,
        name: "stats",
        binding: 3,
        space: Space::ReadWrite,
        wgsl_type: "Stats",
        element_bytes: bytes::<GpuStats>(),
        stand_in: None,
        doc: "",
    },
    texels(
        Resource::TlasTexels,
        "tlas_texels",
        4,
        bytes::<WideNode>(),
        "The BVH over instances and the instances in its leaf order, as texels: read them\n\
         through fetch_tlas_node, fetch_placement and fetch_instance (shaders/texels.wgsl).",
    ),
    texels(
        Resource::Instances,
        "instance_texels",
        5,
        bytes::<GpuInstance>(),
        "",
    ),
    Binding {
        doc: "Page 0 of the paged arrays. Read them through fetch_blas_node and fetch_triangle,\n\
              which kernel assembly generates for the pages a scene uses (src/shader/features.rs,\n\
              `paging_wgsl`).",
        ..blas_page("blas_nodes_0", 6, 0)
    },
    triangle_page("triangles_0", 7, 0),
    texels(
        Resource::TriangleVertices,
        "triangle_vertex_texels",
        8,
        bytes::<[u32; 4]>(),
        "Per triangle, in the same order as the triangles: its three global vertex indices\n\
         (fetch_triangle_vertices).",
    ),
    texels(
        Resource::Vertices,
        "vertex_texels",
        9,
        bytes::<[u32; 4]>(),
        "Per vertex (fetch_vertex): x = octahedral normal (pack2x16snorm), y, z = uv as f32\n\
         bits, w = colour (pack4x8unorm).",
    ),
    texels(
        Resource::Materials,
        "material_texels",
        10,
        bytes::<GpuMaterial>(),
        "The materials (fetch_material), the emissive triangles (fetch_light_triangle) and the\n\
         inclusive prefix sums of their pick probabilities (light_cdf_at, last entry == 1).",
    ),
    texels(
        Resource::LightTriangles,
        "light_triangle_texels",
        11,
        bytes::<GpuLightTriangle>(),
        "",
    ),
    texels(
        Resource::LightCdf,
        "light_cdf_texels",
        12,
        bytes::<[f32; 4]>(),
        "",
    ),
    blas_page("blas_nodes_1", 13, 1),
    blas_page("blas_nodes_2", 14, 2),
    blas_page("blas_nodes_3", 15, 3),
    triangle_page("triangles_1", 16, 1),
    triangle_page("triangles_2", 17, 2),
    triangle_page("triangles_3", 18, 3),
    read_only(
        Resource::AnalyticLights,
        "analytic_lights",
        19,
        "array<AnalyticLight>",
        bytes::<GpuAnalyticLight>(),
        "",
    ),
    read_only(
        Resource::EnvironmentData,
        "env_data",
        20,
        "array<vec4<f32>>",
        bytes::<[f32; 4]>(),
        "The environment map and its sampling CDFs (shaders/lights/environment.wgsl).",
    ),
    Binding {
        resource: Resource::DielectricEnergyTable,
        name: "dielectric_energy_table",
        binding: 21,
        space: Space::Uniform,
        wgsl_type: "array<vec4<f32>, 2048>",
        element_bytes: bytes::<[f32; 8192]>(),
        stand_in: None,
        doc: "The rough dielectric's energy table, 2 × 16³ f32 four to a vec4 (shaders/bsdf/\n\
              dielectric_energy.wgsl).",
    },
    read_only(
        Resource::Textures,
        "texture_data",
        22,
        "array<u32>",
        bytes::<u32>(),
        "The image textures (src/material/texture.rs), when a scene has any.",
    ),
    Binding {
        resource: Resource::FilmAov,
        name: "film_aov",
        binding: 23,
        space: Space::ReadWrite,
        wgsl_type: "array<vec4<f32>>",
        element_bytes: bytes::<[f32; 4]>(),
        stand_in: Some("array<vec4<f32>, 3>"),
        doc: "Per pixel: (albedo sum, depth sum), (normal sum, samples), (sum of the emission seen\n\
              directly, 0); when AOVs are rendered.",
    },
    Binding {
        resource: Resource::Uv1,
        name: "uv1_data",
        binding: 24,
        space: Space::ReadOnly,
        wgsl_type: "array<vec2<f32>>",
        element_bytes: bytes::<[f32; 2]>(),
        stand_in: Some("array<vec2<f32>, 1>"),
        doc: "The second UV set per vertex, when a mesh has one.",
    },
    Binding {
        resource: Resource::MaterialParams,
        name: "material_params",
        binding: 25,
        space: Space::Uniform,
        wgsl_type: "array<vec4<f32>, 2048>",
        element_bytes: bytes::<[[f32; 4]; MATERIAL_PARAMS]>(),
        stand_in: None,
        doc: "The graph materials' constant inputs in the editor (src/material/compile.rs,\n\
              `Constants::Live`); uniform, so it takes none of GL's storage-buffer slots.",
    },
    Binding {
        resource: Resource::VolumeGrid,
        name: "volume_grid",
        binding: 26,
        space: Space::ReadWrite,
        wgsl_type: "array<u32>",
        element_bytes: bytes::<u32>(),
        stand_in: Some("array<u32, 1>"),
        doc: "The heterogeneous volumes baked into grids (src/render/volume_grid.rs), when a scene\n\
              has any: written by bake_volume_grid, read by the path tracer.",
    },
    Binding {
        resource: Resource::FilmNoise,
        name: "film_noise",
        binding: 27,
        space: Space::ReadWrite,
        wgsl_type: "array<vec4<f32>>",
        element_bytes: bytes::<[f32; 4]>(),
        stand_in: Some("array<vec4<f32>, 1>"),
        doc: "Per pixel: the Kahan sum of the squared samples (r + g + b)² and its compensation,\n\
              the noise estimate at the last check, and 1 once adaptive sampling found the pixel\n\
              converged (shaders/integrator/adaptive.wgsl); when the noise is estimated.",
    },
    texels(
        Resource::NodeTexels,
        "blas_nodes_texels",
        28,
        bytes::<WideNode>(),
        "The BLAS nodes and the triangles as texels, when they fit: read them through\n\
         fetch_blas_node and fetch_triangle too.",
    ),
    texels(
        Resource::TriangleTexels,
        "triangles_texels",
        29,
        bytes::<GpuTriangle>(),
        "",
    ),
];

/// Elements of `material_params`: live constants beyond it are compiled inline.
pub const MATERIAL_PARAMS: usize = 2048;

/// The group 0 declarations of a kernel built for `features`.
pub fn bindings_wgsl(features: &KernelFeatures) -> String {
    let mut text = features.texel_reads.wgsl().to_owned();
    for b in SCENE_BINDINGS {
        for line in b.doc.lines() {
            text.push_str(&format!("// {line}\n"));
        }
        if b.is_bound(features) {
            text.push_str(&format!(
                "@group({SCENE_GROUP}) @binding({}) var{} {}: {};\n",
                b.binding,
                b.space.wgsl(),
                b.name,
                b.wgsl_type
            ));
        } else if let Some(ty) = b.stand_in {
            text.push_str(&format!("var<private> {}: {ty};\n", b.name));
        }
    }
    text
}

/// The bindings a kernel built for `features` declares.
pub fn bound(features: &KernelFeatures) -> impl Iterator<Item = &'static Binding> + '_ {
    SCENE_BINDINGS.iter().filter(|b| b.is_bound(features))
}

/// A compute stage's layout entry for a binding in `space`; `min_bytes` 0 for no minimum.
/// A texel table's entry is [`TexelReads::Sampled`]'s; a kernel's group 0 reads them as
/// its features say ([`scene_layout_entries`]).
pub fn layout_entry(binding: u32, space: Space, min_bytes: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: space.binding_type(min_bytes),
        count: None,
    }
}

/// The entries of group 0's layout for a kernel built for `features`.
pub fn scene_layout_entries(features: &KernelFeatures) -> Vec<wgpu::BindGroupLayoutEntry> {
    bound(features)
        .map(|b| match b.space {
            Space::Texels => wgpu::BindGroupLayoutEntry {
                ty: features.texel_reads.binding_type(),
                ..layout_entry(b.binding, b.space, b.element_bytes)
            },
            space => layout_entry(b.binding, space, b.element_bytes),
        })
        .collect()
}

/// One binding of a probe kernel's group 1 (`src/render/probe.rs`); the element types
/// are the probe's own, declared in its WGSL.
#[derive(Clone, Copy, Debug)]
pub struct ProbeBinding {
    pub name: &'static str,
    pub binding: u32,
    pub space: Space,
}

/// The group of a probe's own bindings.
pub const PROBE_GROUP: u32 = 1;

/// A probe's input and output arrays.
pub const PROBE_BINDINGS: [ProbeBinding; 2] = [
    ProbeBinding {
        name: "probe_in",
        binding: 0,
        space: Space::ReadOnly,
    },
    ProbeBinding {
        name: "probe_out",
        binding: 1,
        space: Space::ReadWrite,
    },
];

/// The entries of a probe's group 1 layout.
pub fn probe_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    PROBE_BINDINGS
        .iter()
        .map(|b| layout_entry(b.binding, b.space, 0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_has_unique_bindings_and_names_and_every_page() {
        let mut numbers: Vec<u32> = SCENE_BINDINGS.iter().map(|b| b.binding).collect();
        numbers.sort();
        numbers.dedup();
        assert_eq!(
            numbers.len(),
            SCENE_BINDINGS.len(),
            "a binding number is used twice"
        );
        let mut names: Vec<&str> = SCENE_BINDINGS.iter().map(|b| b.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), SCENE_BINDINGS.len(), "a name is used twice");
        for page in 0..PAGES as u32 {
            for (resource, prefix) in [
                (Resource::BlasNodes { page }, "blas_nodes"),
                (Resource::Triangles { page }, "triangles"),
            ] {
                let b = SCENE_BINDINGS
                    .iter()
                    .find(|b| b.resource == resource)
                    .unwrap_or_else(|| panic!("no binding for {resource:?}"));
                assert_eq!(b.name, format!("{prefix}_{page}"));
            }
        }
    }

    /// Every probe kernel under `shaders/tests/` declares its group 1 as `PROBE_BINDINGS`
    /// says, which is what `run_probe` builds the layout from.
    #[test]
    fn probe_kernels_declare_the_probe_bindings() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/tests");
        let expected: Vec<String> = PROBE_BINDINGS
            .iter()
            .map(|b| {
                format!(
                    "@group({PROBE_GROUP}) @binding({}) var{} {}:",
                    b.binding,
                    b.space.wgsl(),
                    b.name
                )
            })
            .collect();
        let mut probes = 0;
        for entry in std::fs::read_dir(&dir).expect("shaders/tests is readable") {
            let path = entry.expect("a directory entry").path();
            let text = std::fs::read_to_string(&path).expect("a probe kernel is readable");
            let declared: Vec<&str> = text.lines().filter(|l| l.starts_with("@group(")).collect();
            if declared.is_empty() {
                continue; // a library part of other probes (lobe_dispatch.wgsl)
            }
            probes += 1;
            assert_eq!(declared.len(), expected.len(), "{}", path.display());
            for (line, prefix) in declared.iter().zip(&expected) {
                assert!(line.starts_with(prefix), "{}: {line}", path.display());
            }
        }
        assert!(probes >= 8, "found {probes} probe kernels");
    }
}
