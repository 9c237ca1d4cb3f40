//! A binary BVH in the GPU layout, built top-down with binned SAH (Wald 2007, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies").
//!
//! Why not a crate: obvhs (PLOC) was the first choice and is faster, but on coincident
//! primitives (a mesh with thousands of stacked duplicate triangles, which real exports
//! contain) it degenerates into a linear chain as deep as the primitive count, which no
//! GPU traversal stack can hold and whose debug validation overflows the CPU stack. This
//! builder falls back to a median split wherever SAH cannot separate primitives, so its
//! depth stays logarithmic for any input, and it never recurses.

use glam::Vec3;

use super::wide::{WideBvh, widen};

/// A node of a binary BVH (the CPU's queries walk these; the kernel walks them collapsed
/// into [`WideNode`]s): inner nodes (`count == 0`) have their children at `first` and
/// `first + 1`; leaves hold primitives `first .. first + count`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn bounds(&self) -> (glam::Vec3, glam::Vec3) {
        (self.min.into(), self.max.into())
    }

    /// Half the surface area of its box, as the builder's SAH weighs boxes.
    pub(super) fn half_area(&self) -> f32 {
        Aabb {
            lo: self.min.into(),
            hi: self.max.into(),
        }
        .half_area()
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
    /// The same tree collapsed four-wide, as the kernel walks it.
    pub wide: WideBvh,
}

const BINS: usize = 16;
/// Cost of a node visit relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

#[derive(Clone, Copy)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Self = Self {
        lo: Vec3::splat(f32::INFINITY),
        hi: Vec3::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, lo: Vec3, hi: Vec3) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// Builds a BVH over boxes given as (min, max). `max_leaf_size` bounds primitives per leaf.
pub fn build_bvh(boxes: &[(Vec3, Vec3)], max_leaf_size: u32) -> Bvh {
    assert!(!boxes.is_empty(), "a BVH needs at least one primitive");
    let max_leaf = max_leaf_size.max(1) as usize;
    let centroids: Vec<Vec3> = boxes.iter().map(|(lo, hi)| (*lo + *hi) * 0.5).collect();
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![BvhNode::default()];
    let mut depth = 0;
    // (node, first, end, depth)
    let mut work = vec![(0usize, 0usize, boxes.len(), 1u32)];
    while let Some((node, first, end, d)) = work.pop() {
        depth = depth.max(d);
        let mut bounds = Aabb::EMPTY;
        let mut centroid_bounds = Aabb::EMPTY;
        for &p in &order[first..end] {
            let (lo, hi) = boxes[p as usize];
            bounds.grow(lo, hi);
            let c = centroids[p as usize];
            centroid_bounds.grow(c, c);
        }
        nodes[node].min = bounds.lo.into();
        nodes[node].max = bounds.hi.into();
        let count = end - first;
        let split = if count <= 1 {
            None
        } else {
            choose_split(
                boxes,
                &centroids,
                &mut order[first..end],
                bounds,
                centroid_bounds,
                max_leaf,
            )
        };
        match split {
            None => {
                nodes[node].first = first as u32;
                nodes[node].count = count as u32;
            }
            Some(mid) => {
                let left = nodes.len();
                nodes.push(BvhNode::default());
                nodes.push(BvhNode::default());
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                work.push((left + 1, first + mid, end, d + 1));
                work.push((left, first, first + mid, d + 1));
            }
        }
    }
    let wide = widen(&nodes);
    Bvh {
        nodes,
        primitive_order: order,
        depth,
        wide,
    }
}

/// Partitions `prims` and returns the size of the left part, or `None` for a leaf.
fn choose_split(
    boxes: &[(Vec3, Vec3)],
    centroids: &[Vec3],
    prims: &mut [u32],
    bounds: Aabb,
    centroid_bounds: Aabb,
    max_leaf: usize,
) -> Option<usize> {
    let count = prims.len();
    let extent = centroid_bounds.hi - centroid_bounds.lo;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of =
            |c: Vec3| (((c[axis] - centroid_bounds.lo[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for &p in prims.iter() {
            let b = bin_of(centroids[p as usize]);
            let (lo, hi) = boxes[p as usize];
            bin_bounds[b].grow(lo, hi);
            bin_counts[b] += 1;
        }
        // Sweep from the right, then evaluate each plane from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for b in (1..BINS).rev() {
            acc.grow(bin_bounds[b].lo, bin_bounds[b].hi);
            n += bin_counts[b];
            right_area[b] = acc.half_area();
            right_count[b] = n;
        }
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for b in 0..BINS - 1 {
            acc.grow(bin_bounds[b].lo, bin_bounds[b].hi);
            n += bin_counts[b];
            if n == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * n as f32 + right_area[b + 1] * right_count[b + 1] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let parent_area = bounds.half_area();
    let leaf_cost = count as f32;
    match best {
        Some((cost, axis, bin)) => {
            let split_cost = TRAVERSAL_COST + cost / parent_area.max(f32::MIN_POSITIVE);
            if count <= max_leaf && split_cost >= leaf_cost {
                return None;
            }
            let scale = BINS as f32 / extent[axis];
            let lo = centroid_bounds.lo[axis];
            let mut mid = 0;
            for i in 0..count {
                let c = centroids[prims[i] as usize][axis];
                if (((c - lo) * scale) as usize).min(BINS - 1) <= bin {
                    prims.swap(i, mid);
                    mid += 1;
                }
            }
            Some(mid)
        }
        // Every centroid in one point (coincident primitives): SAH cannot tell them apart,
        // so split in the middle of the list, which keeps the tree balanced.
        None if count > max_leaf => Some(count / 2),
        None => None,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// `n` boxes up to 0.6 wide scattered over a cube of side 10, the same every call.
    pub fn random_boxes(n: usize) -> Vec<(Vec3, Vec3)> {
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
        assert!(bvh.depth <= 14, "depth {}", bvh.depth);
    }
}
