//! Click-to-select: a ray from the viewport's camera through the clicked point, cast on
//! the CPU through the same two-level BVH the renderer builds ([`crate::accel`]).
//!
//! Not a second renderer: it finds the nearest triangle and nothing else (no alpha, no
//! lights; analytic lights have no geometry to click).

use glam::Vec3;

use crate::accel::query::{hit_triangle, traverse};
use crate::accel::{AccelError, SceneAccel, build_scene_accel};
use crate::scene::{Camera, Scene};

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
        traverse(tlas, origin, dir, f32::INFINITY, |index, t_max| {
            let instance = &scene.instances[index];
            let blas = self.accel.blas[instance.mesh].as_ref()?;
            let mesh = &scene.meshes[instance.mesh];
            // In object space the ray's parameter t is the world one, since the
            // direction is transformed without normalising.
            let to_object = instance.transform.inverse();
            let o = to_object.transform_point3(origin);
            let d = to_object.transform_vector3(dir);
            let t = traverse(blas, o, d, t_max, |tri, _| {
                hit_triangle(o, d, mesh.triangle(tri))
            });
            (t < t_max).then(|| {
                best = Some((index, t));
                t
            })
        });
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
