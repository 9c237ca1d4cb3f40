//! The four-wide BVH the kernel walks, collapsed from a binary one (Wald et al., "Getting
//! Rid of Packets", 2008; pbrt-v4 and Embree collapse the same way): each wide node takes
//! its binary node's two children, then keeps opening the child with the largest surface
//! area until it has four; each child's box is quantised to bytes ([`WideNode`]). On a
//! software rasteriser a traversal step costs about the texels it fetches: four texels for
//! four children here, where a binary step fetched four for two (docs/BENCHMARKS.md).

use glam::Vec3;

use super::bvh::BvhNode;
use crate::shader::gpu_types::{WIDE_COUNT_SHIFT, WIDE_EMPTY, WideNode};

/// The largest primitive count a leaf's reference holds.
pub const WIDE_MAX_LEAF: u32 = (1 << (32 - WIDE_COUNT_SHIFT)) - 1;
/// A reference's index mask; indices stay below it, so no reference is `WIDE_EMPTY`.
pub const WIDE_INDEX_LIMIT: u32 = (1 << WIDE_COUNT_SHIFT) - 1;

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// Root first; children's references are relative to this tree (node indices into
    /// `nodes`, primitive indices into the binary BVH's `primitive_order`).
    pub nodes: Vec<WideNode>,
    /// Entries the kernel's traversal stack needs at most: a step on a node of two or
    /// more children writes the children an ancestor left pending as one entry, so on the
    /// worst root-to-leaf path, one for each such node but the last.
    pub stack_need: u32,
}

/// The binary nodes that become `node`'s wide children.
fn open(nodes: &[BvhNode], node: usize) -> Vec<usize> {
    let n = nodes[node];
    if n.count > 0 {
        // A leaf root: one child, the leaf itself.
        return vec![node];
    }
    let mut children = vec![n.first as usize, n.first as usize + 1];
    while children.len() < 4 {
        let widest = (0..children.len())
            .filter(|&i| nodes[children[i]].count == 0)
            .max_by(|&a, &b| {
                (nodes[children[a]].half_area()).total_cmp(&nodes[children[b]].half_area())
            });
        let Some(i) = widest else { break };
        let inner = nodes[children.swap_remove(i)];
        children.extend([inner.first as usize, inner.first as usize + 1]);
    }
    children
}

/// `origin + q * unit`, as the kernel computes it: the product is exact (a byte times a
/// power of two), so the sum is rounded once, the same with or without a fused
/// multiply-add. Subnormal results count as 0, as a GPU that flushes them sees them.
fn decode(origin: f32, q: u32, unit: f32) -> f32 {
    let v = origin + q as f32 * unit;
    if v.abs() < f32::MIN_POSITIVE { 0.0 } else { v }
}

/// `2^e`, for `e` in -126..=127.
fn power_of_two(e: i32) -> f32 {
    f32::from_bits(((e + 127) as u32) << 23)
}

/// A wide node over `boxes` (one per used slot) with references `child`: per axis, the
/// smallest power-of-two step whose 255 steps from the lowest bound reach the highest, and
/// each bound rounded outwards to a whole step, checked against the decoded value.
fn quantize(boxes: &[(Vec3, Vec3)], child: [u32; 4]) -> WideNode {
    let lo = boxes.iter().fold(Vec3::INFINITY, |a, b| a.min(b.0));
    let hi = boxes.iter().fold(Vec3::NEG_INFINITY, |a, b| a.max(b.1));
    let mut node = WideNode {
        origin: lo.into(),
        child,
        ..WideNode::default()
    };
    // [lo x, lo y, lo z, hi x, hi y, hi z], a byte per slot.
    let mut bytes = [0u32; 6];
    for axis in 0..3 {
        let (origin, top) = (lo[axis], hi[axis]);
        let extent = top - origin;
        let mut e = if extent > 0.0 && extent.is_finite() {
            ((extent / 255.0).log2().ceil() as i32).clamp(-126, 127)
        } else {
            -126
        };
        while e < 127 && decode(origin, 255, power_of_two(e)) < top {
            e += 1;
        }
        let unit = power_of_two(e);
        node.exponents |= ((e + 127) as u32) << (8 * axis);
        for slot in 0..4 {
            let (q_lo, q_hi) = match boxes.get(slot) {
                // An empty slot: an inverted box (the kernel skips it by its reference).
                None => (255, 0),
                Some((b_lo, b_hi)) => {
                    let mut q_lo = (((b_lo[axis] - origin) / unit).floor() as u32).min(255);
                    while q_lo > 0 && decode(origin, q_lo, unit) > b_lo[axis] {
                        q_lo -= 1;
                    }
                    let mut q_hi = (((b_hi[axis] - origin) / unit).ceil() as u32).min(255);
                    while q_hi < 255 && decode(origin, q_hi, unit) < b_hi[axis] {
                        q_hi += 1;
                    }
                    (q_lo, q_hi)
                }
            };
            bytes[axis] |= q_lo << (8 * slot);
            bytes[3 + axis] |= q_hi << (8 * slot);
        }
    }
    node.steps = [
        [bytes[0], bytes[1], bytes[2], bytes[3]],
        [bytes[4], bytes[5], 0, 0],
    ];
    node
}

/// `nodes` (a binary BVH, root first, leaves of at most [`WIDE_MAX_LEAF`] primitives)
/// collapsed into wide nodes.
pub fn widen(nodes: &[BvhNode]) -> WideBvh {
    let mut wide = vec![WideNode::default()];
    let mut stack_need = 0;
    // (wide node, its binary node, nodes of two or more children above it)
    let mut work = vec![(0usize, 0usize, 0u32)];
    while let Some((w, b, above)) = work.pop() {
        let children = open(nodes, b);
        let pushes = above + u32::from(children.len() > 1);
        stack_need = stack_need.max(pushes.saturating_sub(1));
        let mut child = [WIDE_EMPTY; 4];
        for (slot, &c) in children.iter().enumerate() {
            let n = nodes[c];
            child[slot] = if n.count > 0 {
                debug_assert!(n.count <= WIDE_MAX_LEAF, "a leaf of {} primitives", n.count);
                n.count << WIDE_COUNT_SHIFT | n.first
            } else {
                let index = wide.len();
                wide.push(WideNode::default());
                work.push((index, c, pushes));
                index as u32
            };
        }
        let boxes: Vec<(Vec3, Vec3)> = children.iter().map(|&c| nodes[c].bounds()).collect();
        let out = quantize(&boxes, child);
        wide[w] = out;
    }
    WideBvh {
        nodes: wide,
        stack_need,
    }
}

impl WideBvh {
    /// Where traversal enters the tree: the root (0), or the root's only child when that
    /// is a leaf, so a mesh of a few triangles costs no node fetch.
    pub fn entry(&self) -> u32 {
        let [first, second, ..] = self.nodes[0].child;
        if second == WIDE_EMPTY && first >> WIDE_COUNT_SHIFT > 0 {
            first
        } else {
            0
        }
    }
}

/// `child` with its index moved by `nodes` (inner nodes) or `primitives` (leaves).
pub fn rebase(child: u32, nodes: u32, primitives: u32) -> u32 {
    if child == WIDE_EMPTY {
        child
    } else if child >> WIDE_COUNT_SHIFT == 0 {
        child + nodes
    } else {
        child + primitives
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::build_bvh;
    use crate::accel::bvh::tests::random_boxes;

    /// The box of slot `slot` of `node`, as the kernel decodes it.
    fn decoded_box(node: &WideNode, slot: usize) -> (Vec3, Vec3) {
        let byte = |word: u32| (word >> (8 * slot)) & 255;
        let unit = |axis: usize| power_of_two(((node.exponents >> (8 * axis)) & 255) as i32 - 127);
        let lo_words = [node.steps[0][0], node.steps[0][1], node.steps[0][2]];
        let hi_words = [node.steps[0][3], node.steps[1][0], node.steps[1][1]];
        let axis = |words: [u32; 3]| {
            Vec3::from_array(std::array::from_fn(|a| {
                decode(node.origin[a], byte(words[a]), unit(a))
            }))
        };
        (axis(lo_words), axis(hi_words))
    }

    /// Walks the wide tree: every primitive in exactly one leaf and inside the decoded box
    /// of every node above it, and no path needing more stack than `stack_need` (an entry
    /// for every node of two or more children on it but the last).
    fn check(boxes: &[(Vec3, Vec3)], max_leaf: u32) -> (usize, usize) {
        let bvh = build_bvh(boxes, max_leaf);
        let wide = &bvh.wide;
        let mut seen = vec![0u32; boxes.len()];
        let mut need = 0;
        let mut work = vec![(0usize, None::<(Vec3, Vec3)>, 0u32)];
        while let Some((w, parent, above)) = work.pop() {
            let n = wide.nodes[w];
            let used = n.child.iter().filter(|&&c| c != WIDE_EMPTY).count() as u32;
            assert!(used >= 1 && n.child[..used as usize].iter().all(|&c| c != WIDE_EMPTY));
            let pushes = above + u32::from(used > 1);
            need = need.max(pushes.saturating_sub(1));
            for slot in 0..used as usize {
                // What a ray must pass through to reach this child: its decoded box and
                // every ancestor's.
                let (mut lo, mut hi) = decoded_box(&n, slot);
                if let Some((plo, phi)) = parent {
                    (lo, hi) = (lo.max(plo), hi.min(phi));
                }
                let c = n.child[slot];
                let count = c >> WIDE_COUNT_SHIFT;
                if count == 0 {
                    work.push((c as usize, Some((lo, hi)), pushes));
                    continue;
                }
                let first = c & WIDE_INDEX_LIMIT;
                for p in first..first + count {
                    let prim = bvh.primitive_order[p as usize] as usize;
                    seen[prim] += 1;
                    let (blo, bhi) = boxes[prim];
                    assert!(
                        blo.cmpge(lo).all() && bhi.cmple(hi).all(),
                        "primitive outside a box above it"
                    );
                }
            }
        }
        assert!(
            seen.iter().all(|&s| s == 1),
            "a primitive missing or repeated"
        );
        assert_eq!(need, wide.stack_need);
        (wide.nodes.len(), bvh.nodes.len())
    }

    #[test]
    fn collapsed_trees_hold_every_primitive_once_inside_their_boxes() {
        let (wide, binary) = check(&random_boxes(5000), 4);
        // Three binary inner nodes fold into one wide node where the tree is full.
        assert!(
            wide * 4 < binary,
            "{wide} wide nodes for {binary} binary ones"
        );
        check(&random_boxes(3), 4);
        check(&random_boxes(7), 1);
    }

    #[test]
    fn quantised_boxes_hold_their_children_within_one_step() {
        let cases: [[(Vec3, Vec3); 3]; 4] = [
            // Ordinary boxes.
            [
                (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(0.5, 0.25, 3.0)),
                (Vec3::new(0.1, -4.0, 2.5), Vec3::new(0.7, 1.0, 2.75)),
                (Vec3::new(-0.3, 0.0, 2.0), Vec3::new(-0.2, 0.0, 2.0)),
            ],
            // Far from the origin with tiny extents: rounding in the decode decides.
            [
                (Vec3::splat(1.0e7), Vec3::splat(1.0e7 + 1.0)),
                (Vec3::splat(1.0e7 + 0.5), Vec3::splat(1.0e7 + 2.0)),
                (Vec3::splat(-1.0e7), Vec3::splat(-1.0e7)),
            ],
            // Flat on one axis (a wall) and huge on another.
            [
                (Vec3::new(0.0, 5.0, -3.0e30), Vec3::new(1.0, 5.0, 3.0e30)),
                (Vec3::new(0.5, 5.0, 0.0), Vec3::new(0.75, 5.0, 1.0)),
                (Vec3::new(1.0e-30, 5.0, 1.0), Vec3::new(2.0e-30, 5.0, 2.0)),
            ],
            // Subnormal bounds.
            [
                (Vec3::splat(1.0e-40), Vec3::splat(3.0e-40)),
                (Vec3::splat(-1.0e-40), Vec3::splat(0.0)),
                (Vec3::ZERO, Vec3::splat(1.0e-39)),
            ],
        ];
        for boxes in cases {
            let node = quantize(&boxes, [1, 2, 3, WIDE_EMPTY]);
            for (slot, (lo, hi)) in boxes.iter().enumerate() {
                let (qlo, qhi) = decoded_box(&node, slot);
                let unit = Vec3::from_array(std::array::from_fn(|a| {
                    power_of_two(((node.exponents >> (8 * a)) & 255) as i32 - 127)
                }));
                let (lo, hi) = (lo.map(flush), hi.map(flush));
                assert!(
                    qlo.cmple(lo).all() && qhi.cmpge(hi).all(),
                    "{boxes:?} slot {slot}: {qlo} {qhi}"
                );
                // A step, one more where a subnormal decodes as 0, and the rounding of the
                // bound itself.
                let slack = 2.0 * unit + lo.abs().max(hi.abs()) * f32::EPSILON;
                assert!(
                    (lo - qlo).cmple(slack).all(),
                    "{boxes:?} slot {slot}: lo {qlo}"
                );
                assert!(
                    (qhi - hi).cmple(slack).all(),
                    "{boxes:?} slot {slot}: hi {qhi}"
                );
            }
        }
    }

    fn flush(v: f32) -> f32 {
        if v.abs() < f32::MIN_POSITIVE { 0.0 } else { v }
    }

    #[test]
    fn a_single_leaf_becomes_a_root_with_one_child() {
        let (wide, _) = check(&random_boxes(1), 4);
        assert_eq!(wide, 1);
        assert_eq!(
            build_bvh(&random_boxes(1), 4).wide.entry(),
            1 << WIDE_COUNT_SHIFT
        );
        assert_eq!(build_bvh(&random_boxes(50), 4).wide.entry(), 0);
    }

    #[test]
    fn rebasing_moves_nodes_and_primitives_apart_and_keeps_empty_slots() {
        assert_eq!(rebase(5, 100, 1000), 105);
        let leaf = 3 << WIDE_COUNT_SHIFT | 7;
        assert_eq!(rebase(leaf, 100, 1000), 3 << WIDE_COUNT_SHIFT | 1007);
        assert_eq!(rebase(WIDE_EMPTY, 100, 1000), WIDE_EMPTY);
    }
}
