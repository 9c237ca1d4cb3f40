//! Edits applied to a built [`Renderer`] in place: what a scene edit needs written, and
//! only that. A transform edit rebuilds the top-level BVH and writes the instances (and
//! the lights, whose world-space triangles and selection follow the instances); a light or
//! material-parameter edit writes those buffers and recomputes the light distribution.
//! None of them builds a mesh BVH or a kernel.
//!
//! An edit that cannot be written in place — a mesh changed, a buffer would have to grow,
//! the kernel would need other features or other material code — is refused with
//! [`UpdateError::NeedsRebuild`] saying why, and the renderer is left as it was; the
//! caller builds a new renderer (`Renderer::new`), whose kernel comes from the device's
//! pipeline cache unless its contents changed. Whatever the edit, clear the film
//! ([`Renderer::clear_film`]) before rendering again.
//!
//! An updated renderer renders the same film, bit for bit, as one built afresh for the
//! edited scene: both pack the same arrays with the same code (`gpu_scene.rs`), and
//! `tests/incremental.rs` checks it.

use thiserror::Error;

use std::borrow::Cow;

use super::gpu_scene::{
    LightArrays, in_fours, instance_arrays, instanced_lobes, light_arrays, write_grid_headers,
    write_texels,
};
use super::materials::SceneMaterials;
use super::renderer::{RenderError, RenderSettings, Renderer, kernel_features};
use super::volume_grid::{VolumeGrids, kernel_indices};
use crate::accel::{Bvh, build_tlas};
use crate::scene::Scene;
use crate::shader::KernelFeatures;
use crate::shader::bindings::{
    INSTANCE_TEXELS, LIGHT_CDF_TEXELS, LIGHT_TRIANGLE_TEXELS, MATERIAL_TEXELS, NODE_TEXELS,
    TexelLayout,
};
use crate::shader::gpu_types::GpuInstance;
use crate::shader::sampling::Sampling;

/// Why an edit was not applied in place.
#[derive(Debug, Error)]
pub enum UpdateError {
    /// The renderer cannot take the edit in place; build a new one. `kernel` says whether
    /// the new one needs a kernel of other contents (a compile, unless cached).
    #[error("the edit needs a new renderer: {reason}")]
    NeedsRebuild { reason: String, kernel: bool },
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl UpdateError {
    fn rebuild(reason: impl Into<String>) -> Self {
        Self::NeedsRebuild {
            reason: reason.into(),
            kernel: false,
        }
    }

    fn kernel(reason: impl Into<String>) -> Self {
        Self::NeedsRebuild {
            reason: reason.into(),
            kernel: true,
        }
    }
}

/// What [`Renderer::update`] wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Updated {
    pub camera: bool,
    /// The top-level BVH and the instances (a transform or an instance's material).
    pub instances: bool,
    pub materials: bool,
    /// The light distribution: analytic lights, emissive triangles, the environment's
    /// colour and share.
    pub lights: bool,
    /// The path-length limits: bounces, volume bounces.
    pub max_bounces: bool,
    /// How samples are drawn: the seed of the random sequence, the sampler, the pixel
    /// filter (the scene's render settings).
    pub sampling: bool,
    /// The firefly clamp.
    pub clamp: bool,
}

impl Updated {
    /// Whether anything changed (and so the film must start over).
    pub fn any(&self) -> bool {
        self.camera
            || self.instances
            || self.materials
            || self.lights
            || self.max_bounces
            || self.sampling
            || self.clamp
    }
}

impl Renderer {
    /// Brings the renderer from `old` (the scene it renders) to `new` in place, writing
    /// only what differs; refuses (changing nothing) what needs a new renderer.
    pub fn update(&mut self, old: &Scene, new: &Scene) -> Result<Updated, UpdateError> {
        if old.world != new.world {
            return Err(UpdateError::rebuild("the world changed"));
        }
        // A world's map and suns, baked once for both (the bake is remembered).
        let (old, new) = (&*self.with_world(old)?, &*self.with_world(new)?);
        if old.meshes != new.meshes {
            return Err(UpdateError::rebuild("a mesh changed"));
        }
        if old.environment_map != new.environment_map {
            return Err(UpdateError::rebuild("the environment map changed"));
        }
        if old.instances.len() != new.instances.len()
            || old
                .instances
                .iter()
                .zip(&new.instances)
                .any(|(a, b)| a.mesh != b.mesh)
        {
            return Err(UpdateError::rebuild(
                "instances were added, removed or remeshed",
            ));
        }
        if old
            .instances
            .iter()
            .zip(&new.instances)
            .any(|(a, b)| a.shadow_catcher != b.shadow_catcher)
        {
            return Err(UpdateError::rebuild("a shadow catcher was set or cleared"));
        }
        if old.materials.len() != new.materials.len() {
            return Err(UpdateError::rebuild("materials were added or removed"));
        }
        if old.lights.len() != new.lights.len() {
            return Err(UpdateError::rebuild("lights were added or removed"));
        }
        new.validate()
            .map_err(|e| UpdateError::Render(RenderError::Scene(e)))?;
        // Check everything that could refuse before writing anything, so that a refused
        // edit leaves the renderer whole.
        let materials = old.materials != new.materials;
        let instances = old.instances != new.instances;
        let lights = old.lights != new.lights || old.environment != new.environment;
        let light_data = light_arrays(new);
        let sampling = if old.settings.sampling != new.settings.sampling {
            new.settings.sampling
        } else {
            self.settings.sampling
        };
        self.check_features(new, &light_data, sampling)?;
        let compiled = if materials {
            Some(self.check_materials(new, &light_data, sampling)?)
        } else {
            None
        };
        let placed = if instances {
            Some(self.place_instances(new)?)
        } else {
            None
        };
        self.check_lights(&light_data)?;
        let resolution_edited = old.settings.volume_resolution != new.settings.volume_resolution;
        let resolution = if resolution_edited {
            new.settings.volume_resolution
        } else {
            self.settings.volume_resolution
        };
        // Only these move the grids; a camera or light edit (each frame of navigation in
        // the viewport) plans nothing.
        if materials || instances || resolution_edited {
            self.check_volume_grids(new, resolution)?;
        }

        let mut updated = Updated::default();
        if let Some(compiled) = &compiled {
            self.write_materials(new, compiled)?;
            updated.materials = true;
        }
        if let Some((tlas, packed)) = placed {
            self.write_instances(tlas.as_ref(), &packed)?;
            self.place_enclosures(new, Some(gpu_order(tlas.as_ref())));
            updated.instances = true;
        } else if materials {
            self.place_enclosures(new, None);
        }
        // Emission is a material parameter and emissive triangles follow their instances,
        // so any of the three moves light.
        if instances || lights || materials {
            self.write_lights(new, &light_data)?;
            updated.lights = true;
        }
        self.settings.volume_resolution = resolution;
        // A graph's volume may read its object's placement (world position, the
        // instance's random number) as well as its constants: both bake again.
        if materials || instances {
            self.rebake_volume_grids(new)?;
        }
        if old.camera != new.camera {
            self.set_camera(&new.camera);
            updated.camera = true;
        } else if instances || materials {
            self.set_camera_media();
        }
        if old.settings.max_bounces != new.settings.max_bounces {
            self.set_max_bounces(new.settings.max_bounces);
            updated.max_bounces = true;
        }
        if old.settings.max_volume_bounces != new.settings.max_volume_bounces {
            self.set_max_volume_bounces(new.settings.max_volume_bounces);
            updated.max_bounces = true;
        }
        if old.settings.clamp != new.settings.clamp {
            self.set_clamp(new.settings.clamp);
            updated.clamp = true;
        }
        if old.settings.seed != new.settings.seed {
            self.settings.seed = new.settings.seed;
            self.base_params.seed = new.settings.seed;
            updated.sampling = true;
        }
        if old.settings.sampling != new.settings.sampling {
            self.set_sampling(new.settings.sampling);
            updated.sampling = true;
        }
        Ok(updated)
    }

    /// A transform (or an instance's material index) edit: rebuilds the top-level BVH over
    /// the meshes' existing BVHs, writes it and the instances, then the lights. `scene`
    /// must have the meshes and instance count the renderer was built with.
    pub fn update_instances(&mut self, scene: &Scene) -> Result<(), UpdateError> {
        let scene = &*self.with_world(scene)?;
        let lights = light_arrays(scene);
        self.check_features(scene, &lights, self.settings.sampling)?;
        let (tlas, packed) = self.place_instances(scene)?;
        self.check_lights(&lights)?;
        self.check_volume_grids(scene, self.settings.volume_resolution)?;
        self.write_instances(tlas.as_ref(), &packed)?;
        self.place_enclosures(scene, Some(gpu_order(tlas.as_ref())));
        self.set_camera_media();
        self.write_lights(scene, &lights)?;
        self.rebake_volume_grids(scene)
    }

    /// Refuses an edit after which the heterogeneous volumes' grids would lie otherwise
    /// in their buffer (another instance holds one, a resolution changed).
    fn check_volume_grids(&self, scene: &Scene, resolution: u32) -> Result<(), UpdateError> {
        let planned = VolumeGrids::plan(scene, &self.blas, resolution);
        if planned != self.gpu_scene.volume_grids {
            return Err(UpdateError::rebuild(
                "the heterogeneous volumes' grids change size or place",
            ));
        }
        Ok(())
    }

    /// Writes the grids' headers (majorants, the kernel's instance order) and bakes the
    /// grids again.
    fn rebake_volume_grids(&mut self, scene: &Scene) -> Result<(), UpdateError> {
        let grids = &self.gpu_scene.volume_grids;
        if grids.grids.is_empty() {
            return Ok(());
        }
        let order = kernel_indices(self.enclosures.gpu_order(), scene.instances.len());
        let headers = grids.headers(scene, &order);
        write_grid_headers(&self.ctx.queue, &self.gpu_scene.volume_grid, &headers);
        Ok(self.bake_volume_grids()?)
    }

    /// The top-level BVH over the kept mesh BVHs and the instances packed in its order.
    fn place_instances(
        &self,
        scene: &Scene,
    ) -> Result<(Option<Bvh>, Vec<GpuInstance>), UpdateError> {
        if scene.instances.len() as u32 != self.gpu_scene.instance_count {
            return Err(UpdateError::rebuild(format!(
                "the scene has {} instances, the renderer {}",
                scene.instances.len(),
                self.gpu_scene.instance_count
            )));
        }
        let tlas = build_tlas(scene, &self.blas).map_err(RenderError::from)?;
        let nodes = tlas.as_ref().map_or(0, |t| t.wide.nodes.len());
        if NODE_TEXELS.rows(nodes) > self.gpu_scene.tlas_texels.height() {
            return Err(UpdateError::rebuild(
                "the instances' BVH outgrows its buffer",
            ));
        }
        let packed = instance_arrays(
            scene,
            tlas.as_ref(),
            &self.gpu_scene.meshes,
            &self.gpu_scene.volume_grids.offsets,
        );
        Ok((tlas, packed))
    }

    fn write_instances(
        &mut self,
        tlas: Option<&Bvh>,
        packed: &[GpuInstance],
    ) -> Result<(), UpdateError> {
        let nodes = tlas.map_or(&[][..], |t| &t.wide.nodes[..]);
        let queue = &self.ctx.queue;
        write_texels(queue, &self.gpu_scene.tlas_texels, NODE_TEXELS, nodes);
        write_texels(queue, &self.gpu_scene.instances, INSTANCE_TEXELS, packed);
        Ok(())
    }

    /// A light edit (an analytic light, the environment's colour): recomputes and writes
    /// the light distribution. `scene` must have the renderer's light count.
    pub fn update_lights(&mut self, scene: &Scene) -> Result<(), UpdateError> {
        let scene = &*self.with_world(scene)?;
        let lights = light_arrays(scene);
        self.check_features(scene, &lights, self.settings.sampling)?;
        self.check_lights(&lights)?;
        self.write_lights(scene, &lights)
    }

    /// A material-parameter edit: writes the materials, then the lights (an emission may
    /// have changed). Refuses a change of a graph material's code or of the lobes the
    /// kernel contains.
    pub fn update_materials(&mut self, scene: &Scene) -> Result<(), UpdateError> {
        let scene = &*self.with_world(scene)?;
        let lights = light_arrays(scene);
        let compiled = self.check_materials(scene, &lights, self.settings.sampling)?;
        self.check_lights(&lights)?;
        self.check_volume_grids(scene, self.settings.volume_resolution)?;
        self.write_materials(scene, &compiled)?;
        self.place_enclosures(scene, None);
        self.set_camera_media();
        self.write_lights(scene, &lights)?;
        self.rebake_volume_grids(scene)
    }

    /// The objects holding media placed as in `scene`; `gpu_order` is the kernel's new
    /// instance order, `None` when it is unchanged.
    fn place_enclosures(&mut self, scene: &Scene, gpu_order: Option<Vec<u32>>) {
        let order = gpu_order.unwrap_or_else(|| self.enclosures.gpu_order().to_vec());
        self.enclosures.place(scene, &self.blas, &order);
    }

    /// Changes the volume bounce limit; a parameter, not a kernel change.
    pub fn set_max_volume_bounces(&mut self, max_volume_bounces: u32) {
        self.settings.max_volume_bounces = max_volume_bounces;
        self.base_params.max_volume_bounces = max_volume_bounces;
    }

    /// Changes the sampler or the pixel filter; parameters, not a kernel change.
    pub fn set_sampling(&mut self, sampling: Sampling) {
        self.settings.sampling = sampling;
        self.base_params.sampler = sampling.sampler.gpu_id();
        self.base_params.filter_quantiles = sampling.filter.quantiles();
    }

    /// Changes the firefly clamp; a parameter, not a kernel change.
    pub fn set_clamp(&mut self, clamp: crate::scene::Clamp) {
        self.settings.clamp = clamp;
        self.base_params.clamp_direct = clamp.direct;
        self.base_params.clamp_indirect = clamp.indirect;
    }

    /// Changes the path length; a parameter, not a kernel change.
    pub fn set_max_bounces(&mut self, max_bounces: u32) {
        self.settings.max_bounces = max_bounces;
        self.base_params.max_bounces = max_bounces;
    }

    /// `scene` with its world baked into its environment and lights, as the renderer
    /// renders it ([`super::world_bake::resolve_world`]).
    fn with_world<'a>(&self, scene: &'a Scene) -> Result<Cow<'a, Scene>, UpdateError> {
        Ok(super::world_bake::resolve_world(&self.ctx, scene)?)
    }

    /// Checks that the scene's materials (and its `lights`, [`light_arrays`], and
    /// `sampling`) fit the kernel; returns them compiled as the kernel has them (with their
    /// live constants, if the kernel reads those).
    fn check_materials(
        &self,
        scene: &Scene,
        lights: &LightArrays,
        sampling: Sampling,
    ) -> Result<SceneMaterials, UpdateError> {
        self.check_features(scene, lights, sampling)?;
        if scene.materials.len() as u32 != self.gpu_scene.material_count {
            return Err(UpdateError::rebuild("the material count changed"));
        }
        let compiled = super::materials::scene_materials(scene, self.settings.kernel)
            .map_err(RenderError::from)?;
        if compiled.wgsl != self.materials_wgsl {
            return Err(UpdateError::kernel("a material graph's code changed"));
        }
        let textures = super::materials::scene_textures(scene);
        let words = std::mem::size_of_val(&textures.gpu_words()[..]) as u64;
        if textures.images.len() as u32 != self.gpu_scene.texture_count
            || words > self.gpu_scene.textures.size()
        {
            return Err(UpdateError::kernel("the material graphs read other images"));
        }
        Ok(compiled)
    }

    fn write_materials(
        &mut self,
        scene: &Scene,
        compiled: &SceneMaterials,
    ) -> Result<(), UpdateError> {
        let packed: Vec<_> = scene
            .materials
            .iter()
            .map(super::gpu_scene::pack_material)
            .collect();
        let queue = &self.ctx.queue;
        write_texels(queue, &self.gpu_scene.materials, MATERIAL_TEXELS, &packed);
        let words = super::materials::scene_textures(scene).gpu_words();
        if !words.is_empty() {
            self.write("textures", &self.gpu_scene.textures, &words)?;
        }
        if !compiled.parameters.is_empty() {
            let buffer = &self.gpu_scene.material_params;
            self.write("material parameters", buffer, &compiled.parameters)?;
        }
        Ok(())
    }

    /// Refuses an edit after which the scene would need a kernel with other features
    /// (a lobe, a light type the kernel left out, another sampler where the kernel has one
    /// compiled in); `lights` are the scene's ([`light_arrays`]), computed once per edit by
    /// the caller, and `sampling` what the renderer samples with after the edit.
    fn check_features(
        &self,
        scene: &Scene,
        lights: &LightArrays,
        sampling: Sampling,
    ) -> Result<(), UpdateError> {
        let needed = kernel_features(
            KernelFeatures {
                lobes: instanced_lobes(scene),
                analytic_lights: !lights.analytic_lights.is_empty(),
                infinite_lights: lights.light_split[0] > 0.0,
                emissive_triangles: !lights.light_triangles.is_empty(),
                ..self.gpu_scene.features()
            },
            &RenderSettings {
                sampling,
                ..self.settings
            },
        );
        if needed != self.features {
            return Err(UpdateError::kernel(
                "the scene needs a kernel with other lobes, light types or sampler",
            ));
        }
        Ok(())
    }

    fn check_lights(&self, lights: &LightArrays) -> Result<(), UpdateError> {
        let fits = |layout: TexelLayout, count: usize, table: &wgpu::Texture| {
            layout.rows(count) <= table.height()
        };
        let g = &self.gpu_scene;
        if !fits(
            LIGHT_TRIANGLE_TEXELS,
            lights.light_triangles.len(),
            &g.light_triangles,
        ) || !fits(
            LIGHT_CDF_TEXELS,
            lights.light_cdf.len().div_ceil(4),
            &g.light_cdf,
        ) || lights.analytic_lights.len() as u32 != g.analytic_light_count
        {
            return Err(UpdateError::rebuild(
                "the emissive triangles or lights outgrow their buffers",
            ));
        }
        Ok(())
    }

    fn write_lights(&mut self, scene: &Scene, lights: &LightArrays) -> Result<(), UpdateError> {
        let queue = &self.ctx.queue;
        let g = &self.gpu_scene;
        write_texels(
            queue,
            &g.light_triangles,
            LIGHT_TRIANGLE_TEXELS,
            &lights.light_triangles,
        );
        write_texels(
            queue,
            &g.light_cdf,
            LIGHT_CDF_TEXELS,
            &in_fours(&lights.light_cdf),
        );
        self.write(
            "lights",
            &self.gpu_scene.analytic_lights,
            &lights.analytic_lights,
        )?;
        let g = &mut self.gpu_scene;
        g.light_count = lights.light_triangles.len() as u32;
        g.light_power = lights.light_power;
        g.triangle_pick = lights.triangle_pick;
        g.environment_pick = lights.environment_pick;
        g.light_split = lights.light_split;
        g.local_lights = lights.local_lights;
        let p = &mut self.base_params;
        p.light_count = g.light_count;
        p.light_power = g.light_power;
        p.triangle_pick = g.triangle_pick;
        p.environment = scene.environment.extend(g.environment_pick).into();
        p.light_split = g.light_split;
        p.local_lights = g.local_lights;
        Ok(())
    }

    /// Writes `data` at the start of `buffer`; nothing for empty data (the kernel reads no
    /// element past the counts in its parameters).
    fn write<T: bytemuck::Pod>(
        &self,
        name: &str,
        buffer: &wgpu::Buffer,
        data: &[T],
    ) -> Result<(), UpdateError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > buffer.size() {
            return Err(UpdateError::rebuild(format!(
                "the {name} outgrow their buffer ({} > {} bytes)",
                bytes.len(),
                buffer.size()
            )));
        }
        if !bytes.is_empty() {
            self.ctx.queue.write_buffer(buffer, 0, bytes);
        }
        Ok(())
    }
}

/// The scene index of each instance in the kernel's array: the TLAS's leaf order.
fn gpu_order(tlas: Option<&Bvh>) -> Vec<u32> {
    tlas.map_or_else(Vec::new, |t| t.primitive_order.clone())
}
