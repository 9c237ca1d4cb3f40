//! The shader contract: what the CPU and the kernel agree on, at the bottom of the layers.
//! The WGSL files of `shaders/` ([`LIBRARY`]), the principled lobes' bits ([`lobes`]), what
//! a kernel is specialised for ([`features`]), the principled parameters ([`principled`]),
//! the Rust mirrors of the GPU structs
//! ([`gpu_types`]), the one table of bindings ([`bindings`]) and the view transforms the
//! display pass selects ([`view`]). It uses no other module
//! of the crate; every layer above may use it (`tests/architecture.rs`).

pub mod bindings;
pub mod features;
pub mod gpu_types;
pub mod principled;
pub mod sampling;
pub mod view;

pub use features::{Ablation, KernelFeatures};

/// One WGSL file of `shaders/`, embedded in the binary.
#[derive(Clone, Copy, Debug)]
pub struct ShaderFile {
    pub path: &'static str,
    pub source: &'static str,
}

macro_rules! shader_file {
    ($path:literal) => {
        ShaderFile {
            path: concat!("shaders/", $path),
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $path)),
        }
    };
}

/// The shared kernel code, in the order the files depend on each other.
pub const LIBRARY: &[ShaderFile] = &[
    shader_file!("scene.wgsl"),
    shader_file!("rng.wgsl"),
    shader_file!("sampling.wgsl"),
    shader_file!("float_error.wgsl"),
    shader_file!("intersect.wgsl"),
    shader_file!("texels.wgsl"),
    shader_file!("traverse.wgsl"),
    shader_file!("surface.wgsl"),
    shader_file!("camera.wgsl"),
    shader_file!("bsdf/microfacet.wgsl"),
    shader_file!("bsdf/fresnel.wgsl"),
    shader_file!("bsdf/conductor.wgsl"),
    shader_file!("bsdf/ggx_albedo_table.wgsl"),
    shader_file!("bsdf/multiple_scattering.wgsl"),
    shader_file!("bsdf/dielectric.wgsl"),
    shader_file!("bsdf/dielectric_energy.wgsl"),
    shader_file!("bsdf/lambert.wgsl"),
    shader_file!("bsdf/diffuse_albedo_table.wgsl"),
    shader_file!("bsdf/sheen_table.wgsl"),
    shader_file!("bsdf/sheen.wgsl"),
    shader_file!("media/phase.wgsl"),
    shader_file!("media/subsurface.wgsl"),
    shader_file!("bsdf/principled.wgsl"),
    shader_file!("lights/emissive_triangle.wgsl"),
    shader_file!("lights/environment.wgsl"),
    shader_file!("lights/analytic.wgsl"),
    shader_file!("lights/selection.wgsl"),
];

/// The path-tracing entry point `render` and the media it tracks.
pub const PATH_INTEGRATOR: &[ShaderFile] = &[
    shader_file!("integrator/media.wgsl"),
    shader_file!("integrator/path.wgsl"),
];

/// The entry point `bake_volume_grid`, which bakes heterogeneous volumes into grids
/// (`src/render/volume_grid.rs`): after the integrator, in kernels for scenes with one.
pub const VOLUME_BAKE: ShaderFile = shader_file!("integrator/volume_bake.wgsl");

/// The denoiser's entry point `atrous` (`src/render/denoise.rs`), a module of its own.
pub const DENOISE: ShaderFile = shader_file!("denoise/atrous.wgsl");

/// Adaptive sampling's entry points, compiled into the path tracer's module when it
/// estimates the noise ([`KernelFeatures::noise`]).
pub const ADAPTIVE: ShaderFile = shader_file!("integrator/adaptive.wgsl");

/// The principled surface's lobes, one bit each, as [`KernelFeatures::lobes`] counts them.
pub mod lobes {
    pub const COAT: u32 = 1;
    pub const SHEEN: u32 = 2;
    /// The metal and its multiple-scattering compensation.
    pub const METAL: u32 = 4;
    pub const GLASS: u32 = 8;
    pub const SPECULAR: u32 = 16;
    pub const DIFFUSE: u32 = 32;
    /// The random walk under the surface (`shaders/media/subsurface.wgsl`).
    pub const SUBSURFACE: u32 = 64;
    /// Not a lobe of the surface: a volume inside it (`shaders/nodes/volume.wgsl`), which
    /// the kernel specialises on like a lobe.
    pub const VOLUME: u32 = 128;
    /// A volume whose coefficients vary inside: delta and ratio tracking, and the
    /// volume functions of the material graphs (`evaluate_volume`).
    pub const HETEROGENEOUS: u32 = 256;
    /// What a volume adds to a kernel.
    pub const VOLUMES: u32 = VOLUME | HETEROGENEOUS;
    /// Diffuse transmission through a thin wall: the subsurface of a thin-walled surface.
    pub const TRANSLUCENT: u32 = 512;
    /// Not a lobe either: an alpha below 1 somewhere (cut-outs the path passes through).
    pub const CUTOUT: u32 = 1024;
    pub const ALL: u32 = (CUTOUT << 1) - 1;
    /// What the unspecialised kernels take from the scene rather than always compile in
    /// ([`super::KernelFeatures::everything`]): volumes make their build on lavapipe
    /// several times longer, and cut-outs make every shadow ray evaluate the material it
    /// meets (the interpreted kernel ran the Cornell box 1.4–1.9× slower with them). A scene gains them with a kernel
    /// build.
    pub const FROM_SCENE: u32 = VOLUMES | CUTOUT;
    pub const NAMES: [(u32, &str); 11] = [
        (COAT, "COAT"),
        (SHEEN, "SHEEN"),
        (METAL, "METAL"),
        (GLASS, "GLASS"),
        (SPECULAR, "SPECULAR"),
        (DIFFUSE, "DIFFUSE"),
        (SUBSURFACE, "SUBSURFACE"),
        (VOLUME, "VOLUME"),
        (HETEROGENEOUS, "HETEROGENEOUS"),
        (TRANSLUCENT, "TRANSLUCENT"),
        (CUTOUT, "CUTOUT"),
    ];
}
