//! The film: per-pixel sums of radiance samples and their counts, read back from the GPU,
//! and the single path from film to a file (exposure → tonemap → 8-bit sRGB, or linear
//! float for EXR).
//!
//! A film holds sums, not means, so films rendered from disjoint sample ranges merge by
//! addition; the mean is taken only when an image is made.

pub mod output;
pub mod tonemap;

use glam::Vec3;

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
