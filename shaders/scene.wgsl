// Scene data as the kernel sees it: the types and bindings of group 0.
// The Rust mirror of every struct here is in src/render/gpu_types.rs; keep the two in step.

const PI: f32 = 3.14159265358979323846;
const INV_PI: f32 = 0.31830988618379067154;
const INV_4PI: f32 = 0.07957747154594766788;

// Params.flags
const FLAG_LIGHT_SAMPLING: u32 = 1u;
const FLAG_ENVIRONMENT_MAP: u32 = 2u;

struct Params {
    film_size: vec2<u32>,
    tile_origin: vec2<u32>,
    tile_size: vec2<u32>,
    sample_start: u32,
    sample_count: u32,
    seed: u32,
    max_bounces: u32,
    flags: u32,
    light_count: u32,
    instance_count: u32,
    // Always 1.0. Multiplying by a value the compiler cannot see keeps it from
    // simplifying Kahan summation's (sum + y) - sum to y (Mesa does, under SPIR-V's
    // default float semantics), which would silently turn it into plain summation.
    opaque_one: f32,
    // Elements per page of the paged arrays below, as powers of two.
    triangle_page_shift: u32,
    node_page_shift: u32,
    // Camera: position, orthonormal frame, and the thin lens (aperture 0 = pinhole).
    cam_position: vec4<f32>,
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    cam_forward: vec4<f32>,
    // x: tan(fov_y / 2), y: aspect (w / h), z: aperture radius, w: focus distance
    cam_lens: vec4<f32>,
    // rgb: uniform environment radiance; w: probability of picking the environment in NEE
    environment: vec4<f32>,
    // x: total power of emissive triangles (sum of luminance * area); y: probability of
    // picking an emissive triangle in NEE; z: number of analytic lights.
    light_totals: vec4<f32>,
};

// A BVH node. Inner nodes (count == 0) have their children at `first` and `first + 1`;
// leaves hold `count` primitives starting at `first`.
struct BvhNode {
    min: vec3<f32>,
    first: u32,
    max: vec3<f32>,
    count: u32,
};

// The three vertices of a triangle in object space, in BVH leaf order.
struct Triangle {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
};

struct Instance {
    // Rows of the 3x4 object-to-world and world-to-object matrices.
    to_world: array<vec4<f32>, 3>,
    to_object: array<vec4<f32>, 3>,
    blas_root: u32,
    material: u32,
    flags: u32,
    _pad: u32,
};

// Instance.flags
const INSTANCE_HAS_NORMALS: u32 = 1u;
const INSTANCE_HAS_UVS: u32 = 2u;
const INSTANCE_HAS_UV1: u32 = 4u;

// A principled material: the seven vec4s of `principled_unpack`, emission (+ opacity in
// w), and flags (x: thin-walled, y: transmissive, z: diffuse roughness and w: anisotropy
// rotation in turns, as f32 bits).
struct Material {
    principled: array<vec4<f32>, 7>,
    emission: vec4<f32>,
    flags: vec4<u32>,
};

// An emissive triangle in world space, for next-event estimation.
struct LightTriangle {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    // rgb: emitted radiance; w: probability of picking this triangle among the triangles.
    emission: vec4<f32>,
};

// A point, spot or distant light (src/scene/light.rs).
struct AnalyticLight {
    // xyz: position (point, spot) or the direction light travels (distant); w: kind
    // (0 point, 1 spot, 2 distant).
    position: vec4<f32>,
    // xyz: spot axis (unit); w: sphere radius, or for distant lights 1 - cos of the disk's
    // angular radius.
    axis: vec4<f32>,
    // rgb: intensity (point, spot) or irradiance (distant); w: pick probability.
    intensity: vec4<f32>,
    // x, y: cosines of the spot's outer and inner cone; w: cumulative pick probability,
    // counted after the environment and the emissive triangles.
    shape: vec4<f32>,
};

struct Stats {
    rays: atomic<u32>,
    non_finite: atomic<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> film_sum: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> film_compensation: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> stats: Stats;
@group(0) @binding(4) var<storage, read> tlas_nodes: array<BvhNode>;
@group(0) @binding(5) var<storage, read> instances: array<Instance>;
// The two largest arrays are split into up to four pages, each its own binding, so a
// scene is not limited by the per-binding size (128 MiB on lavapipe). Read them through
// fetch_blas_node and fetch_triangle, which kernel assembly generates together with the
// bindings of pages 1 to 3 (13-15 and 16-18) for the pages the scene uses
// (src/render/kernel.rs, `paging_wgsl`): unused pages take no binding slot, which keeps
// ordinary scenes within GL's 16 storage buffers per stage.
@group(0) @binding(6) var<storage, read> blas_nodes_0: array<BvhNode>;
@group(0) @binding(7) var<storage, read> triangles_0: array<Triangle>;
// Three global vertex indices per triangle, in the same order as `triangles`.
@group(0) @binding(8) var<storage, read> triangle_vertices: array<u32>;
// Per vertex: x = octahedral normal (pack2x16snorm), y, z = uv as f32 bits, w = colour
// (pack4x8unorm).
@group(0) @binding(9) var<storage, read> vertices: array<vec4<u32>>;
@group(0) @binding(10) var<storage, read> materials: array<Material>;
@group(0) @binding(11) var<storage, read> light_triangles: array<LightTriangle>;
// Inclusive prefix sums of the light triangles' pick probabilities (last entry == 1).
@group(0) @binding(12) var<storage, read> light_cdf: array<f32>;
@group(0) @binding(19) var<storage, read> analytic_lights: array<AnalyticLight>;
// The environment map and its sampling CDFs (shaders/lights/environment.wgsl).
@group(0) @binding(20) var<storage, read> env_data: array<vec4<f32>>;
// The rough dielectric's energy table, 2 × 16³ f32 four to a vec4 (shaders/bsdf/
// dielectric_energy.wgsl).
@group(0) @binding(21) var<uniform> dielectric_energy_table: array<vec4<f32>, 2048>;
