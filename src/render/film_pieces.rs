//! The film on the device, in pieces: per pixel the radiance sums as 64-bit fixed point,
//! their low and high words in two buffers, and the sample count (and, when asked for, the
//! AOV sums), split into bands of whole rows whose buffers each fit one
//! storage binding. A film is then bounded by memory, not by the per-binding limit
//! (128 MiB on lavapipe and on many GPUs, which a 3840×2160 film already fills).
//!
//! Each piece has its own bind group: the scene's buffers and the piece's. The kernel
//! indexes a piece by the pixel's index in the whole film minus `Params::film_piece_start`
//! and seeds its samples by the index in the whole film, so how the film is split never
//! changes a sample (`tests/film_pieces.rs`).
//!
//! Not here: what is rendered into the pieces (`renderer.rs`), and the host's film
//! (`crate::film::Film`), which the pieces are read back into, a band of rows at a time.

use std::ops::Range;

use super::context::GpuContext;
use super::gpu_scene::{FrameBuffers, GpuScene};
use super::readback::read_buffer_range;
use super::renderer::{Aovs, RenderError};
use crate::film::{ExactFilm, Film};

/// Bytes per pixel of the film's low words and count, and of its high words (one
/// `vec4<u32>` each; see [`crate::film::ExactFilm`]).
pub const SUM_BYTES: u64 = 16;
/// Bytes per pixel of the AOV film (three `vec4<f32>`).
pub const AOV_BYTES: u64 = 48;
/// Bytes per pixel of the noise estimate's film (one `vec4<f32>`).
pub const NOISE_BYTES: u64 = 16;
/// One band of the film's rows on the device.
pub struct FilmPiece {
    pub rows: Range<u32>,
    pub sum: wgpu::Buffer,
    /// The high words of the sums ([`FilmPiece::sum`] holds the low words and the count).
    pub high: wgpu::Buffer,
    pub aov: Option<wgpu::Buffer>,
    /// The noise estimate's film (`shaders/integrator/adaptive.wgsl`).
    pub noise: Option<wgpu::Buffer>,
    /// The scene's buffers with this piece's film.
    pub bind_group: wgpu::BindGroup,
}

impl FilmPiece {
    /// The piece's buffers: the sums' low words and counts, their high words, then the AOV and noise films
    /// when it has them.
    pub fn buffers(&self) -> impl Iterator<Item = &wgpu::Buffer> {
        [
            Some(&self.sum),
            Some(&self.high),
            self.aov.as_ref(),
            self.noise.as_ref(),
        ]
        .into_iter()
        .flatten()
    }
}

/// Cuts `height` rows of `width` pixels into bands of about equal height whose largest
/// buffer (`pixel_bytes` per pixel) fits in `limit` bytes.
pub fn piece_rows(
    width: u32,
    height: u32,
    pixel_bytes: u64,
    limit: u64,
) -> Result<Vec<Range<u32>>, RenderError> {
    let row_bytes = width as u64 * pixel_bytes;
    if row_bytes > limit {
        return Err(RenderError::FilmRowTooLarge {
            width,
            row_bytes,
            limit,
        });
    }
    let max_rows = (limit / row_bytes).clamp(1, height.max(1) as u64) as u32;
    // As many pieces as needed, then rows shared out evenly (no sliver of a last piece):
    // piece i ends at row ⌊(i + 1) h / n⌋, so lengths differ by at most one row and none
    // exceeds ⌈h / n⌉ ≤ max_rows.
    let pieces = height.div_ceil(max_rows).max(1) as u64;
    let edge = |i: u64| (i * height as u64 / pieces) as u32;
    Ok((0..pieces).map(|i| edge(i)..edge(i + 1)).collect())
}

/// Refuses a `width`×`height` film that would not fit in memory, before anything is
/// allocated: `host_pixel_bytes` per pixel that the caller will hold on the host (its
/// output image: 3 bytes a pixel for 8-bit RGB, 32 for a whole [`Film`] of four f64),
/// plus the film on the device where the device's memory is the host's (a CPU
/// adapter such as lavapipe). Elsewhere the device film is checked when it is allocated.
pub fn memory_check(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    film: DeviceFilm,
    host_pixel_bytes: u64,
) -> Result<(), RenderError> {
    let device = if ctx.info.device_type == wgpu::DeviceType::Cpu {
        film.pixel_bytes()
    } else {
        0
    };
    check_film_memory(width, height, host_pixel_bytes + device, available_memory())
}

/// Refuses a film that cannot fit in `available` bytes, saying the largest film of the
/// same aspect ratio that would.
fn check_film_memory(
    width: u32,
    height: u32,
    pixel_bytes: u64,
    available: Option<u64>,
) -> Result<(), RenderError> {
    let Some(available) = available else {
        return Ok(());
    };
    let pixels = width as u64 * height as u64;
    let needed = pixels * pixel_bytes;
    if needed <= available || pixel_bytes == 0 {
        return Ok(());
    }
    let scale = ((available / pixel_bytes) as f64 / pixels as f64).sqrt();
    Err(RenderError::FilmTooLarge {
        width,
        height,
        needed,
        available,
        max_width: (width as f64 * scale).floor() as u32,
        max_height: (height as f64 * scale).floor() as u32,
    })
}

/// Memory the system could give this process without swapping, where it says
/// (`MemAvailable` on Linux); None elsewhere.
pub(crate) fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The optional layers of the film on the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeviceFilm {
    pub aovs: bool,
    pub noise: bool,
}

impl DeviceFilm {
    /// Bytes per pixel of the film on the device.
    pub fn pixel_bytes(self) -> u64 {
        2 * SUM_BYTES
            + if self.aovs { AOV_BYTES } else { 0 }
            + if self.noise { NOISE_BYTES } else { 0 }
    }
}

/// The per-render buffers every piece binds beside its own.
pub struct SharedBuffers<'a> {
    pub params: &'a wgpu::Buffer,
    pub stats: &'a wgpu::Buffer,
}

/// Creates the pieces' buffers and bind groups. The device's running out of memory is an
/// error naming the film, not a crash.
pub fn allocate_pieces(
    ctx: &GpuContext,
    scene: &GpuScene,
    layout: &wgpu::BindGroupLayout,
    rows: &[Range<u32>],
    width: u32,
    film: DeviceFilm,
    shared: SharedBuffers,
) -> Result<Vec<FilmPiece>, RenderError> {
    let device = &ctx.device;
    let storage = |label: &str, size: u64| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let pieces: Vec<FilmPiece> = rows
        .iter()
        .map(|r| {
            let pixels = width as u64 * r.len() as u64;
            let sum = storage("film sum", pixels * SUM_BYTES);
            let high = storage("film sum high words", pixels * SUM_BYTES);
            let aov = film.aovs.then(|| storage("film AOVs", pixels * AOV_BYTES));
            let noise = film
                .noise
                .then(|| storage("film noise", pixels * NOISE_BYTES));
            let bind_group = scene.bind_group(
                device,
                layout,
                &FrameBuffers {
                    params: shared.params,
                    film_sum: &sum,
                    film_high: &high,
                    stats: shared.stats,
                    film_aov: aov.as_ref(),
                    film_noise: noise.as_ref(),
                },
            );
            FilmPiece {
                rows: r.clone(),
                sum,
                high,
                aov,
                noise,
                bind_group,
            }
        })
        .collect();
    if let Some(e) = pollster::block_on(scope.pop()) {
        let height = rows.last().map_or(0, |r| r.end);
        return Err(RenderError::FilmOutOfMemory {
            width,
            height,
            bytes: width as u64 * height as u64 * film.pixel_bytes(),
            message: e.to_string(),
        });
    }
    Ok(pieces)
}

/// The pieces holding rows of `rows`, each with the rows of it that do.
fn overlapping(
    pieces: &[FilmPiece],
    rows: Range<u32>,
) -> impl Iterator<Item = (&FilmPiece, Range<u32>)> {
    pieces.iter().filter_map(move |p| {
        let r = p.rows.start.max(rows.start)..p.rows.end.min(rows.end);
        (!r.is_empty()).then_some((p, r))
    })
}

/// Rows `rows` of `buffer` (a piece's, `pixel_bytes` per pixel) as bytes.
fn read_piece_rows(
    ctx: &GpuContext,
    piece: &FilmPiece,
    buffer: &wgpu::Buffer,
    width: u32,
    rows: &Range<u32>,
    pixel_bytes: u64,
) -> Result<Vec<u8>, RenderError> {
    let row_bytes = width as u64 * pixel_bytes;
    let offset = (rows.start - piece.rows.start) as u64 * row_bytes;
    Ok(read_buffer_range(
        ctx,
        buffer,
        offset,
        rows.len() as u64 * row_bytes,
    )?)
}

/// Rows `rows` of the film as a film of their own (`width` wide, `rows.len()` high),
/// exactly as the device holds it.
pub fn read_exact_film_rows(
    ctx: &GpuContext,
    pieces: &[FilmPiece],
    width: u32,
    rows: Range<u32>,
) -> Result<ExactFilm, RenderError> {
    let mut film = ExactFilm::new(width, rows.len() as u32);
    for (piece, r) in overlapping(pieces, rows.clone()) {
        let low = read_piece_rows(ctx, piece, &piece.sum, width, &r, SUM_BYTES)?;
        let high = read_piece_rows(ctx, piece, &piece.high, width, &r, SUM_BYTES)?;
        let low: &[[u32; 4]] = bytemuck::cast_slice(&low);
        let high: &[[u32; 4]] = bytemuck::cast_slice(&high);
        let first = (r.start - rows.start) as usize * width as usize;
        for (i, (l, h)) in low.iter().zip(high).enumerate() {
            film.sums[first + i] = std::array::from_fn(|c| ExactFilm::join(l[c], h[c]));
            film.counts[first + i] = l[3];
        }
    }
    Ok(film)
}

/// Rows `rows` of the film as a film of their own (`width` wide, `rows.len()` high).
pub fn read_film_rows(
    ctx: &GpuContext,
    pieces: &[FilmPiece],
    width: u32,
    rows: Range<u32>,
) -> Result<Film, RenderError> {
    Ok(read_exact_film_rows(ctx, pieces, width, rows)?.to_film())
}

/// Rows `rows` of the AOVs, averaged over each pixel's samples; None without AOVs.
pub fn read_aov_rows(
    ctx: &GpuContext,
    pieces: &[FilmPiece],
    width: u32,
    rows: Range<u32>,
) -> Result<Option<Aovs>, RenderError> {
    let mut aovs = Aovs::default();
    for (piece, r) in overlapping(pieces, rows) {
        let Some(buffer) = &piece.aov else {
            return Ok(None);
        };
        let raw = read_piece_rows(ctx, piece, buffer, width, &r, AOV_BYTES)?;
        let raw: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        for px in raw.chunks_exact(3) {
            let [a, n, e] = [px[0], px[1], px[2]];
            // The AOV film counts its own samples.
            let samples = n[3].max(1.0);
            aovs.albedo.extend([a[0], a[1], a[2]].map(|v| v / samples));
            aovs.depth.push(a[3] / samples);
            aovs.emission
                .extend([e[0], e[1], e[2]].map(|v| v / samples));
            aovs.alpha.push(e[3] / samples);
            let normal = glam::Vec3::new(n[0], n[1], n[2]);
            let unit = normal.try_normalize().unwrap_or(glam::Vec3::ZERO);
            aovs.normal.extend(unit.to_array());
        }
    }
    Ok(Some(aovs))
}

/// Rows `rows` of the noise film, one value per pixel taken from its texel
/// (`[Σ (r + g + b)², its compensation, noise estimate, converged]`) by `value`; None
/// without the noise film.
pub fn read_noise_rows<T>(
    ctx: &GpuContext,
    pieces: &[FilmPiece],
    width: u32,
    rows: Range<u32>,
    value: impl Fn(&[f32; 4]) -> T,
) -> Result<Option<Vec<T>>, RenderError> {
    let mut values = Vec::with_capacity(width as usize * rows.len());
    for (piece, r) in overlapping(pieces, rows) {
        let Some(buffer) = &piece.noise else {
            return Ok(None);
        };
        let raw = read_piece_rows(ctx, piece, buffer, width, &r, NOISE_BYTES)?;
        let raw: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        values.extend(raw.iter().map(&value));
    }
    Ok(Some(values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_cover_every_row_once_and_each_fits_the_limit() {
        for (width, height, limit) in [
            (512, 512, 512 * 32 * 100),
            (7, 1000, 7 * 16 * 3),
            (100, 1, 1 << 20),
        ] {
            let rows = piece_rows(width, height, 16, limit).unwrap();
            assert_eq!(rows.first().unwrap().start, 0);
            assert_eq!(rows.last().unwrap().end, height);
            for pair in rows.windows(2) {
                assert_eq!(pair[0].end, pair[1].start, "{rows:?}");
            }
            for r in &rows {
                assert!(
                    width as u64 * r.len() as u64 * 16 <= limit,
                    "{r:?} of {rows:?}"
                );
            }
            // Even shares: no piece more than one row shorter than another.
            let lens: Vec<usize> = rows.iter().map(|r| r.len()).collect();
            let (min, max) = (lens.iter().min().unwrap(), lens.iter().max().unwrap());
            assert!(max - min <= 1 || rows.len() == 1, "{lens:?}");
        }
        // 512 rows, 100 to a piece at most: six pieces.
        assert_eq!(piece_rows(512, 512, 32, 512 * 32 * 100).unwrap().len(), 6);
    }

    #[test]
    fn a_row_wider_than_the_limit_is_refused_with_the_numbers() {
        let err = piece_rows(1000, 10, 16, 8000).unwrap_err().to_string();
        assert!(err.contains("16000") && err.contains("8000"), "{err}");
    }

    #[test]
    fn a_film_beyond_memory_is_refused_with_the_largest_that_fits() {
        // 64 bytes per pixel, 1 GiB available: 2^24 pixels, 4096×4096 at a square aspect.
        let err = check_film_memory(16384, 16384, 64, Some(1 << 30)).unwrap_err();
        let RenderError::FilmTooLarge {
            max_width,
            max_height,
            ..
        } = err
        else {
            panic!("{err}");
        };
        assert_eq!((max_width, max_height), (4096, 4096));
        assert!(err.to_string().contains("4096x4096"), "{err}");
        assert!(check_film_memory(4096, 4096, 64, Some(1 << 30)).is_ok());
        assert!(check_film_memory(16384, 16384, 64, None).is_ok());
    }
}
