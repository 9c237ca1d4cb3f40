//! The GPU side: device ([`context`]), kernel assembly ([`kernel`]), scene upload
//! ([`gpu_scene`]) with the light-selection distributions ([`light_distribution`]) and
//! the environment map's CDF ([`environment_cdf`]), and the progressive [`Renderer`]
//! that accumulates samples into a film (on the device in pieces that each fit a binding)
//! in whole-image passes.
//!
//! What the renderer does not do: decide file formats, print, or own threads. Callers
//! (the CLI, benchmarks, tests) drive it in sample ranges and read the film back.

pub mod checkpoint;
pub mod context;
pub mod denoise;
pub mod environment_cdf;
mod export;
mod film_pieces;
pub mod gpu_scene;
pub mod kernel;
pub mod light_distribution;
pub mod materials;
pub mod probe;
pub mod prune;
mod readback;
mod renderer;
pub mod tables;
mod update;
pub mod volume_grid;
pub mod world_bake;

pub use context::{Backend, GpuContext, GpuError, release_free_host_memory};
pub use export::export_film;
pub use film_pieces::{DeviceFilm, memory_check};
pub use readback::map_and_read;
pub use renderer::{
    Aovs, BuildInfo, KernelKind, Pacing, Progress, RenderControl, RenderError, RenderSettings,
    RenderStats, Renderer, is_adaptive_check, next_adaptive_check,
};
pub use update::{UpdateError, Updated};
