//! Reading the EXR files the CLI writes: every channel of the single part, by name.

use std::collections::HashMap;
use std::path::Path;

/// The channels of a single-part EXR file, by name (`R`, `normal.X`, `depth.Z`, …), each
/// row by row from the top-left.
pub struct Exr {
    pub width: usize,
    pub height: usize,
    pub channels: HashMap<String, Vec<f32>>,
}

pub fn read_exr(path: &Path) -> Exr {
    let image = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{} is not a readable EXR: {e}", path.display()));
    assert_eq!(
        image.layer_data.len(),
        1,
        "one part, layers as channel prefixes"
    );
    let layer = &image.layer_data[0];
    Exr {
        width: layer.size.0,
        height: layer.size.1,
        channels: layer
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
            .collect(),
    }
}

impl Exr {
    pub fn channel(&self, name: &str) -> &[f32] {
        self.channels
            .get(name)
            .unwrap_or_else(|| panic!("no channel {name} among {:?}", self.channels.keys()))
    }

    pub fn rgb(&self, pixel: usize) -> [f32; 3] {
        ["R", "G", "B"].map(|c| self.channel(c)[pixel])
    }

    /// Mean radiance per channel over `pixels`.
    pub fn mean_over(&self, pixels: &[usize]) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for &p in pixels {
            for (s, v) in sum.iter_mut().zip(self.rgb(p)) {
                *s += v as f64;
            }
        }
        sum.map(|s| s / pixels.len() as f64)
    }

    pub fn mean(&self) -> [f64; 3] {
        self.mean_over(&(0..self.width * self.height).collect::<Vec<_>>())
    }

    /// Pixels where no camera sample met the light: its base colour (0.78) is above that
    /// of every other Cornell box material (0.73 and less), so one sample on it in 64
    /// lifts the albedo layer's red by 0.05 / 64 > 5e-4.
    pub fn pixels_off_the_light(&self) -> Vec<usize> {
        let albedo = self.channel("albedo.R");
        (0..self.width * self.height)
            .filter(|&p| albedo[p] < 0.7305)
            .collect()
    }
}
