//! Acceleration structures, built on the CPU: one BVH per mesh (BLAS) and one over the
//! instances (TLAS), laid out as the kernel's `shaders/traverse.wgsl` walks them.
//!
//! Trees are built top-down with binned SAH ([`bvh`]) into a flat binary layout, which the
//! CPU's queries walk, collapsed four-wide for the kernel ([`wide`]), and checked against
//! the kernel's traversal stacks.

mod bvh;
pub mod query;
mod two_level;
mod wide;

pub use bvh::{Bvh, BvhNode, build_bvh};
pub use two_level::{AccelError, SceneAccel, build_scene_accel, build_tlas};
pub use wide::{WIDE_INDEX_LIMIT, WIDE_MAX_LEAF, WideBvh, rebase, widen};

/// Traversal stack sizes of `shaders/traverse.wgsl`; a tree whose wide form needs more
/// ([`WideBvh::stack_need`]) cannot be traversed.
pub const BLAS_STACK_SIZE: u32 = 96;
pub const TLAS_STACK_SIZE: u32 = 64;
/// Node indices of each level stay below this: a traversal stack entry packs a node's
/// index in 24 bits (`pack_pending` in `shaders/traverse.wgsl`).
pub const STACK_NODE_LIMIT: u32 = 1 << 24;
