//! The viewport's display pass (`shaders/editor/display.wgsl`) shows what `kiln render`
//! writes: for every view transform and a spread of radiances (six decades, grey and
//! saturated hues, exposure applied), the pass's 8-bit sRGB texels equal the CPU's
//! `film::tonemap::to_srgb8` to within one code value (the GPU's `pow`, `log2` and
//! `exp2` are not correctly rounded).

use glam::Vec3;
use kiln::editor::display::DisplayPipeline;
use kiln::film::ExactFilm;
use kiln::film::output::ViewSettings;
use kiln::film::tonemap::{Tonemap, to_srgb8};
use kiln::render::{GpuContext, map_and_read};
use wgpu::util::DeviceExt;

const WIDTH: u32 = 64;
const HUES: [[f32; 3]; 6] = [
    [1.0, 1.0, 1.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.6, 0.1],
    [0.2, 0.5, 1.0],
];

/// Row `y` holds hue `y` at radiances from 1e-3 to 1e3 across the row.
fn radiance(x: u32, y: u32) -> Vec3 {
    let level = 10f32.powf(-3.0 + 6.0 * x as f32 / (WIDTH - 1) as f32);
    Vec3::from_array(HUES[y as usize]) * level
}

#[test]
fn the_display_pass_matches_the_cpu_view_transforms_within_one_code_value() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread of this test starts a device.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let ctx = GpuContext::new(None).unwrap_or_else(|e| panic!("a GPU adapter: {e}"));
    let height = HUES.len() as u32;
    // A film of 3 samples per pixel whose mean is `radiance`, as the kernel holds it: the
    // sums in fixed point, low words and count in one buffer, high words in the other
    // (nonzero from a sum of about 16 up).
    let mut lows: Vec<u32> = Vec::new();
    let mut highs: Vec<u32> = Vec::new();
    for y in 0..height {
        for x in 0..WIDTH {
            let sum = radiance(x, y) * 3.0;
            let fixed = sum
                .to_array()
                .map(|v| (v as f64 * (ExactFilm::FRACTION_BITS as f64).exp2()).round() as i64);
            lows.extend(fixed.map(|v| v as u32));
            lows.push(3);
            highs.extend(fixed.map(|v| (v >> 32) as u32));
            highs.push(0);
        }
    }
    assert!(
        highs.iter().any(|&h| h != 0),
        "the film exercises the high words"
    );
    let buffer = |label, data: &[u32]| {
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(data),
                usage: wgpu::BufferUsages::STORAGE,
            })
    };
    let (sum, comp) = (buffer("sum", &lows), buffer("high words", &highs));
    let pipeline = DisplayPipeline::new(&ctx);
    let display = pipeline.bind(&ctx, (&sum, &comp), [WIDTH, height]);

    for tonemap in Tonemap::ALL {
        for exposure_ev in [0.0, -2.5, 1.5] {
            let view = ViewSettings {
                exposure_ev,
                tonemap,
            };
            pipeline.run(&ctx, &display, view);
            let texels = read_texture(&ctx, &display.texture, [WIDTH, height]);
            let mut worst = (0, 0, 0);
            for y in 0..height {
                for x in 0..WIDTH {
                    let expected = to_srgb8(radiance(x, y), exposure_ev, tonemap);
                    let at = ((y * WIDTH + x) * 4) as usize;
                    for c in 0..3 {
                        let d = (texels[at + c] as i32 - expected[c] as i32).abs();
                        if d > worst.0 {
                            worst = (d, x, y);
                        }
                    }
                    assert_eq!(texels[at + 3], 255, "opaque");
                }
            }
            let (d, x, y) = worst;
            assert!(
                d <= 1,
                "{tonemap:?} at {exposure_ev} EV: pixel ({x}, {y}) (radiance {}) differs by {d} code values from the CPU's",
                radiance(x, y)
            );
        }
    }
}

/// The RGBA8 texels of `texture`, row after row.
fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture, [width, height]: [u32; 2]) -> Vec<u8> {
    let padded = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("display readback"),
        size: (padded * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    let data = map_and_read(ctx, &staging).expect("the copy reads back");
    (0..height as usize)
        .flat_map(|y| {
            let row = y * padded as usize;
            data[row..row + width as usize * 4].to_vec()
        })
        .collect()
}
