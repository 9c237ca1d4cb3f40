//! A binary BVH in the GPU layout, built from bounding boxes by obvhs.

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;

/// One node as `BvhNode` in `shaders/scene.wgsl`: inner nodes (`count == 0`) have their
/// children at `first` and `first + 1`; leaves hold primitives `first .. first + count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.min.into(), self.max.into())
    }
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Root first.
    pub nodes: Vec<BvhNode>,
    /// The input primitive index of every leaf slot: leaves index into this order, so
    /// primitives are stored in it.
    pub primitive_order: Vec<u32>,
    /// Largest number of nodes on a root-to-leaf path, counting both ends.
    pub depth: u32,
}

/// Builds a BVH over boxes given as (min, max). `max_leaf_size` bounds primitives per leaf.
pub fn build_bvh(boxes: &[(Vec3, Vec3)], max_leaf_size: u32) -> Bvh {
    assert!(!boxes.is_empty(), "a BVH needs at least one primitive");
    let aabbs: Vec<Aabb> = boxes
        .iter()
        .map(|&(lo, hi)| Aabb::new(Vec3A::from(lo), Vec3A::from(hi)))
        .collect();
    let params = BvhBuildParams {
        max_prims_per_leaf: max_leaf_size,
        ..BvhBuildParams::medium_build()
    };
    let mut build_time = std::time::Duration::ZERO;
    let bvh2 = obvhs::bvh2::builder::build_bvh2(&aabbs, params, &mut build_time);
    let nodes: Vec<BvhNode> = bvh2
        .nodes
        .iter()
        .map(|n| BvhNode {
            min: Vec3::from(n.aabb.min).into(),
            first: n.first_index,
            max: Vec3::from(n.aabb.max).into(),
            count: n.prim_count,
        })
        .collect();
    let depth = tree_depth(&nodes);
    Bvh {
        nodes,
        primitive_order: bvh2.primitive_indices,
        depth,
    }
}

fn tree_depth(nodes: &[BvhNode]) -> u32 {
    let mut max_depth = 0;
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, d)) = stack.pop() {
        max_depth = max_depth.max(d);
        let n = nodes[i];
        if n.count == 0 {
            stack.push((n.first as usize, d + 1));
            stack.push((n.first as usize + 1, d + 1));
        }
    }
    max_depth
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_boxes(n: usize) -> Vec<(Vec3, Vec3)> {
        let mut state = 0x9e37_79b9u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
                let h = Vec3::new(rnd(), rnd(), rnd()) * 0.3;
                (c - h, c + h)
            })
            .collect()
    }

    #[test]
    fn every_primitive_is_in_exactly_one_leaf_and_inside_its_bounds() {
        let boxes = random_boxes(5000);
        let bvh = build_bvh(&boxes, 4);
        let mut seen = vec![0u32; boxes.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = bvh.nodes[i];
            let (lo, hi) = n.bounds();
            if n.count == 0 {
                for c in [n.first as usize, n.first as usize + 1] {
                    let (clo, chi) = bvh.nodes[c].bounds();
                    assert!(
                        clo.cmpge(lo).all() && chi.cmple(hi).all(),
                        "child outside parent"
                    );
                    stack.push(c);
                }
            } else {
                assert!(n.count <= 4);
                for slot in n.first..n.first + n.count {
                    let p = bvh.primitive_order[slot as usize] as usize;
                    seen[p] += 1;
                    let (plo, phi) = boxes[p];
                    assert!(
                        plo.cmpge(lo).all() && phi.cmple(hi).all(),
                        "primitive outside leaf"
                    );
                }
            }
        }
        assert!(
            seen.iter().all(|&c| c == 1),
            "primitives missing or duplicated"
        );
        assert!(bvh.depth >= 2 && bvh.depth < 64, "depth {}", bvh.depth);
    }

    #[test]
    fn single_primitive_is_a_root_leaf() {
        let bvh = build_bvh(&[(Vec3::ZERO, Vec3::ONE)], 4);
        assert_eq!(bvh.nodes[0].count, 1);
        assert_eq!(bvh.depth, 1);
    }

    #[test]
    fn identical_boxes_still_give_a_shallow_tree() {
        let boxes = vec![(Vec3::ZERO, Vec3::ONE); 10_000];
        let bvh = build_bvh(&boxes, 4);
        assert!(bvh.depth <= 64, "depth {}", bvh.depth);
    }
}
