//! Resource limits: the sizes past which Kiln refuses its input with an error naming the
//! limit and the flag that raises it, instead of exhausting memory on a malformed or
//! hostile file (docs/RELIABILITY.md lists them with what each guards against).
//!
//! They are process-wide, like a thread pool's size: `kiln` sets them from its flags
//! (`--max-texture-size`, `--max-triangles`, `--max-graph-nodes`, `--max-group-depth`)
//! before it reads anything, and every loader and the material compiler read them where
//! they check. The triangle limit also goes to importer plugins, through the environment
//! (`kiln_plugin_api::MAX_TRIANGLES_ENV`), so that they refuse a file's claimed counts
//! before allocating them.

use std::sync::atomic::{AtomicU32, AtomicU64, AtomicUsize, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// The largest width or height of an image texture, and of an environment map (whose
    /// height may be half of it).
    pub texture_size: u32,
    /// Vertices, and triangles, one import may hand over in total, and a scene file's
    /// meshes may hold together.
    pub triangles: u64,
    /// Nodes a material graph may expand to, every use of a group counted with its nodes.
    pub graph_nodes: usize,
    /// How deep node groups may nest.
    pub group_depth: usize,
}

impl Limits {
    pub const DEFAULT: Self = Self {
        texture_size: 16384,
        triangles: kiln_plugin_api::DEFAULT_MAX_TRIANGLES,
        graph_nodes: 10_000,
        group_depth: 16,
    };
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

static TEXTURE_SIZE: AtomicU32 = AtomicU32::new(Limits::DEFAULT.texture_size);
static TRIANGLES: AtomicU64 = AtomicU64::new(Limits::DEFAULT.triangles);
static GRAPH_NODES: AtomicUsize = AtomicUsize::new(Limits::DEFAULT.graph_nodes);
static GROUP_DEPTH: AtomicUsize = AtomicUsize::new(Limits::DEFAULT.group_depth);

/// The limits in force.
pub fn current() -> Limits {
    Limits {
        texture_size: TEXTURE_SIZE.load(Ordering::Relaxed),
        triangles: TRIANGLES.load(Ordering::Relaxed),
        graph_nodes: GRAPH_NODES.load(Ordering::Relaxed),
        group_depth: GROUP_DEPTH.load(Ordering::Relaxed),
    }
}

/// Puts `limits` in force for the rest of the process.
pub fn set(limits: Limits) {
    TEXTURE_SIZE.store(limits.texture_size, Ordering::Relaxed);
    TRIANGLES.store(limits.triangles, Ordering::Relaxed);
    GRAPH_NODES.store(limits.graph_nodes, Ordering::Relaxed);
    GROUP_DEPTH.store(limits.group_depth, Ordering::Relaxed);
}
