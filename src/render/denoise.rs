//! Denoising a rendered film ([`Denoiser`]): the à-trous filter of
//! `shaders/denoise/atrous.wgsl` on the GPU, guided by the albedo, normal and depth AOVs
//! and by each pixel's variance (from the noise film's second moments).
//!
//! The film less the emission the camera sees directly (lights, the sky: exact where
//! their edges cross a pixel, and never noisy) is divided by its albedo before filtering
//! and multiplied back after (SVGF's demodulation), so texture detail is never blurred and
//! the emission added back keeps the lights' edges sharp; the filter runs on bands of rows
//! that each fit one storage binding, each band with the rows its five iterations reach
//! beyond it, so a band's rows come out as they would from the whole image.
//!
//! Not here: when a film is denoised (the callers of [`super::export_film`]).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::context::GpuContext;
use super::kernel::KernelSource;
use super::readback::read_buffer_range;
use super::{Aovs, RenderError};
use crate::film::Film;
use crate::scene::Denoiser;
use crate::shader::DENOISE;
use crate::shader::bindings::{Space, layout_entry};

/// The filter's steps: taps 1, 2, 4, 8 and 16 pixels apart.
const STEPS: [u32; 5] = [1, 2, 4, 8, 16];
/// Rows beyond a band's own that its iterations read: two taps of each step.
const HALO: u32 = 2 * (1 + 2 + 4 + 8 + 16);
const WORKGROUP: u32 = 8;
/// The albedo below which a channel is not divided out (black texels would blow up).
const MIN_ALBEDO: f32 = 0.01;

/// `DenoiseParams` in `shaders/denoise/atrous.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DenoiseParams {
    size: [u32; 2],
    step: u32,
    _pad: u32,
    sigma_normal: f32,
    sigma_depth: f32,
    sigma_albedo: f32,
    sigma_luminance: f32,
}

/// What the filter's edges stop at: SVGF's value for the normal; for the luminance 2
/// standard deviations, not SVGF's 4 (on the Cornell box at 16 spp the RMSE against a
/// reference is 0.56× the noisy image's with 2, 0.62× with 4, 0.65× with 1, and a
/// converged image moves half as much with 2 as with 4).
const SIGMA_NORMAL: f32 = 128.0;
const SIGMA_DEPTH: f32 = 0.02;
const SIGMA_ALBEDO: f32 = 0.1;
const SIGMA_LUMINANCE: f32 = 2.0;

/// `film` denoised with `denoiser`: the same sample counts, other sums. `aovs` are the
/// film's AOVs and `second_moments` its per-pixel sums of (r + g + b)²
/// ([`super::Renderer::read_second_moments`]).
pub fn denoise_film(
    ctx: &GpuContext,
    film: &Film,
    aovs: &Aovs,
    second_moments: &[f64],
    denoiser: Denoiser,
) -> Result<Film, RenderError> {
    match denoiser {
        Denoiser::None => Ok(film.clone()),
        Denoiser::Atrous => atrous(ctx, film, aovs, second_moments),
        Denoiser::Oidn => oidn(film, aovs),
    }
}

/// `film` through Open Image Denoise's ray-tracing filter (HDR, on the CPU), guided by
/// the albedo (clamped to [0, 1], as OIDN expects) and the normal AOV (zero where the
/// camera saw the sky: OIDN's "no surface"). As with the à-trous filter, the emission
/// seen directly is taken out first and added back after: the network would otherwise
/// spread a light's radiance over its rim (on the Cornell box at 24×24 a converged image
/// moved by more than its mean).
#[cfg(feature = "oidn")]
fn oidn(film: &Film, aovs: &Aovs) -> Result<Film, RenderError> {
    let pixels = film.sums.len();
    if aovs.albedo.len() != 3 * pixels
        || aovs.normal.len() != 3 * pixels
        || aovs.emission.len() != 3 * pixels
    {
        return Err(RenderError::Denoise(
            "the film's AOVs do not match it".into(),
        ));
    }
    let colour: Vec<f32> = film
        .sums
        .iter()
        .zip(aovs.emission.chunks_exact(3))
        .flat_map(|(s, e)| {
            let n = s[3].max(1.0);
            [0, 1, 2].map(|c| ((s[c] / n) as f32 - e[c]).max(0.0))
        })
        .collect();
    let albedo: Vec<f32> = aovs.albedo.iter().map(|a| a.clamp(0.0, 1.0)).collect();
    let device = oidn::Device::new();
    let mut filtered = vec![0.0f32; 3 * pixels];
    oidn::RayTracing::new(&device)
        .hdr(true)
        .image_dimensions(film.width as usize, film.height as usize)
        .albedo_normal(&albedo, &aovs.normal)
        .filter(&colour, &mut filtered)
        .map_err(|e| RenderError::Denoise(format!("Open Image Denoise: {e:?}")))?;
    if let Err((_, message)) = device.get_error() {
        return Err(RenderError::Denoise(format!(
            "Open Image Denoise: {message}"
        )));
    }
    let mut out = film.clone();
    for ((sum, c), e) in out
        .sums
        .iter_mut()
        .zip(filtered.chunks_exact(3))
        .zip(aovs.emission.chunks_exact(3))
    {
        let n = sum[3];
        let [r, g, b] = [0, 1, 2].map(|i| (c[i] + e[i]) as f64 * n);
        *sum = [r, g, b, n];
    }
    Ok(out)
}

#[cfg(not(feature = "oidn"))]
fn oidn(_: &Film, _: &Aovs) -> Result<Film, RenderError> {
    Err(RenderError::Denoise(
        Denoiser::Oidn
            .unavailable()
            .unwrap_or("Open Image Denoise is not linked")
            .into(),
    ))
}

/// Per pixel what the albedo is divided out by: its channels (at least [`MIN_ALBEDO`])
/// where the camera met a surface, 1 where it saw the sky.
fn demodulation(aovs: &Aovs, pixel: usize) -> glam::Vec3 {
    let normal = glam::Vec3::from_slice(&aovs.normal[3 * pixel..]);
    if normal == glam::Vec3::ZERO {
        return glam::Vec3::ONE;
    }
    glam::Vec3::from_slice(&aovs.albedo[3 * pixel..]).max(glam::Vec3::splat(MIN_ALBEDO))
}

fn luminance(c: glam::Vec3) -> f32 {
    c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The variance of a pixel's mean luminance from its sums: that of its mean r + g + b
/// over 9 (the luminance weights are near a third each). With one sample nothing is
/// known: its variance is taken as its value squared.
fn mean_variance(sum: [f64; 4], second_moment: f64) -> f32 {
    let n = sum[3];
    let mean = (sum[0] + sum[1] + sum[2]) / n.max(1.0);
    if n < 2.0 {
        return (mean * mean / 9.0) as f32;
    }
    let variance = (second_moment / n - mean * mean).max(0.0) * n / (n - 1.0);
    (variance / n / 9.0) as f32
}

fn atrous(
    ctx: &GpuContext,
    film: &Film,
    aovs: &Aovs,
    second_moments: &[f64],
) -> Result<Film, RenderError> {
    let pixels = film.sums.len();
    if aovs.depth.len() != pixels
        || aovs.emission.len() != 3 * pixels
        || second_moments.len() != pixels
    {
        return Err(RenderError::Denoise(
            "the film's AOVs and noise film do not match it".into(),
        ));
    }
    // Per pixel: (albedo, depth), (normal, 0).
    let mut guide = Vec::with_capacity(2 * pixels);
    let mut source = Vec::with_capacity(pixels);
    let mut modulation = Vec::with_capacity(pixels);
    for (i, sum) in film.sums.iter().enumerate() {
        let d = demodulation(aovs, i);
        let n = sum[3].max(1.0);
        let colour = glam::Vec3::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        );
        let emission = glam::Vec3::from_slice(&aovs.emission[3 * i..]);
        let variance = mean_variance(*sum, second_moments[i]) / luminance(d).powi(2);
        let scattered = (colour - emission).max(glam::Vec3::ZERO);
        source.push((scattered / d).extend(variance).to_array());
        let albedo = glam::Vec3::from_slice(&aovs.albedo[3 * i..]);
        guide.push(albedo.extend(aovs.depth[i]).to_array());
        guide.push(
            glam::Vec3::from_slice(&aovs.normal[3 * i..])
                .extend(0.0)
                .to_array(),
        );
        modulation.push((d, emission));
    }
    let filtered = run_atrous(ctx, film.width, film.height, &guide, &source)?;
    let mut out = film.clone();
    for ((sum, f), (d, emission)) in out.sums.iter_mut().zip(&filtered).zip(&modulation) {
        let c = glam::Vec3::new(f[0], f[1], f[2]) * *d + *emission;
        let n = sum[3];
        *sum = [c.x as f64 * n, c.y as f64 * n, c.z as f64 * n, n];
    }
    Ok(out)
}

/// Runs the filter's iterations over the image in bands; returns (illumination,
/// variance) per pixel.
fn run_atrous(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    guide: &[[f32; 4]],
    source: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>, RenderError> {
    let device = &ctx.device;
    let entries = [
        layout_entry(0, Space::Uniform, size_of::<DenoiseParams>() as u64),
        layout_entry(1, Space::ReadOnly, 32),
        layout_entry(2, Space::ReadOnly, 16),
        layout_entry(3, Space::ReadWrite, 16),
    ];
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("denoiser"),
        entries: &entries,
    });
    let mut kernel = KernelSource::new("denoiser");
    kernel.push(DENOISE.path, DENOISE.source);
    let pipeline = kernel.create_pipeline(ctx, &[&layout], "atrous")?;

    let limits = ctx.limits();
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    // The guide is the widest buffer: 32 bytes a pixel.
    let rows_fit = binding / (width as u64 * 32);
    let band = rows_fit.saturating_sub(2 * HALO as u64).min(height as u64) as u32;
    if band == 0 {
        return Err(RenderError::Denoise(format!(
            "an image {width} pixels wide does not fit the adapter's {binding}-byte buffers"
        )));
    }
    let row = width as usize;
    let mut out = Vec::with_capacity(source.len());
    for first in (0..height).step_by(band as usize) {
        let kept = first..(first + band).min(height);
        let lo = first.saturating_sub(HALO);
        let hi = (kept.end + HALO).min(height);
        let rows = hi - lo;
        let span = lo as usize * row..hi as usize * row;
        let storage = |label: &str, data: &[[f32; 4]], extra: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(data),
                usage: wgpu::BufferUsages::STORAGE | extra,
            })
        };
        let guide_buffer = storage(
            "denoiser guide",
            &guide[2 * span.start..2 * span.end],
            wgpu::BufferUsages::empty(),
        );
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let ping = [
            storage("denoiser a", &source[span.clone()], copy),
            storage("denoiser b", &source[span.clone()], copy),
        ];
        let mut encoder = device.create_command_encoder(&Default::default());
        for (k, &step) in STEPS.iter().enumerate() {
            let params = DenoiseParams {
                size: [width, rows],
                step,
                _pad: 0,
                sigma_normal: SIGMA_NORMAL,
                sigma_depth: SIGMA_DEPTH,
                sigma_albedo: SIGMA_ALBEDO,
                sigma_luminance: SIGMA_LUMINANCE,
            };
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("denoiser params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let (from, to) = (&ping[k % 2], &ping[(k + 1) % 2]);
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("denoiser"),
                layout: &layout,
                entries: &[
                    entry(0, &params),
                    entry(1, &guide_buffer),
                    entry(2, from),
                    entry(3, to),
                ],
            });
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(width.div_ceil(WORKGROUP), rows.div_ceil(WORKGROUP), 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let last = &ping[STEPS.len() % 2];
        let offset = (kept.start - lo) as u64 * row as u64 * 16;
        let bytes = read_buffer_range(ctx, last, offset, kept.len() as u64 * row as u64 * 16)?;
        out.extend_from_slice(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes));
    }
    Ok(out)
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_halo_covers_every_tap_of_every_step() {
        assert_eq!(HALO, STEPS.iter().map(|s| 2 * s).sum::<u32>());
    }

    #[test]
    fn a_pixel_with_equal_samples_has_no_variance_and_one_sample_is_all_noise() {
        // Four samples of 0.5 each in every channel: r + g + b = 1.5, squared 2.25.
        assert_eq!(mean_variance([2.0, 2.0, 2.0, 4.0], 4.0 * 2.25), 0.0);
        // Samples 0 and 3 of r + g + b: variance 4.5, of the mean 2.25, of luminance /9.
        let v = mean_variance([1.0, 1.0, 1.0, 2.0], 9.0);
        assert!((v - 0.25).abs() < 1e-6, "{v}");
        let v = mean_variance([0.3, 0.3, 0.3, 1.0], 0.81);
        assert!((v - 0.09).abs() < 1e-6, "{v}");
    }
}
