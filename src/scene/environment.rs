//! Image-based lighting: an equirectangular HDR environment map (`.hdr` or `.exr`) with
//! strength and rotation. Directions map to the image with +Y up: the top row is straight
//! up, the middle column looks down −Z, and u grows toward +X (then +Z).

use std::path::Path;

use glam::Vec3;
use kiln_plugin_api::read::{MAX_FILE_BYTES, read_bounded};

#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    /// Linear RGB radiance, row-major from the top row.
    pub texels: Vec<Vec3>,
    pub strength: f32,
    /// Rotation about +Y in degrees.
    pub rotation_degrees: f32,
}

impl EnvironmentMap {
    /// Loads an equirectangular image; formats by extension (`.hdr`, `.exr`). Only a
    /// regular file of at most [`MAX_FILE_BYTES`] is read.
    pub fn load(path: &Path) -> Result<Self, String> {
        let bytes = read_bounded(path, MAX_FILE_BYTES).map_err(|e| e.to_string())?;
        let format = image::ImageFormat::from_path(path).map_err(|e| e.to_string())?;
        let image = image::load_from_memory_with_format(&bytes, format)
            .map_err(|e| e.to_string())?
            .to_rgb32f();
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| Vec3::from(p.0)).collect();
        let map = Self {
            width,
            height,
            texels,
            strength: 1.0,
            rotation_degrees: 0.0,
        };
        map.validate()?;
        Ok(map)
    }

    /// A map of one colour (tests, and a constant sky through the map path).
    pub fn constant(colour: Vec3, width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            texels: vec![colour; (width * height) as usize],
            strength: 1.0,
            rotation_degrees: 0.0,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0
            || self.height == 0
            || self.texels.len() != (self.width * self.height) as usize
        {
            return Err(format!(
                "environment map of {}x{} has {} texels",
                self.width,
                self.height,
                self.texels.len()
            ));
        }
        let size = crate::limits::current().texture_size;
        let half = (size / 2).max(1);
        if self.width > size || self.height > half {
            return Err(format!(
                "environment map of {}x{} is larger than {size}x{half} (--max-texture-size raises the limit)",
                self.width, self.height
            ));
        }
        if let Some(i) = self
            .texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(format!(
                "environment map texel {i} is negative or not finite"
            ));
        }
        if !(self.strength.is_finite() && self.strength >= 0.0 && self.rotation_degrees.is_finite())
        {
            return Err(
                "environment map strength must be finite and non-negative, rotation finite".into(),
            );
        }
        Ok(())
    }
}
