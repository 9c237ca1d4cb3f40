// Scene data as the kernel sees it: the types of group 0's bindings. The Rust mirror of
// every struct and constant here is in src/render/gpu_types.rs (a test compares them with
// naga's layout); the bindings themselves are declared by kernel assembly from the table
// in src/render/bindings.rs.

const PI: f32 = 3.14159265358979323846;
const INV_PI: f32 = 0.31830988618379067154;
const INV_4PI: f32 = 0.07957747154594766788;

// Params.flags
const FLAG_LIGHT_SAMPLING: u32 = 1u;
const FLAG_ENVIRONMENT_MAP: u32 = 2u;
const FLAG_SHADOW_CATCHER: u32 = 4u;

// Params.sampler (shaders/rng.wgsl)
const SAMPLER_INDEPENDENT: u32 = 0u;
const SAMPLER_SOBOL: u32 = 1u;

struct Params {
    film_size: vec2<u32>,
    tile_origin: vec2<u32>,
    tile_size: vec2<u32>,
    // The one sample a dispatch adds to each pixel of its tile.
    sample_index: u32,
    // Keeps the camera's vectors 16-byte aligned.
    padding: u32,
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
    // among the lights at infinity
    environment: vec4<f32>,
    // Total power of the emissive triangles (sum of luminance * area).
    light_power: f32,
    // Probability of picking an emissive triangle in NEE among the local lights.
    triangle_pick: f32,
    analytic_light_count: u32,
    // Index of the first pixel of the film piece bound to this dispatch: the film is split
    // into bands of rows that each fit one binding (src/render/film_pieces.rs).
    film_piece_start: u32,
    // The instances the camera is inside whose insides hold media (volumes, glass),
    // outermost first: the media paths start in (src/accel/query.rs finds them).
    camera_media: vec4<u32>,
    camera_media_count: u32,
    // Volume scattering events per path; past them media only absorb (their whole
    // extinction), as Cycles' Light Paths ▸ Volume.
    max_volume_bounces: u32,
    // SAMPLER_INDEPENDENT or SAMPLER_SOBOL (shaders/rng.wgsl).
    sampler: u32,
    // A bake dispatch's grid (the word its header starts at) and first voxel
    // (shaders/integrator/volume_bake.wgsl); unused by the path tracer.
    bake_grid: u32,
    bake_first: u32,
    // The firefly clamp: the most a sample's direct (scattered at most once) and indirect
    // light may add, per contribution; 0 for no limit.
    clamp_direct: f32,
    clamp_indirect: f32,
    noise_threshold: f32,
    // Where next-event estimation splits its samples between the lights at infinity (the
    // environment, distant lights) and the local ones (infinite_light_pick): x the
    // irradiance at infinity, y the local lights' summed intensity (luminance); the local
    // lights' bounding sphere (centre, squared radius).
    light_split: vec4<f32>,
    local_lights: vec4<f32>,
    // The pixel filter's quantile function at FILTER_TABLE_SIZE evenly spaced
    // probabilities, in pixels, four to a vector (shaders/sampling.wgsl).
    filter_quantiles: array<vec4<f32>, 32>,
};

const FILTER_TABLE_SIZE: u32 = 128u;

// A node of a four-wide BVH (src/accel/wide.rs, WideNode in src/shader/gpu_types.rs): its
// children's boxes in bytes of steps from `origin` (exponents: per axis the step's exponent
// biased by 127, a byte each; steps: lo x, y, z, hi x, then hi y, z, a byte per child), and
// per child a leaf (its primitive count shifted by WIDE_COUNT_SHIFT over its first
// primitive), an inner node's index (count 0), or WIDE_EMPTY. wide_boxes decodes them.
struct WideNode {
    origin: vec3<f32>,
    exponents: u32,
    child: vec4<u32>,
    steps: array<vec4<u32>, 2>,
};

const WIDE_COUNT_SHIFT: u32 = 28u;
const WIDE_EMPTY: u32 = 0xffffffffu;

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
    // Where traversal enters its mesh's BVH: the root node, or the root's only child when
    // that is a leaf.
    blas_root: u32,
    material: u32,
    flags: u32,
    // The word of `volume_grid` its heterogeneous volume's grid starts at, or NO_GRID
    // (src/render/volume_grid.rs).
    volume_grid: u32,
    // Its mesh's bounds in object space (w unused).
    mesh_min: vec4<f32>,
    mesh_max: vec4<f32>,
};

const NO_GRID: u32 = 0xffffffffu;

// Instance.flags
const INSTANCE_HAS_NORMALS: u32 = 1u;
const INSTANCE_HAS_UVS: u32 = 2u;
const INSTANCE_HAS_UV1: u32 = 4u;
const INSTANCE_SHADOW_CATCHER: u32 = 8u;

// A fixed-parameter material: the principled parameters packed as `principled_unpack`
// reads them (generated from src/shader/principled.rs, like PRINCIPLED_VEC4S).
struct Material {
    principled: array<vec4<f32>, PRINCIPLED_VEC4S>,
    // rgb: the emitted radiance light sampling knows in advance (0 where a graph varies it).
    emission: vec4<f32>,
    // 1 if light passes through: the surface keeps its geometric orientation.
    transmissive: u32,
    // 1 for a volume's boundary without a surface: light crosses it unchanged.
    boundary_only: u32,
    // A heterogeneous volume inside: the extinction per unit length no point of it
    // exceeds (its coefficients come from `evaluate_volume`); 0 for a homogeneous one.
    volume_majorant: f32,
    // 1 if its alpha can be below 1 somewhere: shadow rays evaluate its opacity.
    cutout: u32,
    // The homogeneous volume inside: absorption per unit length (w: the phase function's
    // g), scattering, emission per unit length; zero without one.
    volume_absorption: vec4<f32>,
    volume_scattering: vec4<f32>,
    volume_emission: vec4<f32>,
};

// An emissive triangle in world space, for next-event estimation.
struct LightTriangle {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    // rgb: emitted radiance; w: probability of picking this triangle among the triangles.
    emission: vec4<f32>,
};

// AnalyticLight.kind
const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DISTANT: u32 = 2u;

// A point, spot or distant light (src/scene/light.rs).
struct AnalyticLight {
    // Position (point, spot) or the direction light travels (distant).
    position: vec3<f32>,
    // LIGHT_POINT, LIGHT_SPOT or LIGHT_DISTANT.
    kind: u32,
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
    active_pixels: atomic<u32>,
    skipped_samples: atomic<u32>,
};
