//! Viewport navigation as Blender does it: orbit around the view's pivot (the camera's
//! `look_at`), pan in the view plane, dolly towards the pivot, frame the scene's bounds.
//!
//! Pure functions on a [`Camera`]; which mouse buttons drive them is the viewport's
//! business.

use glam::{Quat, Vec3};

use crate::scene::{Camera, Scene};

/// Radians of orbit per point of mouse movement (Blender: about 0.4° per pixel).
const ORBIT_RADIANS_PER_POINT: f32 = 0.007;
/// How close to straight up or down an orbit may tilt the view, in radians.
const POLE_MARGIN: f32 = 0.01;

/// Orbits the view around its pivot: `dx` turns about the world up axis (the camera's
/// `up`), `dy` tilts about the view's right axis, both in points of mouse movement.
pub fn orbit(camera: &Camera, dx: f32, dy: f32) -> Camera {
    let up = camera.up.normalize_or(Vec3::Y);
    let offset = camera.position - camera.look_at;
    let yaw = Quat::from_axis_angle(up, -dx * ORBIT_RADIANS_PER_POINT);
    let offset = yaw * offset;
    // Tilt, stopping just short of the poles so that the view never flips.
    let right = offset.cross(up).normalize_or(Vec3::X);
    let angle_from_up = offset.normalize().dot(up).clamp(-1.0, 1.0).acos();
    let tilt = (dy * ORBIT_RADIANS_PER_POINT).clamp(
        POLE_MARGIN - angle_from_up,
        std::f32::consts::PI - POLE_MARGIN - angle_from_up,
    );
    let offset = Quat::from_axis_angle(right, -tilt) * offset;
    Camera {
        position: camera.look_at + offset,
        ..*camera
    }
}

/// Fly navigation (Blender's walk/fly modes): turns the view in place by `dx`, `dy` points
/// of mouse movement (about the world up axis, then the view's right axis) and moves it by
/// `movement` (right, up, forward) in world units in the turned view's frame. The pivot
/// keeps its distance in front of the camera, so orbiting afterwards turns about what is
/// ahead.
pub fn fly(camera: &Camera, dx: f32, dy: f32, movement: Vec3) -> Camera {
    let up = camera.up.normalize_or(Vec3::Y);
    let offset = camera.look_at - camera.position;
    let distance = offset.length().max(1e-3);
    let yaw = Quat::from_axis_angle(up, -dx * ORBIT_RADIANS_PER_POINT);
    let forward = yaw * offset.normalize_or(Vec3::NEG_Z);
    let right = forward.cross(up).normalize_or(Vec3::X);
    let angle_from_up = forward.dot(up).clamp(-1.0, 1.0).acos();
    // Positive tilt looks down, away from up.
    let tilt = (dy * ORBIT_RADIANS_PER_POINT).clamp(
        POLE_MARGIN - angle_from_up,
        std::f32::consts::PI - POLE_MARGIN - angle_from_up,
    );
    let forward = Quat::from_axis_angle(right, -tilt) * forward;
    let view_up = right.cross(forward);
    let position =
        camera.position + right * movement.x + view_up * movement.y + forward * movement.z;
    Camera {
        position,
        look_at: position + forward * distance,
        ..*camera
    }
}

/// Moves the view and its pivot in the view plane by `dx`, `dy` points, so that what is
/// at the pivot follows the mouse in a viewport `viewport_height` points tall.
pub fn pan(camera: &Camera, dx: f32, dy: f32, viewport_height: f32) -> Camera {
    let (right, up, _) = camera.frame();
    let distance = (camera.look_at - camera.position).length();
    let world_per_point =
        2.0 * distance * (camera.fov_y_degrees.to_radians() * 0.5).tan() / viewport_height.max(1.0);
    let shift = (-dx * right + dy * up) * world_per_point;
    Camera {
        position: camera.position + shift,
        look_at: camera.look_at + shift,
        ..*camera
    }
}

/// Dollies towards the pivot: `steps` > 0 moves in (one mouse-wheel notch is one step),
/// never reaching the pivot.
pub fn zoom(camera: &Camera, steps: f32) -> Camera {
    let factor = 0.85f32.powf(steps);
    let offset = camera.position - camera.look_at;
    let length = offset.length();
    let new_length = (length * factor).max(length.max(1.0) * 1e-4);
    Camera {
        position: camera.look_at + offset * (new_length / length),
        ..*camera
    }
}

/// The diagonal of the scene's bounds (1 for a scene without geometry): what fly speed
/// scales with, so that a room and a city both take seconds to cross.
pub fn scene_size(scene: &Scene) -> f32 {
    scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length())
}

/// Keeps the view's direction and field of view and moves it back until every object
/// fits, with the pivot at the centre of their bounds (Blender's Frame All, Home).
pub fn frame_all(camera: &Camera, scene: &Scene) -> Camera {
    let Some((lo, hi)) = scene.bounds() else {
        return *camera;
    };
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-4);
    let (_, _, forward) = camera.frame();
    // The narrower of the two fields of view is what must hold the bounding sphere; the
    // viewport is at least as wide as tall in practice, so the vertical one.
    let half_fov = camera.fov_y_degrees.to_radians() * 0.5;
    let distance = radius / half_fov.sin() * 1.05;
    Camera {
        position: centre - forward * distance,
        look_at: centre,
        ..*camera
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, 40.0)
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot() {
        let c = orbit(&camera(), 120.0, -45.0);
        assert!(((c.position - c.look_at).length() - 10.0).abs() < 1e-3);
        assert_eq!(c.look_at, Vec3::ZERO);
        assert!(c.validate().is_ok());
    }

    #[test]
    fn orbit_stops_short_of_the_pole() {
        let c = orbit(&camera(), 0.0, 10_000.0);
        assert!(c.validate().is_ok(), "{c:?}");
        let c = orbit(&camera(), 0.0, -10_000.0);
        assert!(c.validate().is_ok(), "{c:?}");
    }

    #[test]
    fn pan_moves_pivot_and_eye_together() {
        let before = camera();
        let c = pan(&before, 100.0, 0.0, 500.0);
        assert!(((c.position - c.look_at) - (before.position - before.look_at)).length() < 1e-5);
        // Dragging right moves the view left (the scene follows the mouse).
        assert!(c.look_at.x < 0.0, "{:?}", c.look_at);
    }

    #[test]
    fn zoom_in_then_out_returns() {
        let c = zoom(&zoom(&camera(), 3.0), -3.0);
        assert!((c.position - camera().position).length() < 1e-4);
        assert!((zoom(&camera(), 1.0).position.z) < 10.0);
    }

    #[test]
    fn fly_moves_along_the_view_and_turns_in_place() {
        let before = camera();
        let ahead = fly(&before, 0.0, 0.0, Vec3::new(0.0, 0.0, 2.0));
        let direction = (before.look_at - before.position).normalize();
        assert!((ahead.position - (before.position + direction * 2.0)).length() < 1e-4);
        let turned = fly(&before, 120.0, 0.0, Vec3::ZERO);
        assert_eq!(turned.position, before.position, "turning does not move");
        let new_direction = (turned.look_at - turned.position).normalize();
        assert!(new_direction.dot(direction) < 0.9, "{new_direction:?}");
        let distance = (turned.look_at - turned.position).length();
        assert!((distance - (before.look_at - before.position).length()).abs() < 1e-3);
        // Dragging the mouse down looks down, and never past straight down.
        let down = fly(&before, 0.0, 1e5, Vec3::ZERO);
        let d = (down.look_at - down.position).normalize();
        assert!(d.y < -0.99 && d.is_finite(), "{d:?}");
        assert!(down.validate().is_ok());
    }

    #[test]
    fn frame_all_centres_the_cornell_box() {
        let scene = crate::scene::default_scene().unwrap();
        let c = frame_all(&orbit(&scene.camera, 50.0, 20.0), &scene);
        assert!(
            (c.look_at - Vec3::new(278.0, 274.4, 279.6)).length() < 2.0,
            "{c:?}"
        );
        assert!(c.validate().is_ok());
    }
}
