//! Triangle meshes with optional per-vertex normals and texture coordinates.

use glam::{Vec2, Vec3, Vec4};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Empty, or one unit normal per position.
    pub normals: Vec<Vec3>,
    /// Empty, or one coordinate per position.
    pub uvs: Vec<Vec2>,
    /// A second UV set (lightmaps, decals): empty, or one coordinate per position.
    pub uvs1: Vec<Vec2>,
    /// Empty, or one linear RGBA colour per position (the Color Attribute node; stored
    /// with 8 bits per channel, so clamped to [0, 1]).
    pub colors: Vec<Vec4>,
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.indices.is_empty() {
            return Err("has no triangles".into());
        }
        if self.positions.len() > u32::MAX as usize {
            return Err("has more than 2^32 vertices".into());
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("position {i} is not finite"));
        }
        if !self.normals.is_empty() && self.normals.len() != self.positions.len() {
            return Err(format!(
                "has {} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            ));
        }
        if let Some(i) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(format!("normal {i} is not finite"));
        }
        if !self.uvs.is_empty() && self.uvs.len() != self.positions.len() {
            return Err(format!(
                "has {} uvs for {} positions",
                self.uvs.len(),
                self.positions.len()
            ));
        }
        if let Some(i) = self.uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(format!("uv {i} is not finite"));
        }
        if !self.uvs1.is_empty() && self.uvs1.len() != self.positions.len() {
            return Err(format!(
                "has {} second-set uvs for {} positions",
                self.uvs1.len(),
                self.positions.len()
            ));
        }
        if let Some(i) = self.uvs1.iter().position(|uv| !uv.is_finite()) {
            return Err(format!("second-set uv {i} is not finite"));
        }
        if !self.colors.is_empty() && self.colors.len() != self.positions.len() {
            return Err(format!(
                "has {} colours for {} positions",
                self.colors.len(),
                self.positions.len()
            ));
        }
        let n = self.positions.len() as u32;
        if let Some((t, tri)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&i| i >= n))
        {
            return Err(format!(
                "triangle {t} has index {:?} but there are only {n} positions",
                tri
            ));
        }
        Ok(())
    }
}
