//! Kernel assembly: the WGSL files under `shaders/` concatenated in dependency order,
//! validated by naga (so errors name the file and line they come from, not a wgpu
//! panic), then compiled into a compute pipeline.
//!
//! Every kernel, the renderer's and the small test kernels that check BVH traversal or
//! sampling, is built from the same [`LIBRARY`](crate::shader::LIBRARY) files: tests run the shipped WGSL.

use thiserror::Error;

use super::context::{GpuContext, PipelineKey};
use super::prune::prune;
use crate::shader::bindings::bindings_wgsl;
use crate::shader::features::{features_wgsl, paging_wgsl};
use crate::shader::{ADAPTIVE, KernelFeatures, LIBRARY, PATH_INTEGRATOR, VOLUME_BAKE, lobes};

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
                source.push(
                    "generated: principled parameters (src/shader/principled.rs)",
                    &crate::shader::principled::wgsl(),
                );
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
        validator().validate(&module).map_err(|e| {
            self.wgsl_error(
                e.location(&self.text),
                e.as_inner().to_string(),
                e.emit_to_string(&self.text),
            )
        })?;
        Ok(module)
    }

    fn cache_key(&self, layouts: usize, entry_point: &str) -> PipelineKey {
        (self.source_key(layouts), hash(&entry_point))
    }

    /// The part of [`cache_key`](Self::cache_key) every entry point shares.
    fn source_key(&self, layouts: usize) -> u64 {
        hash(&(&self.text, layouts))
    }

    /// Whether [`KernelSource::create_pipeline`] would find this kernel in `ctx`'s
    /// pipeline cache (and so compile nothing).
    pub fn is_cached(&self, ctx: &GpuContext, layouts: usize, entry_point: &str) -> bool {
        let key = self.cache_key(layouts, entry_point);
        ctx.pipelines.lock().is_ok_and(|p| p.contains(key))
    }

    /// Drops this kernel's pipelines (every entry point) from `ctx`'s pipeline cache
    /// (their machine code goes once no renderer holds them).
    pub fn forget(&self, ctx: &GpuContext, layouts: usize) {
        let source = self.source_key(layouts);
        if let Ok(mut cache) = ctx.pipelines.lock() {
            cache.retain(|&(s, _)| s != source);
        }
    }

    /// Validates, then creates the compute pipeline for `entry_point`.
    pub fn create_pipeline(
        &self,
        ctx: &GpuContext,
        layouts: &[&wgpu::BindGroupLayout],
        entry_point: &str,
    ) -> Result<wgpu::ComputePipeline, KernelError> {
        let key = self.cache_key(layouts.len(), entry_point);
        let cached = ctx.pipelines.lock().ok().and_then(|mut p| p.get(key));
        if let Some(pipeline) = cached {
            return Ok(pipeline);
        }
        let mut module = self.validate()?;
        let pruned = prune(&mut module);
        tracing::debug!(
            kernel = %self.name,
            branches = pruned.branches,
            calls = pruned.calls,
            functions = pruned.functions,
            "pruned the branches the kernel's constants rule out"
        );
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&self.name),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module)),
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

/// naga's validator with every check and the capabilities every backend has.
pub(super) fn validator() -> naga::valid::Validator {
    // Half floats packed in 32-bit words (`pack2x16float`, the baked volume grids):
    // every backend wgpu runs on has them (its downlevel flag `SHADER_F16_IN_F32`).
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default() | naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32,
    )
}

/// The path-tracing kernel's source, with a scene's materials
/// ([`super::materials::scene_materials_wgsl`]) spliced in before the integrator, and
/// for a scene with heterogeneous volumes the entry point that bakes them
/// ([`super::volume_grid`]).
pub fn path_tracing_kernel(
    features: &KernelFeatures,
    materials: &[(String, String)],
) -> KernelSource {
    let mut source = KernelSource::with_library("path tracer", features);
    for (label, wgsl) in materials {
        source.push(label, wgsl);
    }
    for file in PATH_INTEGRATOR {
        source.push(file.path, file.source);
    }
    if features.lobes & lobes::HETEROGENEOUS != 0 {
        source.push(VOLUME_BAKE.path, VOLUME_BAKE.source);
    }
    if features.noise {
        source.push(ADAPTIVE.path, ADAPTIVE.source);
    }
    source
}

/// A value's hash with the standard library's hasher (stable within a process, which is
/// as long as a pipeline cache lives).
fn hash(value: &impl std::hash::Hash) -> u64 {
    use std::hash::Hasher;
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    value.hash(&mut hasher);
    hasher.finish()
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use naga::proc::Layouter;

    use super::*;
    use crate::shader::Ablation;
    use crate::shader::bindings::{
        PAGES, SCENE_BINDINGS, SCENE_GROUP, Space, TexelReads, bound, scene_layout_entries,
    };

    fn feature_sets() -> Vec<KernelFeatures> {
        let everything = KernelFeatures {
            node_pages: PAGES as u32,
            triangle_pages: PAGES as u32,
            ..KernelFeatures::default()
        };
        let nothing_optional = KernelFeatures {
            node_pages: 1,
            triangle_pages: 1,
            lobes: crate::shader::lobes::DIFFUSE,
            environment_map: false,
            analytic_lights: false,
            infinite_lights: false,
            emissive_triangles: false,
            shadow_catcher: false,
            textures: false,
            aovs: false,
            uv1: false,
            noise: false,
            ablation: Ablation::Full,
            texel_reads: TexelReads::Sampled,
            sampler: Some(crate::shader::sampling::Sampler::Independent),
        };
        let mixed = KernelFeatures {
            node_pages: 2,
            triangle_pages: 3,
            textures: true,
            aovs: false,
            uv1: true,
            ..nothing_optional
        };
        let in_texels = KernelFeatures {
            node_pages: 0,
            triangle_pages: 0,
            ..mixed
        };
        let in_storage_texels = KernelFeatures {
            texel_reads: TexelReads::Storage,
            ..in_texels
        };
        vec![
            everything,
            nothing_optional,
            mixed,
            in_texels,
            in_storage_texels,
        ]
    }

    /// naga's address space for a table entry.
    fn address_space(space: Space) -> naga::AddressSpace {
        match space {
            Space::Uniform | Space::UniformSlots => naga::AddressSpace::Uniform,
            Space::ReadOnly => naga::AddressSpace::Storage {
                access: naga::StorageAccess::LOAD,
            },
            Space::ReadWrite => naga::AddressSpace::Storage {
                access: naga::StorageAccess::LOAD | naga::StorageAccess::STORE,
            },
            Space::Texels => naga::AddressSpace::Handle,
        }
    }

    #[test]
    fn the_assembled_kernel_declares_exactly_the_layout_s_bindings() {
        for features in feature_sets() {
            let materials = crate::material::materials_wgsl(&[]);
            let module = path_tracing_kernel(&features, &materials)
                .validate()
                .unwrap_or_else(|e| panic!("{features:?}: {e}"));
            let mut layouter = Layouter::default();
            layouter
                .update(module.to_ctx())
                .expect("the kernel lays out");
            // What naga read from the assembled WGSL: binding → (name, space, stride).
            let mut declared = BTreeMap::new();
            for (_, var) in module.global_variables.iter() {
                let Some(rb) = &var.binding else { continue };
                assert_eq!(
                    rb.group, SCENE_GROUP,
                    "{:?} outside the scene's group",
                    var.name
                );
                let stride = match module.types[var.ty].inner {
                    naga::TypeInner::Array {
                        size: naga::ArraySize::Dynamic,
                        stride,
                        ..
                    } => stride,
                    _ => layouter[var.ty].size,
                };
                let previous = declared.insert(
                    rb.binding,
                    (var.name.clone().unwrap_or_default(), var.space, stride),
                );
                assert!(previous.is_none(), "binding {} declared twice", rb.binding);
            }
            // What the bind group layout is built from.
            let layout: BTreeMap<u32, wgpu::BindGroupLayoutEntry> = scene_layout_entries(&features)
                .into_iter()
                .map(|e| (e.binding, e))
                .collect();
            assert_eq!(
                declared.keys().collect::<Vec<_>>(),
                layout.keys().collect::<Vec<_>>(),
                "{features:?}: bindings declared in WGSL vs the layout's"
            );
            for b in bound(&features) {
                let (name, space, stride) = &declared[&b.binding];
                assert_eq!(name, b.name, "name of binding {}", b.binding);
                assert_eq!(*space, address_space(b.space), "address space of {name}");
                if b.space == Space::Texels {
                    let var = module
                        .global_variables
                        .iter()
                        .find(|(_, v)| v.name.as_deref() == Some(b.name))
                        .map(|(_, v)| v)
                        .expect("declared");
                    let class = match features.texel_reads {
                        TexelReads::Sampled => naga::ImageClass::Sampled {
                            kind: naga::ScalarKind::Uint,
                            multi: false,
                        },
                        TexelReads::Storage => naga::ImageClass::Storage {
                            format: naga::StorageFormat::Rgba32Uint,
                            access: naga::StorageAccess::LOAD,
                        },
                    };
                    assert_eq!(
                        module.types[var.ty].inner,
                        naga::TypeInner::Image {
                            dim: naga::ImageDimension::D2,
                            arrayed: false,
                            class,
                        },
                        "{name}: the WGSL type of a table read as {:?}",
                        features.texel_reads
                    );
                    assert_eq!(
                        layout[&b.binding].ty,
                        features.texel_reads.binding_type(),
                        "layout type of {name}"
                    );
                    continue;
                }
                assert_eq!(
                    *stride as u64, b.element_bytes,
                    "bytes per element of {name}: WGSL vs the Rust data uploaded"
                );
                let wgpu::BindingType::Buffer {
                    ty,
                    min_binding_size,
                    ..
                } = layout[&b.binding].ty
                else {
                    panic!("{name} is not a buffer in the layout");
                };
                let expected = match space {
                    naga::AddressSpace::Uniform => wgpu::BufferBindingType::Uniform,
                    naga::AddressSpace::Storage { access } => wgpu::BufferBindingType::Storage {
                        read_only: !access.contains(naga::StorageAccess::STORE),
                    },
                    other => panic!("{name} in {other:?}"),
                };
                assert_eq!(ty, expected, "layout type of {name}");
                assert_eq!(min_binding_size.map(|s| s.get()), Some(*stride as u64));
            }
            // Unbound bindings with a stand-in are still variables the code can name.
            for b in SCENE_BINDINGS.iter().filter(|b| !b.is_bound(&features)) {
                let var = module
                    .global_variables
                    .iter()
                    .find(|(_, v)| v.name.as_deref() == Some(b.name));
                match (b.stand_in, var) {
                    (Some(_), Some((_, v))) => {
                        assert_eq!(v.space, naga::AddressSpace::Private, "{}", b.name)
                    }
                    (None, None) => {}
                    (stand_in, var) => panic!(
                        "{}: stand-in {stand_in:?}, variable {:?}",
                        b.name,
                        var.map(|(_, v)| v.space)
                    ),
                }
            }
        }
    }

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
    fn every_ablated_kernel_passes_naga_validation() {
        for ablation in Ablation::ALL {
            let features = KernelFeatures {
                ablation,
                ..KernelFeatures::default()
            };
            let materials = crate::material::materials_wgsl(&[]);
            if let Err(e) = path_tracing_kernel(&features, &materials).validate() {
                panic!("{}: {e}", ablation.name());
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
