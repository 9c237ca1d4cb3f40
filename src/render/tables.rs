//! Data tables the BSDFs read from a uniform buffer (see `shaders/bsdf/dielectric_energy.wgsl`).

mod dielectric_energy;

pub use dielectric_energy::DIELECTRIC_ENERGY;

/// Entries per axis of the dielectric energy table: cos θo, roughness, IOR.
pub const DIELECTRIC_ENERGY_SIZE: usize = 16;
/// The table's IOR axis covers (η - 1) / (η + 1) from 0 to this, η from 1 to 4.
pub const DIELECTRIC_ENERGY_MAX_F: f32 = 0.6;
