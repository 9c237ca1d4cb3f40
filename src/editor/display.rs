//! The viewport's display pass: a small compute pass (`shaders/editor/display.wgsl`) that
//! turns the renderer's film, where it lies on the device, into an 8-bit sRGB texture egui
//! draws. Nothing is read back to the CPU.

use crate::film::output::ViewSettings;
use crate::render::GpuContext;

const SOURCE: &str = include_str!("../../shaders/editor/display.wgsl");
const WORKGROUP: u32 = 8;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DisplayParams {
    size: [u32; 2],
    exposure_scale: f32,
    tonemap: u32,
}

/// The pipeline of the display pass, made once per device.
pub struct DisplayPipeline {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

/// The display pass bound to one film and its output texture.
pub struct FilmDisplay {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    size: [u32; 2],
}

impl FilmDisplay {
    /// Width and height in pixels.
    pub fn size(&self) -> [u32; 2] {
        self.size
    }
}

impl DisplayPipeline {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewport display"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport display"),
            entries: &[
                storage(0),
                storage(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::Rgba8Unorm,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("viewport display"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("display_film"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { pipeline, layout }
    }

    /// Binds a film of `size` pixels (its buffers of the sums' low and high words, see
    /// [`crate::render::Renderer::film_buffers`]) to a new output texture of that size.
    pub fn bind(
        &self,
        ctx: &GpuContext,
        film: (&wgpu::Buffer, &wgpu::Buffer),
        size: [u32; 2],
    ) -> FilmDisplay {
        let device = &ctx.device;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("viewport image"),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport display params"),
            size: std::mem::size_of::<DisplayParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = self.bind_group(ctx, film, &view, &params);
        FilmDisplay {
            texture,
            view,
            params,
            bind_group,
            size,
        }
    }

    fn bind_group(
        &self,
        ctx: &GpuContext,
        film: (&wgpu::Buffer, &wgpu::Buffer),
        view: &wgpu::TextureView,
        params: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport display"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: film.0.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: film.1.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: params.as_entire_binding(),
                },
            ],
        })
    }

    /// Writes the film's current image into the display's texture (queued on the device;
    /// anything submitted earlier, such as the samples just rendered, is included).
    pub fn run(&self, ctx: &GpuContext, display: &FilmDisplay, view: ViewSettings) {
        let params = DisplayParams {
            size: display.size,
            exposure_scale: view.exposure_ev.exp2(),
            tonemap: view.tonemap.gpu_id(),
        };
        ctx.queue
            .write_buffer(&display.params, 0, bytemuck::bytes_of(&params));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &display.bind_group, &[]);
            pass.dispatch_workgroups(
                display.size[0].div_ceil(WORKGROUP),
                display.size[1].div_ceil(WORKGROUP),
                1,
            );
        }
        ctx.queue.submit([encoder.finish()]);
    }
}
