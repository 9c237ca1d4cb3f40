//! The camera: a perspective projection with an optional thin lens for depth of field.

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
    /// Radius of the lens in scene units; 0 is a pinhole.
    pub aperture_radius: f32,
    /// Distance along the view direction that is in sharp focus (thin lens only).
    pub focus_distance: f32,
}

impl Camera {
    pub fn look_at(position: Vec3, look_at: Vec3, fov_y_degrees: f32) -> Self {
        Self {
            position,
            look_at,
            up: Vec3::Y,
            fov_y_degrees,
            aperture_radius: 0.0,
            focus_distance: (look_at - position).length(),
        }
    }

    /// Right-handed orthonormal frame (right, up, forward) of the view.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }

    pub fn validate(&self) -> Result<(), String> {
        let finite = self.position.is_finite()
            && self.look_at.is_finite()
            && self.up.is_finite()
            && self.fov_y_degrees.is_finite()
            && self.aperture_radius.is_finite()
            && self.focus_distance.is_finite();
        if !finite {
            return Err("camera: every value must be finite".into());
        }
        if !(self.fov_y_degrees > 0.0 && self.fov_y_degrees < 180.0) {
            return Err(format!(
                "camera: fov_y {} must be between 0 and 180 degrees",
                self.fov_y_degrees
            ));
        }
        let forward = self.look_at - self.position;
        if forward.length_squared() == 0.0 {
            return Err("camera: position and look_at coincide".into());
        }
        if forward.cross(self.up).length_squared() == 0.0 {
            return Err("camera: up is parallel to the view direction".into());
        }
        if self.aperture_radius < 0.0 {
            return Err("camera: aperture_radius must not be negative".into());
        }
        if self.aperture_radius > 0.0 && self.focus_distance <= 0.0 {
            return Err("camera: a thin lens needs a positive focus_distance".into());
        }
        Ok(())
    }
}
