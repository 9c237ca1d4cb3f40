//! Click-to-select: a ray from the viewport's camera through the clicked point, cast on
//! the CPU through the same two-level BVH the renderer builds ([`crate::accel`]).
//!
//! Not a second renderer: it finds the nearest triangle and nothing else (no alpha, no
//! lights; analytic lights have no geometry to click).

use glam::Vec3;

use crate::accel::{AccelError, SceneAccel, build_scene_accel};
use crate::scene::{Camera, Scene};
use crate::shader::gpu_types::BvhNode;

/// A scene's BVHs kept for picking.
pub struct Picker {
    accel: SceneAccel,
}

/// The primary ray of `camera` through the point `(u, v)` of the image, each in [0, 1]
/// from the top-left, for an image of aspect `width / height`: the pinhole ray the kernel's
/// `camera_ray` (`shaders/camera.wgsl`) shoots through that point.
pub fn camera_ray(camera: &Camera, u: f32, v: f32, aspect: f32) -> (Vec3, Vec3) {
    let (right, up, forward) = camera.frame();
    let tan_half = (camera.fov_y_degrees.to_radians() * 0.5).tan();
    let ndc_x = u * 2.0 - 1.0;
    let ndc_y = v * 2.0 - 1.0;
    let d = ndc_x * tan_half * aspect * right - ndc_y * tan_half * up + forward;
    (camera.position, d.normalize())
}

fn hit_box(node: &BvhNode, origin: Vec3, inv_dir: Vec3, t_max: f32) -> bool {
    let (lo, hi) = node.bounds();
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element();
    near <= far && near < t_max
}

/// Möller–Trumbore; the distance along `dir` when the ray meets the triangle (either side).
fn hit_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
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

/// Visits the leaves of `nodes` the ray may reach; `leaf(primitive, t_max)` returns a
/// nearer hit distance when it finds one.
fn traverse(
    nodes: &[BvhNode],
    order: &[u32],
    origin: Vec3,
    dir: Vec3,
    mut t_max: f32,
    mut leaf: impl FnMut(usize, f32) -> Option<f32>,
) -> f32 {
    let inv_dir = dir.recip();
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let node = &nodes[i];
        if !hit_box(node, origin, inv_dir, t_max) {
            continue;
        }
        if node.count > 0 {
            let first = node.first as usize;
            for &primitive in &order[first..first + node.count as usize] {
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

impl Picker {
    /// Builds the BVHs of `scene` (as the renderer would).
    pub fn new(scene: &Scene) -> Result<Self, AccelError> {
        Ok(Self {
            accel: build_scene_accel(scene)?,
        })
    }

    /// The instance of `scene` (the one this picker was built from) nearest along the
    /// ray, and the distance to it.
    pub fn pick(&self, scene: &Scene, origin: Vec3, dir: Vec3) -> Option<(usize, f32)> {
        let tlas = self.accel.tlas.as_ref()?;
        let mut best: Option<(usize, f32)> = None;
        traverse(
            &tlas.nodes,
            &tlas.primitive_order,
            origin,
            dir,
            f32::INFINITY,
            |index, t_max| {
                let instance = &scene.instances[index];
                let blas = self.accel.blas[instance.mesh].as_ref()?;
                let mesh = &scene.meshes[instance.mesh];
                // In object space the ray's parameter t is the world one, since the
                // direction is transformed without normalising.
                let to_object = instance.transform.inverse();
                let o = to_object.transform_point3(origin);
                let d = to_object.transform_vector3(dir);
                let t = traverse(&blas.nodes, &blas.primitive_order, o, d, t_max, |tri, _| {
                    hit_triangle(o, d, mesh.triangle(tri))
                });
                (t < t_max).then(|| {
                    best = Some((index, t));
                    t
                })
            },
        );
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where `p` appears in the image of `camera` (u, v from the top-left), for a square
    /// image: the inverse of [`camera_ray`].
    fn project(camera: &Camera, p: Vec3) -> (f32, f32) {
        let (right, up, forward) = camera.frame();
        let tan_half = (camera.fov_y_degrees.to_radians() * 0.5).tan();
        let rel = p - camera.position;
        let z = rel.dot(forward);
        let u = (rel.dot(right) / z / tan_half + 1.0) * 0.5;
        let v = (1.0 - rel.dot(up) / z / tan_half) * 0.5;
        (u, v)
    }

    #[test]
    fn a_click_on_each_cornell_block_picks_that_block() {
        let scene = crate::scene::default_scene().unwrap();
        let picker = Picker::new(&scene).unwrap();
        for instance in [6, 7] {
            let centre: Vec3 = scene.instances[instance].transform.translation.into();
            let (u, v) = project(&scene.camera, centre);
            let (o, d) = camera_ray(&scene.camera, u, v, 1.0);
            let (hit, t) = picker.pick(&scene, o, d).expect("the block is in view");
            assert_eq!(hit, instance, "u {u} v {v}");
            // The front face is nearer than the centre, but not by more than the block.
            let to_centre = (centre - o).length();
            assert!(t < to_centre && t > to_centre - 200.0, "t = {t}");
        }
        // Above both blocks, the ray goes on to the back wall (instance 2) at z = 559.2.
        let (o, d) = camera_ray(&scene.camera, 0.5, 0.3, 1.0);
        let (hit, t) = picker.pick(&scene, o, d).unwrap();
        assert_eq!(hit, 2);
        assert!((o.z + t * d.z - 559.2).abs() < 0.1, "t = {t}");
    }

    #[test]
    fn a_ray_into_the_void_hits_nothing() {
        let scene = crate::scene::default_scene().unwrap();
        let picker = Picker::new(&scene).unwrap();
        assert!(
            picker
                .pick(&scene, Vec3::new(0.0, 0.0, -800.0), -Vec3::Z)
                .is_none()
        );
    }
}
