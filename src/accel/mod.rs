//! Acceleration structures, built on the CPU: one BVH per mesh (BLAS) and one over the
//! instances (TLAS), laid out as the kernel's `shaders/traverse.wgsl` walks them.
//!
//! Trees are built top-down with binned SAH ([`bvh`]) straight into the flat GPU node
//! layout, and checked against the depth of the kernel's traversal stacks.

mod bvh;
pub mod query;
mod two_level;

pub use bvh::{Bvh, build_bvh};
pub use two_level::{AccelError, SceneAccel, build_scene_accel, build_tlas};

/// Traversal stack sizes of `shaders/traverse.wgsl`; a deeper tree cannot be traversed.
pub const BLAS_STACK_SIZE: u32 = 64;
pub const TLAS_STACK_SIZE: u32 = 48;
