//! Kernel assembly: the WGSL files under `shaders/` concatenated in dependency order,
//! validated by naga (so errors name the file and line they come from, not a wgpu
//! panic), then compiled into a compute pipeline.
//!
//! Every kernel, the renderer's and the small test kernels that check BVH traversal or
//! sampling, is built from the same [`LIBRARY`] files: tests run the shipped WGSL.

use thiserror::Error;

use super::bindings::bindings_wgsl;
use super::context::GpuContext;

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
    shader_file!("bsdf/principled.wgsl"),
    shader_file!("lights/emissive_triangle.wgsl"),
    shader_file!("lights/environment.wgsl"),
    shader_file!("lights/analytic.wgsl"),
];

/// The path-tracing entry point `render`.
pub const PATH_INTEGRATOR: ShaderFile = shader_file!("integrator/path.wgsl");

#[derive(Debug, Error)]
pub enum KernelError {
    #[error("WGSL error at {file}:{line}:{column}: {message}\n{detail}")]
    Wgsl {
        file: String,
        line: u32,
        column: u32,
        message: String,
        detail: String,
    },
    #[error("the driver rejected kernel \"{kernel}\": {message}")]
    Pipeline { kernel: String, message: String },
}

/// Concatenated WGSL with a map from its lines back to the files they came from.
#[derive(Clone, Debug)]
pub struct KernelSource {
    pub name: String,
    pub text: String,
    /// (first line in `text`, 1-based; file path) per part.
    parts: Vec<(u32, String)>,
}

impl KernelSource {
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            text: String::new(),
            parts: Vec::new(),
        }
    }

    /// The shader library, specialised for `features`.
    pub fn with_library(name: &str, features: &KernelFeatures) -> Self {
        let mut source = Self::new(name);
        for (i, file) in LIBRARY.iter().enumerate() {
            source.push(file.path, file.source);
            if i == 0 {
                // Right after scene.wgsl, whose structs the bindings hold.
                source.push("generated: scene bindings", &bindings_wgsl(features));
                source.push("generated: paged array accessors", &paging_wgsl(features));
                source.push("generated: kernel features", &features_wgsl(features));
            }
        }
        source
    }

    pub fn push(&mut self, path: &str, wgsl: &str) {
        let first_line = self.text.lines().count() as u32 + 1;
        self.parts.push((first_line, path.to_owned()));
        self.text.push_str(wgsl);
        if !wgsl.ends_with('\n') {
            self.text.push('\n');
        }
    }

    /// The file and file-relative line of a line of the assembled text.
    pub fn locate(&self, line: u32) -> (String, u32) {
        match self.parts.iter().rev().find(|(first, _)| *first <= line) {
            Some((first, path)) => (path.clone(), line - first + 1),
            None => (self.name.clone(), line),
        }
    }

    fn wgsl_error(
        &self,
        location: Option<naga::SourceLocation>,
        message: String,
        detail: String,
    ) -> KernelError {
        let (file, line, column) = match location {
            Some(loc) => {
                let (file, line) = self.locate(loc.line_number);
                (file, line, loc.line_position)
            }
            None => (self.name.clone(), 0, 0),
        };
        KernelError::Wgsl {
            file,
            line,
            column,
            message,
            detail,
        }
    }

    /// Parses and validates with naga, the same checks wgpu would make, but with errors
    /// that point into `shaders/`.
    pub fn validate(&self) -> Result<naga::Module, KernelError> {
        let module = naga::front::wgsl::parse_str(&self.text).map_err(|e| {
            self.wgsl_error(
                e.location(&self.text),
                e.message().to_owned(),
                e.emit_to_string(&self.text),
            )
        })?;
        let mut validator = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        );
        validator.validate(&module).map_err(|e| {
            self.wgsl_error(
                e.location(&self.text),
                e.as_inner().to_string(),
                e.emit_to_string(&self.text),
            )
        })?;
        Ok(module)
    }

    /// Validates, then creates the compute pipeline for `entry_point`.
    pub fn create_pipeline(
        &self,
        ctx: &GpuContext,
        layouts: &[&wgpu::BindGroupLayout],
        entry_point: &str,
    ) -> Result<wgpu::ComputePipeline, KernelError> {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        (&self.text, entry_point, layouts.len()).hash(&mut hasher);
        let key = hasher.finish();
        let cached = ctx.pipelines.lock().ok().and_then(|p| p.get(&key).cloned());
        if let Some(pipeline) = cached {
            return Ok(pipeline);
        }
        self.validate()?;
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&self.name),
            source: wgpu::ShaderSource::Wgsl(self.text.as_str().into()),
        });
        let bind_group_layouts: Vec<Option<&wgpu::BindGroupLayout>> =
            layouts.iter().map(|l| Some(*l)).collect();
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&self.name),
            bind_group_layouts: &bind_group_layouts,
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&self.name),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry_point),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(KernelError::Pipeline {
                kernel: self.name.clone(),
                message: e.to_string(),
            });
        }
        ctx.pipelines_compiled
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if let Ok(mut cache) = ctx.pipelines.lock() {
            cache.insert(key, pipeline.clone());
        }
        Ok(pipeline)
    }
}

/// The principled surface's lobes, one bit each, as `KernelFeatures::lobes` counts them.
pub mod lobes {
    pub const COAT: u32 = 1;
    pub const SHEEN: u32 = 2;
    /// The metal and its multiple-scattering compensation.
    pub const METAL: u32 = 4;
    pub const GLASS: u32 = 8;
    pub const SPECULAR: u32 = 16;
    pub const DIFFUSE: u32 = 32;
    pub const ALL: u32 = 63;
    pub const NAMES: [(u32, &str); 6] = [
        (COAT, "COAT"),
        (SHEEN, "SHEEN"),
        (METAL, "METAL"),
        (GLASS, "GLASS"),
        (SPECULAR, "SPECULAR"),
        (DIFFUSE, "DIFFUSE"),
    ];
}

/// What a kernel is specialised for; only what a scene uses is compiled in. The shaders
/// test `FEATURE_*` constants (generated by [`features_wgsl`]), and the driver removes
/// the code behind the false ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KernelFeatures {
    /// Pages in use of the paged arrays (1 to `bindings::PAGES`).
    pub node_pages: u32,
    pub triangle_pages: u32,
    /// Principled lobes any material can reach ([`lobes`]).
    pub lobes: u32,
    pub environment_map: bool,
    /// Point, spot and distant lights.
    pub analytic_lights: bool,
    pub emissive_triangles: bool,
    /// Image textures: binds `texture_data`.
    pub textures: bool,
    /// AOV layers (albedo, normal, depth): binds `film_aov`.
    pub aovs: bool,
    /// A second UV set: binds `uv1_data`.
    pub uv1: bool,
}

impl Default for KernelFeatures {
    /// Everything on, with one page each.
    fn default() -> Self {
        Self {
            node_pages: 1,
            triangle_pages: 1,
            lobes: lobes::ALL,
            environment_map: true,
            analytic_lights: true,
            emissive_triangles: true,
            textures: true,
            aovs: true,
            uv1: true,
        }
    }
}

impl KernelFeatures {
    /// Every lobe and light type compiled in: the unspecialised kernel. What changes the
    /// bindings (pages, textures, AOVs, the second UV set) stays the scene's, so the
    /// kernel fits the scene's bind group layout.
    pub fn everything(self) -> Self {
        Self {
            lobes: lobes::ALL,
            environment_map: true,
            analytic_lights: true,
            emissive_triangles: true,
            ..self
        }
    }
}

/// The `FEATURE_*` constants the shaders test.
pub fn features_wgsl(features: &KernelFeatures) -> String {
    let mut text = String::new();
    for (bit, name) in lobes::NAMES {
        text.push_str(&format!(
            "const FEATURE_{name}: bool = {};\n",
            features.lobes & bit != 0
        ));
    }
    for (name, on) in [
        ("ENVIRONMENT_MAP", features.environment_map),
        ("ANALYTIC_LIGHTS", features.analytic_lights),
        ("EMISSIVE_TRIANGLES", features.emissive_triangles),
    ] {
        text.push_str(&format!("const FEATURE_{name}: bool = {on};\n"));
    }
    for (name, on) in [("AOVS", features.aovs), ("UV1", features.uv1)] {
        text.push_str(&format!("const FEATURE_{name}: bool = {on};\n"));
    }
    text
}

/// `fetch_blas_node` and `fetch_triangle` for the pages a scene uses. With one page the
/// accessor is a plain load: on lavapipe even an untaken branch to the other pages slows
/// traversal by 40%.
pub fn paging_wgsl(features: &KernelFeatures) -> String {
    // The pages' bindings are declared by `bindings_wgsl`.
    fn accessor(name: &str, ty: &str, array: &str, shift: &str, pages: u32) -> String {
        let mut body = String::new();
        if pages <= 1 {
            body.push_str(&format!("    return {array}_0[i];\n"));
        } else {
            body.push_str(&format!("    let page = i >> params.{shift};\n"));
            body.push_str(&format!("    let j = i & ((1u << params.{shift}) - 1u);\n"));
            for p in 0..pages - 1 {
                body.push_str(&format!(
                    "    if (page == {p}u) {{\n        return {array}_{p}[j];\n    }}\n"
                ));
            }
            body.push_str(&format!("    return {array}_{}[j];\n", pages - 1));
        }
        format!("fn {name}(i: u32) -> {ty} {{\n{body}}}\n")
    }
    format!(
        "// Generated for {} node page(s) and {} triangle page(s).\n{}\n{}",
        features.node_pages,
        features.triangle_pages,
        accessor(
            "fetch_blas_node",
            "BvhNode",
            "blas_nodes",
            "node_page_shift",
            features.node_pages
        ),
        accessor(
            "fetch_triangle",
            "Triangle",
            "triangles",
            "triangle_page_shift",
            features.triangle_pages
        ),
    )
}

/// The path-tracing kernel's source, with a scene's materials
/// (`crate::material::scene_materials_wgsl`) spliced in before the integrator.
pub fn path_tracing_kernel(
    features: &KernelFeatures,
    materials: &[(String, String)],
) -> KernelSource {
    let mut source = KernelSource::with_library("path tracer", features);
    for (label, wgsl) in materials {
        source.push(label, wgsl);
    }
    source.push(PATH_INTEGRATOR.path, PATH_INTEGRATOR.source);
    source
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_tracing_kernel_passes_naga_validation() {
        for pages in 1..=4 {
            let features = KernelFeatures {
                node_pages: pages,
                triangle_pages: 5 - pages,
                ..KernelFeatures::default()
            };
            let materials = crate::material::materials_wgsl(&[]);
            if let Err(e) = path_tracing_kernel(&features, &materials).validate() {
                panic!("{e}");
            }
        }
    }

    #[test]
    fn errors_point_into_the_file_they_come_from() {
        let mut source = KernelSource::with_library("broken", &KernelFeatures::default());
        source.push(
            "shaders/tests/broken.wgsl",
            "fn f() -> f32 {\n    let a = 1.0\n    return a;\n}\n",
        );
        match source.validate().unwrap_err() {
            KernelError::Wgsl { file, line, .. } => {
                assert_eq!(file, "shaders/tests/broken.wgsl");
                assert_eq!(line, 3, "the statement after the missing semicolon");
            }
            other => panic!("unexpected {other}"),
        }
        // A type error found by validation rather than parsing still names the file.
        let mut source = KernelSource::with_library("ill-typed", &KernelFeatures::default());
        source.push(
            "shaders/tests/ill_typed.wgsl",
            "fn g() -> f32 {\n    return 1u;\n}\n",
        );
        match source.validate().unwrap_err() {
            KernelError::Wgsl { file, .. } => assert_eq!(file, "shaders/tests/ill_typed.wgsl"),
            other => panic!("unexpected {other}"),
        }
    }
}
