//! The two-level structure: a BVH per mesh in object space and one over instances in
//! world space. A mesh used by many instances gets one BLAS.

use std::time::{Duration, Instant};

use glam::Vec3;
use thiserror::Error;

use super::{
    BLAS_STACK_SIZE, Bvh, STACK_NODE_LIMIT, TLAS_STACK_SIZE, WIDE_INDEX_LIMIT, WIDE_MAX_LEAF,
    build_bvh,
};
use crate::scene::Scene;

/// Triangles per BLAS leaf at most; SAH makes smaller leaves where they pay.
const BLAS_MAX_LEAF_SIZE: u32 = 4;
/// Instances per TLAS leaf: exactly one (`build_bvh` splits coincident boxes too), and
/// the kernel's traversal reads one instance per leaf without a loop
/// (`traverse_scene` in shaders/traverse.wgsl): on lavapipe a loop around the BLAS
/// traversal cost 15–19 % of the Cornell box's time (docs/BENCHMARKS.md).
const TLAS_MAX_LEAF_SIZE: u32 = 1;
const _: () = assert!(BLAS_MAX_LEAF_SIZE <= WIDE_MAX_LEAF && TLAS_MAX_LEAF_SIZE == 1);

#[derive(Debug, Error)]
pub enum AccelError {
    #[error(
        "the BVH of {what} needs a traversal stack of {depth} entries, more than the kernel's {limit}"
    )]
    TooDeep {
        what: String,
        depth: u32,
        limit: u32,
    },
    #[error("instance {instance} uses mesh {mesh}, which has no BVH in this structure")]
    MissingBlas { instance: usize, mesh: usize },
    #[error(
        "the scene's BVHs hold {count} {what}, more than the kernel's node references can address ({limit})"
    )]
    TooLarge {
        what: &'static str,
        count: u64,
        limit: u32,
    },
}

#[derive(Clone, Debug)]
pub struct SceneAccel {
    /// One per mesh of the scene; `None` for meshes no instance uses.
    pub blas: Vec<Option<Bvh>>,
    /// Over instances; `None` when the scene has none.
    pub tlas: Option<Bvh>,
    pub build_time: Duration,
}

pub fn build_scene_accel(scene: &Scene) -> Result<SceneAccel, AccelError> {
    let start = Instant::now();
    let mut used = vec![false; scene.meshes.len()];
    for inst in &scene.instances {
        used[inst.mesh] = true;
    }
    let mut blas = Vec::with_capacity(scene.meshes.len());
    for (mesh, used) in scene.meshes.iter().zip(used) {
        if !used {
            blas.push(None);
            continue;
        }
        let boxes: Vec<(Vec3, Vec3)> = (0..mesh.indices.len())
            .map(|i| {
                let [a, b, c] = mesh.triangle(i);
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let bvh = build_bvh(&boxes, BLAS_MAX_LEAF_SIZE);
        if bvh.wide.stack_need > BLAS_STACK_SIZE {
            return Err(AccelError::TooDeep {
                what: format!("mesh \"{}\"", mesh.name),
                depth: bvh.wide.stack_need,
                limit: BLAS_STACK_SIZE,
            });
        }
        blas.push(Some(bvh));
    }

    // The kernel addresses every mesh's nodes and triangles in one table each.
    let built = || blas.iter().flatten();
    for (what, count, limit) in [
        (
            "nodes",
            built().map(|b| b.wide.nodes.len() as u64).sum(),
            STACK_NODE_LIMIT,
        ),
        (
            "triangles",
            built().map(|b| b.primitive_order.len() as u64).sum(),
            WIDE_INDEX_LIMIT,
        ),
    ] {
        if count >= u64::from(limit) {
            return Err(AccelError::TooLarge { what, count, limit });
        }
    }
    let tlas = build_tlas(scene, &blas)?;
    Ok(SceneAccel {
        blas,
        tlas,
        build_time: start.elapsed(),
    })
}

/// The BVH over `scene`'s instances in world space, given the BLAS of each mesh
/// (`SceneAccel::blas`, which must hold one for every instanced mesh); `None` without
/// instances. A transform edit rebuilds only this: the meshes' BVHs stay as they are.
pub fn build_tlas(scene: &Scene, blas: &[Option<Bvh>]) -> Result<Option<Bvh>, AccelError> {
    if scene.instances.is_empty() {
        return Ok(None);
    }
    if scene.instances.len() >= WIDE_INDEX_LIMIT as usize {
        return Err(AccelError::TooLarge {
            what: "instances",
            count: scene.instances.len() as u64,
            limit: WIDE_INDEX_LIMIT,
        });
    }
    let mut boxes: Vec<(Vec3, Vec3)> = Vec::with_capacity(scene.instances.len());
    for (i, inst) in scene.instances.iter().enumerate() {
        let root = blas
            .get(inst.mesh)
            .and_then(Option::as_ref)
            .ok_or(AccelError::MissingBlas {
                instance: i,
                mesh: inst.mesh,
            })?
            .nodes[0];
        let (lo, hi) = root.bounds();
        let mut wlo = Vec3::splat(f32::INFINITY);
        let mut whi = Vec3::splat(f32::NEG_INFINITY);
        for corner in 0..8 {
            let p = Vec3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            let w = inst.transform.transform_point3(p);
            wlo = wlo.min(w);
            whi = whi.max(w);
        }
        // Rounding in the transform may move a vertex past the exact corners.
        let pad = (whi - wlo).max(wlo.abs().max(whi.abs())) * 1e-6;
        boxes.push((wlo - pad, whi + pad));
    }
    let bvh = build_bvh(&boxes, TLAS_MAX_LEAF_SIZE);
    if bvh.wide.nodes.len() >= STACK_NODE_LIMIT as usize {
        return Err(AccelError::TooLarge {
            what: "instance BVH nodes",
            count: bvh.wide.nodes.len() as u64,
            limit: STACK_NODE_LIMIT,
        });
    }
    if bvh.wide.stack_need > TLAS_STACK_SIZE {
        return Err(AccelError::TooDeep {
            what: "the instances".into(),
            depth: bvh.wide.stack_need,
            limit: TLAS_STACK_SIZE,
        });
    }
    Ok(Some(bvh))
}
