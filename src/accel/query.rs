//! What the CPU asks of the BVHs the renderer builds: the nearest surface along a ray
//! (the editor's click-to-select) and which closed objects hold a point (the media around
//! the camera, which paths start inside).

use std::collections::BTreeMap;

use glam::{Affine3A, Vec3};

use super::Bvh;
use super::BvhNode;
use crate::scene::Scene;

fn hit_box(node: &BvhNode, origin: Vec3, inv_dir: Vec3, t_max: f32) -> bool {
    let (lo, hi) = node.bounds();
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element();
    near <= far && near < t_max
}

/// Möller–Trumbore; the distance along `dir` when the ray meets the triangle (either side).
pub fn hit_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// Visits the leaves of `bvh` the ray may reach, nearest-first pruning: `leaf(primitive,
/// t_max)` returns a nearer hit distance when it finds one. Returns the nearest distance
/// found (`t_max` when none).
pub fn traverse(
    bvh: &Bvh,
    origin: Vec3,
    dir: Vec3,
    mut t_max: f32,
    mut leaf: impl FnMut(usize, f32) -> Option<f32>,
) -> f32 {
    let inv_dir = dir.recip();
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes[i];
        if !hit_box(node, origin, inv_dir, t_max) {
            continue;
        }
        if node.count > 0 {
            let first = node.first as usize;
            for &primitive in &bvh.primitive_order[first..first + node.count as usize] {
                if let Some(t) = leaf(primitive as usize, t_max) {
                    t_max = t_max.min(t);
                }
            }
        } else {
            stack.push(node.first as usize);
            stack.push(node.first as usize + 1);
        }
    }
    t_max
}

/// Three directions no two of which lie in a plane of the axes, for inside tests: a ray
/// that grazes an edge or a vertex (and so counts a crossing twice or not at all) is
/// outvoted by the other two.
const PARITY_DIRECTIONS: [Vec3; 3] = [
    Vec3::new(0.267_261_24, 0.534_522_5, 0.801_783_7),
    Vec3::new(-0.801_783_7, 0.267_261_24, -0.534_522_5),
    Vec3::new(0.534_522_5, -0.801_783_7, 0.267_261_24),
];

/// Whether `point` (object space) is inside the closed mesh of `triangles` under `bvh`:
/// an odd number of crossings along a ray, by a vote of three rays.
fn inside(bvh: &Bvh, triangles: &[[Vec3; 3]], point: Vec3) -> bool {
    let votes = PARITY_DIRECTIONS
        .iter()
        .filter(|&&dir| {
            let mut crossings = 0u32;
            traverse(bvh, point, dir, f32::INFINITY, |t, _| {
                crossings += hit_triangle(point, dir, triangles[t]).is_some() as u32;
                None
            });
            crossings % 2 == 1
        })
        .count();
    votes >= 2
}

/// An instance whose inside holds a medium, placed.
struct Enclosure {
    /// Its index in the kernel's instance array.
    gpu_index: u32,
    mesh: usize,
    to_object: Affine3A,
    /// World-space bounds.
    lo: Vec3,
    hi: Vec3,
}

/// The instances a path starting inside them starts in the medium of: those whose
/// material holds a medium inside a closed surface (a volume, or a transmissive surface:
/// glass, water). A renderer keeps one to find the media around its camera.
#[derive(Default)]
pub struct Enclosures {
    list: Vec<Enclosure>,
    /// The triangles (in mesh order) of every mesh an enclosure uses.
    triangles: BTreeMap<usize, Vec<[Vec3; 3]>>,
    /// The scene index of each of the kernel's instances.
    gpu_order: Vec<u32>,
}

impl Enclosures {
    /// The enclosures of `scene`, whose instances the kernel holds in `gpu_order` (the
    /// scene index of each of its instances: the TLAS's primitive order).
    pub fn new(scene: &Scene, blas: &[Option<Bvh>], gpu_order: &[u32]) -> Self {
        let mut enclosures = Self::default();
        enclosures.place(scene, blas, gpu_order);
        enclosures
    }

    /// Places them again after an edit of `scene`'s instances or materials (its meshes
    /// unchanged); `gpu_order` as for [`Enclosures::new`], `None` when it is unchanged.
    /// Only meshes not held already are copied.
    pub fn place(&mut self, scene: &Scene, blas: &[Option<Bvh>], gpu_order: &[u32]) {
        self.gpu_order = gpu_order.to_vec();
        self.list.clear();
        for (gpu_index, &i) in gpu_order.iter().enumerate() {
            let instance = &scene.instances[i as usize];
            let material = &scene.materials[instance.material];
            let Some(bvh) = &blas[instance.mesh] else {
                continue;
            };
            if !(material.is_boundary_only() || material.is_transmissive()) {
                continue;
            }
            let (lo, hi) = bvh.nodes[0].bounds();
            let corners = (0..8).map(|k| {
                let pick = |bit: usize, axis: usize| {
                    if k >> bit & 1 == 1 {
                        hi[axis]
                    } else {
                        lo[axis]
                    }
                };
                instance
                    .transform
                    .transform_point3(Vec3::new(pick(0, 0), pick(1, 1), pick(2, 2)))
            });
            let (lo, hi) = corners.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            });
            self.list.push(Enclosure {
                gpu_index: gpu_index as u32,
                mesh: instance.mesh,
                to_object: instance.transform.inverse(),
                lo,
                hi,
            });
            self.triangles.entry(instance.mesh).or_insert_with(|| {
                let mesh = &scene.meshes[instance.mesh];
                (0..mesh.indices.len()).map(|t| mesh.triangle(t)).collect()
            });
        }
    }

    /// The scene index of each of the kernel's instances, as given to [`Enclosures::new`].
    pub fn gpu_order(&self) -> &[u32] {
        &self.gpu_order
    }

    /// The kernel's indices of the enclosures holding `point`, outermost first (by the
    /// volume of their bounds, so an object inside another comes after it).
    pub fn around(&self, blas: &[Option<Bvh>], point: Vec3) -> Vec<u32> {
        let mut found: Vec<&Enclosure> = self
            .list
            .iter()
            .filter(|e| {
                point.cmpge(e.lo).all()
                    && point.cmple(e.hi).all()
                    && blas[e.mesh].as_ref().is_some_and(|bvh| {
                        inside(
                            bvh,
                            &self.triangles[&e.mesh],
                            e.to_object.transform_point3(point),
                        )
                    })
            })
            .collect();
        let volume = |e: &Enclosure| (e.hi - e.lo).max(Vec3::ZERO).element_product();
        found.sort_by(|a, b| volume(b).total_cmp(&volume(a)));
        found.into_iter().map(|e| e.gpu_index).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::build_scene_accel;
    use crate::scene::{Camera, Material, shapes};

    /// A glass cube of side 2 with a glass sphere of radius 0.5 inside it, and an opaque
    /// cube beside them.
    fn nested() -> Scene {
        let mut scene = Scene::empty(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, 40.0));
        let glass = scene.add_material(Material {
            principled: crate::shader::principled::Principled {
                transmission_weight: 1.0,
                ..Default::default()
            },
            ..Material::diffuse("glass", Vec3::ONE)
        });
        let grey = scene.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
        let cube = scene.add_mesh(shapes::cube());
        let sphere = scene.add_mesh(shapes::uv_sphere(32, 16, true));
        scene.add_instance(sphere, glass, Affine3A::from_scale(Vec3::splat(0.5)));
        scene.add_instance(cube, glass, Affine3A::from_scale(Vec3::splat(2.0)));
        scene.add_instance(cube, grey, Affine3A::from_translation(Vec3::X * 3.0));
        scene
    }

    #[test]
    fn the_enclosures_around_a_point_are_those_holding_it_outermost_first() {
        let scene = nested();
        let accel = build_scene_accel(&scene).unwrap();
        let order = &accel.tlas.as_ref().unwrap().primitive_order;
        let enclosures = Enclosures::new(&scene, &accel.blas, order);
        // Scene instances of what `around` returns.
        let around = |p: Vec3| -> Vec<u32> {
            (enclosures.around(&accel.blas, p).iter())
                .map(|&g| order[g as usize])
                .collect()
        };
        assert_eq!(around(Vec3::ZERO), [1, 0], "the centre: cube, then sphere");
        assert_eq!(around(Vec3::new(0.0, 0.0, 0.45)), [1, 0]);
        assert_eq!(
            around(Vec3::new(0.7, 0.7, 0.0)),
            [1],
            "in the cube's corner"
        );
        assert_eq!(
            around(Vec3::new(0.0, 0.0, 1.05)),
            [] as [u32; 0],
            "just outside"
        );
        assert_eq!(
            around(Vec3::new(3.0, 0.0, 0.0)),
            [] as [u32; 0],
            "an opaque cube"
        );
        // Through the sphere's vertices and edges: the vote still counts them once.
        for k in 0..64 {
            let a = k as f32 * 0.1;
            let p = Vec3::new(a.cos(), a.sin(), (a * 0.37).sin()) * 0.3;
            assert_eq!(around(p), [1, 0], "{p}");
        }
    }
}
