//! The film: per-pixel sums of radiance samples and their counts, read back from the GPU,
//! and the single path from film to a file (exposure → tonemap → 8-bit sRGB, or linear
//! float for EXR).
//!
//! A film holds sums, not means, so films rendered from disjoint sample ranges merge by
//! addition; the mean is taken only when an image is made. On the device the sums are
//! fixed point ([`ExactFilm`]): integer addition is associative, so the parts of a render
//! split by sample ranges merge to the very bits of the render done in one go.

pub mod output;
pub mod tonemap;

use glam::Vec3;

/// The film as the device accumulates it: per pixel each channel's radiance sum as a 64-bit
/// two's-complement fixed-point number of [`ExactFilm::FRACTION_BITS`] fractional bits,
/// and the sample count. Each sample (clamped to ±2²⁴) is rounded to the nearest step
/// (2⁻²⁸ ≈ 3.7·10⁻⁹) and added exactly; a sum saturates at about ±3.4·10¹⁰ (its high word
/// at ±[`ExactFilm::HIGH_LIMIT`]) instead of wrapping.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactFilm {
    pub width: u32,
    pub height: u32,
    /// Per pixel, row-major from the top-left: the r, g, b sums in steps of 2⁻²⁸.
    pub sums: Vec<[i64; 3]>,
    pub counts: Vec<u32>,
}

impl ExactFilm {
    /// Fractional bits of the fixed-point sums (`FILM_FRACTION_BITS` in
    /// `shaders/integrator/path.wgsl`).
    pub const FRACTION_BITS: i32 = 28;
    /// The largest magnitude of a sum's high word (`FILM_HIGH_LIMIT` in the kernel).
    pub const HIGH_LIMIT: i64 = (1 << 31) - (1 << 21);

    pub fn new(width: u32, height: u32) -> Self {
        let pixels = width as usize * height as usize;
        Self {
            width,
            height,
            sums: vec![[0; 3]; pixels],
            counts: vec![0; pixels],
        }
    }

    /// The sum whose low and high 32-bit words the device holds.
    pub fn join(low: u32, high: u32) -> i64 {
        ((high as u64) << 32 | low as u64) as i64
    }

    /// Adds another film's samples, exactly: the result does not depend on the order in
    /// which films are added (unless sums saturate; counts must not overflow).
    pub fn merge(&mut self, other: &ExactFilm) -> Result<(), String> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(format!(
                "cannot merge a {}x{} film into a {}x{} one",
                other.width, other.height, self.width, self.height
            ));
        }
        let (min, max) = (
            -Self::HIGH_LIMIT << 32,
            (Self::HIGH_LIMIT << 32) | 0xffff_ffff,
        );
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..3 {
                a[c] = a[c].saturating_add(b[c]).clamp(min, max);
            }
        }
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a = a
                .checked_add(*b)
                .ok_or("a pixel's sample count overflows 32 bits")?;
        }
        Ok(())
    }

    /// The film with its sums as floating point: the one conversion every image of a
    /// render goes through, merged or not.
    pub fn to_film(&self) -> Film {
        let step = (-Self::FRACTION_BITS as f64).exp2();
        Film {
            width: self.width,
            height: self.height,
            sums: self
                .sums
                .iter()
                .zip(&self.counts)
                .map(|(s, &n)| {
                    [
                        s[0] as f64 * step,
                        s[1] as f64 * step,
                        s[2] as f64 * step,
                        n as f64,
                    ]
                })
                .collect(),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Per pixel, row-major from the top-left: radiance sum (rgb) and sample count.
    pub sums: Vec<[f64; 4]>,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sums: vec![[0.0; 4]; width as usize * height as usize],
        }
    }

    /// Adds another film's samples to this one (the two must have been rendered with
    /// disjoint sample ranges to stay an unbiased estimate).
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(format!(
                "cannot merge a {}x{} film into a {}x{} one",
                other.width, other.height, self.width, self.height
            ));
        }
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..4 {
                a[c] += b[c];
            }
        }
        Ok(())
    }

    /// Mean radiance of a pixel (black where it has no samples yet).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let s = self.sums[(y * self.width + x) as usize];
        if s[3] == 0.0 {
            return Vec3::ZERO;
        }
        Vec3::new(
            (s[0] / s[3]) as f32,
            (s[1] / s[3]) as f32,
            (s[2] / s[3]) as f32,
        )
    }

    /// Mean radiance of every pixel, row-major.
    pub fn radiance(&self) -> Vec<Vec3> {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .map(|(x, y)| self.pixel(x, y))
            .collect()
    }

    pub fn sample_count(&self, x: u32, y: u32) -> u64 {
        self.sums[(y * self.width + x) as usize][3] as u64
    }

    pub fn total_samples(&self) -> u64 {
        self.sums.iter().map(|s| s[3] as u64).sum()
    }
}
