//! Kiln: a physically based path tracer whose kernel is WGSL run by wgpu.
//!
//! Data flows one way: a [`scene::Scene`] is loaded from a `.kiln` file, its meshes get
//! BVHs ([`accel`]), [`render::Renderer`] uploads both and accumulates samples on the GPU
//! into a [`film::Film`], which is tonemapped and written by [`film::output`].
//! Modules are layers that use only those below them: [`shader`] (the CPU–GPU contract),
//! [`material`], [`scene`], [`accel`], [`film`], [`render`], [`plugin`], [`bench`],
//! [`editor`] (`tests/architecture.rs` checks it). The library has no global state and never prints;
//! the `kiln` binary is its CLI.

pub mod accel;
pub mod bench;
pub mod editor;
pub mod farm;
pub mod film;
pub mod limits;
pub mod material;
pub mod plugin;
pub mod render;
pub mod scene;
pub mod shader;
