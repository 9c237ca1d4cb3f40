//! The scene model: meshes, instances, materials, camera and environment, resolved and
//! validated, independent of any file format or GPU layout.
//!
//! A [`Scene`] is what every importer produces and what the renderer consumes. It is
//! deliberately plain data: the `.kiln` file format lives in [`file`](mod@file) (its
//! schema, loading, saving and OBJ mesh files in modules of their own), generated shapes
//! in [`shapes`], and nothing here knows about BVHs or buffers.

mod camera;
mod environment;
pub mod file;
mod light;
mod load;
pub mod lookdev;
mod material;
mod mesh;
mod obj;
mod save;
mod schema;
pub mod shapes;
mod world;

pub use camera::Camera;
pub use environment::EnvironmentMap;
pub use file::{SCENE_FORMAT_VERSION, SceneError, load_scene, parse_scene, save_scene};
pub use light::{Light, LightObject};
pub use material::{GraphMaterial, Material, graph_from_principled};
pub use mesh::Mesh;
pub use world::{DEFAULT_WORLD_RESOLUTION, SKY_TEXTURE, Sun, WORLD_RESOLUTIONS, World};

use std::path::Path;

use glam::{Affine3A, Vec3};

use crate::shader::sampling::Sampling;
use crate::shader::view::ViewSettings;

/// Where the bundled default scene lives in the source tree.
pub const DEFAULT_SCENE_PATH: &str = "assets/scenes/cornell-box.kiln";
const DEFAULT_SCENE_SOURCE: &str = include_str!("../../assets/scenes/cornell-box.kiln");

/// The bundled Cornell box, embedded in the binary so `kiln render` works from any folder.
pub fn default_scene() -> Result<Scene, SceneError> {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    parse_scene(DEFAULT_SCENE_SOURCE, Path::new(DEFAULT_SCENE_PATH), &base)
}

/// One placement of a mesh in the world. Many instances may share a mesh, which is
/// stored and uploaded once.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
    pub transform: Affine3A,
    /// The object's name (Blender's object name); empty when the file gave none.
    pub name: String,
    /// Hidden objects stay in the scene and its file but are not rendered
    /// ([`Scene::without_hidden`]).
    pub visible: bool,
    /// A shadow catcher (Cycles' object property): the camera sees only the shadows
    /// objects cast on it, as alpha, and a transparent background beside it; to every
    /// other ray it is the surface its material makes (`lookdev::Ground::Catcher`).
    pub shadow_catcher: bool,
}

/// A bounce limit no path reaches (the most the editor offers, as Cycles): Russian
/// roulette alone ends paths. The default path length: `kiln bench --depth` measured
/// unbounded depth within 5% of the time of 8 bounces, which lose 0.4% of the Cornell
/// box's red (docs/BENCHMARKS.md).
pub const UNLIMITED_BOUNCES: u32 = 1024;

/// The default volume bounce limit: as many as the path's bounces allow.
pub const UNLIMITED_VOLUME_BOUNCES: u32 = UNLIMITED_BOUNCES;

/// The default resolution of a heterogeneous volume's grid, and the range offered.
pub const DEFAULT_VOLUME_RESOLUTION: u32 = 128;
pub const VOLUME_RESOLUTIONS: std::ops::RangeInclusive<u32> = 8..=1024;

/// Render settings a scene file carries as defaults; the command line overrides them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSettings {
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub max_bounces: u32,
    /// Scattering events in volumes per path (they count against `max_bounces` too);
    /// past them media only absorb, as Cycles' Light Paths ▸ Volume. The default,
    /// [`UNLIMITED_VOLUME_BOUNCES`], leaves `max_bounces` the only limit.
    pub max_volume_bounces: u32,
    /// Seed of the random sequence: the same seed renders the same image.
    pub seed: u32,
    /// The sampler and the pixel filter.
    pub sampling: Sampling,
    /// Grid points along the longest side of a heterogeneous volume's bounds: such a
    /// volume's graph is baked into a grid of this resolution (`render::volume_grid`).
    pub volume_resolution: u32,
    /// The firefly clamp; off by default.
    pub clamp: Clamp,
    /// Adaptive sampling's noise threshold (Cycles' Sampling ▸ Noise Threshold): a pixel
    /// whose estimated noise falls below it takes no more samples
    /// (`shaders/integrator/adaptive.wgsl` defines the estimate); 0, the default, is off.
    /// Final renders only: the editor's viewport samples every pixel.
    pub noise_threshold: f32,
    /// The denoiser a final render's image goes through; none by default.
    pub denoiser: Denoiser,
    /// Exposure and view transform (Blender's colour management).
    pub view: ViewSettings,
}

/// The firefly clamp (Cycles' Light Paths ▸ Clamping): the most one sample's direct light
/// (scattered at most once on its way to the camera) and indirect light may add to a
/// pixel, each contribution scaled down with its colour kept. It trades bias for noise:
/// the highlights and caustics it cuts come out darker (`kiln bench --clamp` measures
/// both). 0 turns a limit off, the default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clamp {
    pub direct: f32,
    pub indirect: f32,
}

impl Clamp {
    pub fn validate(&self) -> Result<(), String> {
        for (name, limit) in [("direct", self.direct), ("indirect", self.indirect)] {
            if !(limit.is_finite() && limit >= 0.0) {
                return Err(format!(
                    "the {name} clamp must be a finite value of 0 (off) or more, got {limit}"
                ));
            }
        }
        Ok(())
    }
}

impl Default for SceneSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            samples_per_pixel: 64,
            max_bounces: UNLIMITED_BOUNCES,
            max_volume_bounces: UNLIMITED_VOLUME_BOUNCES,
            seed: 0,
            sampling: Sampling::default(),
            volume_resolution: DEFAULT_VOLUME_RESOLUTION,
            clamp: Clamp::default(),
            noise_threshold: 0.0,
            denoiser: Denoiser::None,
            view: ViewSettings::default(),
        }
    }
}

impl SceneSettings {
    pub fn validate(&self) -> Result<(), String> {
        validate_image_size(self.width, self.height)?;
        if self.samples_per_pixel == 0 {
            return Err("samples per pixel must be at least 1".into());
        }
        self.sampling.filter.validate()?;
        validate_volume_resolution(self.volume_resolution)?;
        self.clamp.validate()?;
        validate_noise_threshold(self.noise_threshold)?;
        self.view.validate()
    }
}

/// What a final render's image goes through before it is written (Cycles' Denoise).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Denoiser {
    /// The image as rendered.
    #[default]
    None,
    /// An edge-avoiding à-trous wavelet filter guided by the albedo, normal and depth AOVs
    /// and by each pixel's noise, on the GPU (`shaders/denoise/atrous.wgsl`).
    Atrous,
    /// Intel Open Image Denoise's ray-tracing filter (a neural network, on the CPU),
    /// guided by the albedo and normal AOVs: in builds with the `oidn` feature only
    /// ([`Denoiser::unavailable`]).
    Oidn,
}

impl Denoiser {
    pub const ALL: [Denoiser; 3] = [Denoiser::None, Denoiser::Atrous, Denoiser::Oidn];

    /// The name in scene files and on the command line (`--denoise`).
    pub fn key(self) -> &'static str {
        match self {
            Denoiser::None => "none",
            Denoiser::Atrous => "atrous",
            Denoiser::Oidn => "oidn",
        }
    }

    /// The name the editor shows.
    pub fn label(self) -> &'static str {
        match self {
            Denoiser::None => "None",
            Denoiser::Atrous => "À-trous (albedo, normal, depth)",
            Denoiser::Oidn => "Open Image Denoise (albedo, normal)",
        }
    }

    /// Why this build of Kiln cannot run the denoiser, if it cannot: Open Image Denoise
    /// is a system library that Kiln links only when built with `--features oidn` (and
    /// `OIDN_DIR` naming an OIDN 1.4 install; the README says where one comes
    /// from). A scene asking for it still loads and saves unchanged.
    pub fn unavailable(self) -> Option<&'static str> {
        match self {
            Denoiser::Oidn if !cfg!(feature = "oidn") => Some(
                "this build of Kiln has no Intel Open Image Denoise: build it with \
                 `--features oidn` and OIDN_DIR set to an OIDN 1.4 install (README), or \
                 use the à-trous denoiser",
            ),
            _ => None,
        }
    }
}

/// Render quality presets (`kiln render --quality`), each a set of render settings chosen
/// from measurements on this project's scenes (docs/BENCHMARKS.md: `kiln bench --depth`,
/// `--clamp` and `--tradeoff`), not guessed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// Seconds on a laptop: few samples, denoised.
    Draft,
    /// A faithful look in a minute: more samples and bounces, denoised.
    Preview,
    /// Unbiased: every bounce, no clamp, no denoiser; adaptive sampling stops the pixels
    /// that converged.
    Final,
}

/// What a [`Quality`] preset sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QualitySettings {
    pub samples_per_pixel: u32,
    pub max_bounces: u32,
    pub clamp: Clamp,
    pub noise_threshold: f32,
    pub denoiser: Denoiser,
}

impl Quality {
    pub const ALL: [Quality; 3] = [Quality::Draft, Quality::Preview, Quality::Final];

    /// The name on the command line.
    pub fn key(self) -> &'static str {
        match self {
            Quality::Draft => "draft",
            Quality::Preview => "preview",
            Quality::Final => "final",
        }
    }

    /// The settings the preset sets, and why (measured on lavapipe, docs/BENCHMARKS.md).
    pub fn settings(self) -> QualitySettings {
        match self {
            // 4 bounces lose 3.9 % of the Cornell box's light in 0.83 × the time;
            // the indirect clamp at 10 takes the showcase's error to 0.64 × for 1–2 % of
            // its light; denoising gives 0.57 × the relMSE at 0.5 s, where adaptive
            // sampling (first checked at 16 spp) only costs.
            Quality::Draft => QualitySettings {
                samples_per_pixel: 16,
                max_bounces: 4,
                clamp: Clamp {
                    direct: 0.0,
                    indirect: 10.0,
                },
                noise_threshold: 0.0,
                denoiser: Denoiser::Atrous,
            },
            // 8 bounces lose 0.4 % in 0.93 × the time; denoising at ~40 spp gives
            // 0.44 × the relMSE.
            Quality::Preview => QualitySettings {
                samples_per_pixel: 64,
                max_bounces: 8,
                clamp: Clamp {
                    direct: 0.0,
                    indirect: 10.0,
                },
                noise_threshold: 0.0,
                denoiser: Denoiser::Atrous,
            },
            // At a few hundred spp the denoiser's gain (0.93 ×) is not worth its bias;
            // adaptive sampling at 0.02 gives 0.89–0.94 × the relMSE at equal time.
            Quality::Final => QualitySettings {
                samples_per_pixel: 1024,
                max_bounces: UNLIMITED_BOUNCES,
                clamp: Clamp::default(),
                noise_threshold: 0.02,
                denoiser: Denoiser::None,
            },
        }
    }

    /// The preset `settings` hold, if any.
    pub fn of(settings: &SceneSettings) -> Option<Quality> {
        Quality::ALL.into_iter().find(|q| {
            let mut applied = *settings;
            q.apply(&mut applied);
            applied == *settings
        })
    }

    /// The name the editor shows.
    pub fn label(self) -> &'static str {
        match self {
            Quality::Draft => "Draft",
            Quality::Preview => "Preview",
            Quality::Final => "Final",
        }
    }

    /// Sets the preset's settings in `settings`.
    pub fn apply(self, settings: &mut SceneSettings) {
        let q = self.settings();
        settings.samples_per_pixel = q.samples_per_pixel;
        settings.max_bounces = q.max_bounces;
        settings.clamp = q.clamp;
        settings.noise_threshold = q.noise_threshold;
        settings.denoiser = q.denoiser;
    }

    /// One line saying what the preset sets, for `--help`.
    pub fn describe(self) -> String {
        let q = self.settings();
        let bounces = if q.max_bounces >= UNLIMITED_BOUNCES {
            "unbounded".to_owned()
        } else {
            q.max_bounces.to_string()
        };
        let off = |v: f32| {
            if v == 0.0 {
                "off".to_owned()
            } else {
                v.to_string()
            }
        };
        format!(
            "{}: {} spp, max bounces {bounces}, clamp indirect {}, noise threshold {}, denoise {}",
            self.key(),
            q.samples_per_pixel,
            off(q.clamp.indirect),
            off(q.noise_threshold),
            q.denoiser.key()
        )
    }
}

/// A noise threshold: 0 (off) or a finite number above 0.
pub fn validate_noise_threshold(threshold: f32) -> Result<(), String> {
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(format!(
            "the noise threshold must be 0 (off) or a finite number above 0, such as 0.01; got {threshold}"
        ));
    }
    Ok(())
}

/// A heterogeneous volume's grid resolution within [`VOLUME_RESOLUTIONS`].
pub fn validate_volume_resolution(resolution: u32) -> Result<(), String> {
    if !VOLUME_RESOLUTIONS.contains(&resolution) {
        return Err(format!(
            "the volume resolution must be from {} to {} grid points, got {resolution}",
            VOLUME_RESOLUTIONS.start(),
            VOLUME_RESOLUTIONS.end()
        ));
    }
    Ok(())
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub camera: Camera,
    /// Radiance arriving from every direction no geometry covers (linear RGB).
    pub environment: Vec3,
    /// Replaces the uniform `environment` when present.
    pub environment_map: Option<EnvironmentMap>,
    /// A node graph for the environment; replaces `environment` and `environment_map`
    /// when present (the renderer bakes it into a map, `render::world_bake`).
    pub world: Option<World>,
    pub materials: Vec<Material>,
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
    /// Lights other than emissive geometry.
    pub lights: Vec<LightObject>,
    pub settings: SceneSettings,
}

impl Scene {
    /// A scene with nothing but a camera and a black environment.
    pub fn empty(camera: Camera) -> Self {
        Self {
            camera,
            environment: Vec3::ZERO,
            environment_map: None,
            world: None,
            materials: Vec::new(),
            meshes: Vec::new(),
            instances: Vec::new(),
            lights: Vec::new(),
            settings: SceneSettings::default(),
        }
    }

    pub fn add_material(&mut self, material: Material) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    pub fn add_mesh(&mut self, mesh: Mesh) -> usize {
        self.meshes.push(mesh);
        self.meshes.len() - 1
    }

    pub fn add_instance(&mut self, mesh: usize, material: usize, transform: Affine3A) {
        self.instances.push(Instance {
            mesh,
            material,
            transform,
            name: String::new(),
            visible: true,
            shadow_catcher: false,
        });
    }

    pub fn add_light(&mut self, light: Light) -> usize {
        self.lights.push(light.into());
        self.lights.len() - 1
    }

    /// The bounds (lowest, highest corner) of every instance, in world space; `None` for
    /// a scene without geometry.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for instance in &self.instances {
            for p in &self.meshes[instance.mesh].positions {
                let w = instance.transform.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    /// The scene as rendered: hidden objects and lights left out.
    pub fn without_hidden(&self) -> Scene {
        let mut scene = self.clone();
        scene.instances.retain(|i| i.visible);
        scene.lights.retain(|l| l.visible);
        scene
    }

    pub fn triangle_count(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh].indices.len() as u64)
            .sum()
    }

    /// Returns this scene with every length multiplied by `factor`: geometry, instance
    /// placements and camera. Radiance is unchanged, so the image should be too.
    pub fn scaled(&self, factor: f32) -> Self {
        let mut scene = self.clone();
        let scale = Affine3A::from_scale(Vec3::splat(factor));
        for instance in &mut scene.instances {
            instance.transform = scale * instance.transform;
        }
        scene.camera.position *= factor;
        scene.camera.look_at *= factor;
        scene.camera.focus_distance *= factor;
        scene.camera.aperture_radius *= factor;
        for object in &mut scene.lights {
            match &mut object.light {
                // Intensity is per steradian: at a distance scaled by f, irradiance falls
                // by f²; scale intensity by f² to keep the image.
                Light::Point {
                    position,
                    intensity,
                    radius,
                }
                | Light::Spot {
                    position,
                    intensity,
                    radius,
                    ..
                } => {
                    *position *= factor;
                    *intensity *= factor * factor;
                    *radius *= factor;
                }
                Light::Distant { .. } => {}
            }
        }
        scene
    }

    /// Checks every invariant the renderer relies on; the message names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        self.camera.validate()?;
        if !self.environment.is_finite() || self.environment.min_element() < 0.0 {
            return Err(format!(
                "environment radiance {} must be finite and non-negative",
                self.environment
            ));
        }
        if let Some(map) = &self.environment_map {
            map.validate()?;
        }
        if let Some(world) = &self.world {
            world.validate()?;
        }
        for m in &self.materials {
            m.validate()
                .map_err(|e| format!("material \"{}\": {e}", m.name))?;
        }
        for (i, object) in self.lights.iter().enumerate() {
            object
                .light
                .validate()
                .map_err(|e| format!("light {i}: {e}"))?;
        }
        for mesh in &self.meshes {
            mesh.validate()
                .map_err(|e| format!("mesh \"{}\": {e}", mesh.name))?;
        }
        for (i, inst) in self.instances.iter().enumerate() {
            if inst.mesh >= self.meshes.len() {
                return Err(format!(
                    "instance {i}: mesh index {} out of range",
                    inst.mesh
                ));
            }
            if inst.material >= self.materials.len() {
                return Err(format!(
                    "instance {i}: material index {} out of range",
                    inst.material
                ));
            }
            let det = inst.transform.matrix3.determinant();
            if !inst.transform.matrix3.is_finite()
                || !inst.transform.translation.is_finite()
                || det == 0.0
                || !det.is_finite()
            {
                return Err(format!(
                    "instance {i} (mesh \"{}\"): transform is not invertible",
                    self.meshes[inst.mesh].name
                ));
            }
        }
        self.settings.validate()
    }
}

/// Image sizes the renderer accepts.
pub fn validate_image_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(format!(
            "image size {width}x{height} must be between 1x1 and 16384x16384"
        ));
    }
    Ok(())
}
