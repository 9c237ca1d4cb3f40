//! Transforming the selection in the viewport, as Blender does it: the modal tools G
//! (move), R (rotate) and S (scale), each optionally constrained to an axis with X, Y or Z
//! (pressed twice: the object's local axis), confirmed with a click or Enter and cancelled
//! with Esc or a right click; and the gizmo of the active tool at the object's origin:
//! arrows that move it along an axis, rings that turn it about one, handles that scale it
//! along one.
//!
//! Pure geometry on a [`ViewProjection`]: which keys start a tool and how its frames
//! become one undo step is the app's business (each frame is a `SetTransform` command of
//! one gesture).

use egui::{Pos2, Rect, Vec2};
use glam::{Affine3A, Quat, Vec3};

use crate::scene::Camera;

/// What a modal transform does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Move,
    Rotate,
    Scale,
}

/// The axis frame a constraint refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    Global,
    /// The object's own axes (its rotation).
    Local,
}

/// A constraint to one axis (0 = X, 1 = Y, 2 = Z) of an orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Constraint {
    pub axis: usize,
    pub orientation: Orientation,
}

/// Blender's axis colours.
pub const AXIS_COLORS: [egui::Color32; 3] = [
    egui::Color32::from_rgb(255, 51, 82),
    egui::Color32::from_rgb(139, 220, 0),
    egui::Color32::from_rgb(40, 144, 255),
];

/// Length of the move gizmo's arrows in points.
pub const ARROW_POINTS: f32 = 80.0;

/// The viewport's camera and where its image is laid out: world points to screen points
/// and back, as the kernel's pinhole camera sees them.
#[derive(Clone, Copy, Debug)]
pub struct ViewProjection {
    pub camera: Camera,
    pub rect: Rect,
}

impl ViewProjection {
    fn tan_half(&self) -> f32 {
        (self.camera.fov_y_degrees.to_radians() * 0.5).tan()
    }

    /// Where `p` appears in the viewport; None behind the camera.
    pub fn project(&self, p: Vec3) -> Option<Pos2> {
        let (right, up, forward) = self.camera.frame();
        let rel = p - self.camera.position;
        let z = rel.dot(forward);
        if z <= 1e-6 {
            return None;
        }
        let aspect = self.rect.width() / self.rect.height();
        let x = rel.dot(right) / z / (self.tan_half() * aspect);
        let y = rel.dot(up) / z / self.tan_half();
        Some(egui::pos2(
            self.rect.left() + (x + 1.0) * 0.5 * self.rect.width(),
            self.rect.top() + (1.0 - y) * 0.5 * self.rect.height(),
        ))
    }

    /// World units per point of the screen at the depth of `p`.
    pub fn world_per_point(&self, p: Vec3) -> f32 {
        let (_, _, forward) = self.camera.frame();
        let depth = (p - self.camera.position).dot(forward).max(1e-4);
        2.0 * depth * self.tan_half() / self.rect.height().max(1.0)
    }

    /// The world-space displacement of a screen movement `delta` in the view plane
    /// through `p`.
    fn view_plane_delta(&self, p: Vec3, delta: Vec2) -> Vec3 {
        let (right, up, _) = self.camera.frame();
        (delta.x * right - delta.y * up) * self.world_per_point(p)
    }
}

/// The world direction of `constraint` for an object with `transform`.
pub fn axis_direction(transform: &Affine3A, constraint: Constraint) -> Vec3 {
    let unit = Vec3::AXES[constraint.axis];
    match constraint.orientation {
        Orientation::Global => unit,
        Orientation::Local => {
            let (_, rotation, _) = transform.to_scale_rotation_translation();
            rotation * unit
        }
    }
}

/// The transform a modal tool gives the object that had `start` when the mouse went from
/// `from` to `to`.
pub fn modal_transform(
    mode: Mode,
    start: &Affine3A,
    constraint: Option<Constraint>,
    view: &ViewProjection,
    from: Pos2,
    to: Pos2,
) -> Affine3A {
    let origin: Vec3 = start.translation.into();
    let (scale, rotation, translation) = start.to_scale_rotation_translation();
    match mode {
        Mode::Move => {
            let offset = match constraint {
                None => view.view_plane_delta(origin, to - from),
                Some(c) => {
                    let axis = axis_direction(start, c);
                    axis * along_axis(view, origin, axis, to - from)
                }
            };
            Affine3A::from_scale_rotation_translation(scale, rotation, translation + offset)
        }
        Mode::Rotate => {
            let Some(centre) = view.project(origin) else {
                return *start;
            };
            let (a, b) = (from - centre, to - centre);
            if a.length() < 1.0 || b.length() < 1.0 {
                return *start;
            }
            // Counter-clockwise on screen (y down) is a positive turn about the axis
            // pointing at the viewer.
            let angle = -(a.x * b.y - a.y * b.x).atan2(a.dot(b));
            let (_, _, forward) = view.camera.frame();
            let axis = match constraint {
                None => -forward,
                Some(c) => {
                    let axis = axis_direction(start, c);
                    // Turn the same way on screen whichever way the axis points.
                    if axis.dot(forward) > 0.0 { -axis } else { axis }
                }
            };
            let turn = Quat::from_axis_angle(axis.normalize(), angle);
            Affine3A::from_scale_rotation_translation(scale, turn * rotation, translation)
        }
        Mode::Scale => {
            let Some(centre) = view.project(origin) else {
                return *start;
            };
            let start_distance = (from - centre).length().max(1.0);
            let factor = ((to - centre).length() / start_distance).max(1e-3);
            let new_scale = match constraint {
                None => scale * factor,
                Some(c) => {
                    // Scale is along the object's own axes; a constraint picks one.
                    let mut s = scale;
                    s[c.axis] *= factor;
                    s
                }
            };
            Affine3A::from_scale_rotation_translation(new_scale, rotation, translation)
        }
    }
}

/// How far along the world direction `axis` (through `origin`) a screen movement
/// `delta` goes: its component along the axis's screen image, in world units.
fn along_axis(view: &ViewProjection, origin: Vec3, axis: Vec3, delta: Vec2) -> f32 {
    let unit = view.world_per_point(origin);
    let (Some(a), Some(b)) = (view.project(origin), view.project(origin + axis * unit)) else {
        return 0.0;
    };
    // Points on screen per world unit along the axis.
    let screen = (b - a) / unit;
    let length_sq = screen.length_sq();
    if length_sq < 1e-8 {
        // The axis points at the viewer: it cannot be dragged along.
        return 0.0;
    }
    delta.dot(screen) / length_sq
}

/// The move gizmo's arrows for an object with `transform`: for each axis, the screen
/// segment from the origin to the arrow's tip (None when the origin is behind the view).
pub fn arrows(
    view: &ViewProjection,
    transform: &Affine3A,
    orientation: Orientation,
) -> Option<[(Pos2, Pos2); 3]> {
    let origin: Vec3 = transform.translation.into();
    let start = view.project(origin)?;
    let length = ARROW_POINTS * view.world_per_point(origin);
    let tip = |axis| {
        let direction = axis_direction(transform, Constraint { axis, orientation });
        view.project(origin + direction * length).unwrap_or(start)
    };
    Some([(start, tip(0)), (start, tip(1)), (start, tip(2))])
}

/// The arrow of `arrows` within `radius` points of `pos`, the nearest.
pub fn arrow_at(arrows: &[(Pos2, Pos2); 3], pos: Pos2, radius: f32) -> Option<usize> {
    arrows
        .iter()
        .enumerate()
        .filter(|(_, (a, b))| (*b - *a).length() > 4.0)
        .map(|(i, (a, b))| (i, distance_to_segment(pos, *a, *b)))
        .filter(|(_, d)| *d <= radius)
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(i, _)| i)
}

/// Points per ring of the rotate gizmo.
const RING_POINTS: usize = 64;

/// The rotate gizmo's rings for an object with `transform`: for each axis, the screen
/// polyline of the circle about it (radius [`ARROW_POINTS`]); None when the origin is
/// behind the view.
pub fn rings(
    view: &ViewProjection,
    transform: &Affine3A,
    orientation: Orientation,
) -> Option<[Vec<Pos2>; 3]> {
    let origin: Vec3 = transform.translation.into();
    view.project(origin)?;
    let radius = ARROW_POINTS * view.world_per_point(origin);
    let ring = |axis| {
        let normal = axis_direction(transform, Constraint { axis, orientation });
        let (u, v) = normal.any_orthonormal_pair();
        (0..=RING_POINTS)
            .filter_map(|i| {
                let t = i as f32 / RING_POINTS as f32 * std::f32::consts::TAU;
                view.project(origin + (u * t.cos() + v * t.sin()) * radius)
            })
            .collect()
    };
    Some([ring(0), ring(1), ring(2)])
}

/// The ring of `rings` within `radius` points of `pos`, the nearest.
pub fn ring_at(rings: &[Vec<Pos2>; 3], pos: Pos2, radius: f32) -> Option<usize> {
    rings
        .iter()
        .enumerate()
        .filter_map(|(i, ring)| {
            ring.windows(2)
                .map(|w| distance_to_segment(pos, w[0], w[1]))
                .min_by(f32::total_cmp)
                .map(|d| (i, d))
        })
        .filter(|(_, d)| *d <= radius)
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(i, _)| i)
}

fn distance_to_segment(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> ViewProjection {
        ViewProjection {
            camera: Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, 40.0),
            rect: Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(800.0, 600.0)),
        }
    }

    #[test]
    fn a_free_move_follows_the_mouse_in_the_view_plane() {
        let v = view();
        let start = Affine3A::IDENTITY;
        let from = v.project(Vec3::ZERO).unwrap();
        let to = from + egui::vec2(100.0, 0.0);
        let moved = modal_transform(Mode::Move, &start, None, &v, from, to);
        let p: Vec3 = moved.translation.into();
        let back = v.project(p).unwrap();
        assert!((back - to).length() < 0.01, "{back:?} vs {to:?}");
        assert!(p.z.abs() < 1e-4, "stays in the view plane");
    }

    #[test]
    fn a_constrained_move_stays_on_its_axis() {
        let v = view();
        let start = Affine3A::from_rotation_z(0.5);
        let from = v.project(Vec3::ZERO).unwrap();
        let to = from + egui::vec2(50.0, -80.0);
        let x = Constraint {
            axis: 0,
            orientation: Orientation::Global,
        };
        let moved = modal_transform(Mode::Move, &start, Some(x), &v, from, to);
        let p: Vec3 = moved.translation.into();
        assert!(p.x > 0.0 && p.y.abs() < 1e-5 && p.z.abs() < 1e-5, "{p:?}");
        let local_x = Constraint {
            axis: 0,
            orientation: Orientation::Local,
        };
        let moved = modal_transform(Mode::Move, &start, Some(local_x), &v, from, to);
        let p: Vec3 = moved.translation.into();
        let axis = Quat::from_rotation_z(0.5) * Vec3::X;
        assert!(p.cross(axis).length() < 1e-4 * p.length().max(1.0), "{p:?}");
        // The rotation and scale are kept.
        assert!(moved.matrix3.abs_diff_eq(start.matrix3, 1e-6));
    }

    #[test]
    fn rotating_a_quarter_turn_about_the_view_axis() {
        let v = view();
        let start = Affine3A::IDENTITY;
        let centre = v.project(Vec3::ZERO).unwrap();
        let from = centre + egui::vec2(100.0, 0.0);
        // A quarter turn counter-clockwise on screen (up is -y).
        let to = centre + egui::vec2(0.0, -100.0);
        let turned = modal_transform(Mode::Rotate, &start, None, &v, from, to);
        let x = turned.transform_vector3(Vec3::X);
        assert!((x - Vec3::Y).length() < 1e-4, "{x:?}");
    }

    #[test]
    fn scaling_by_the_distance_ratio_and_on_one_axis() {
        let v = view();
        let start = Affine3A::from_scale(Vec3::splat(2.0));
        let centre = v.project(Vec3::ZERO).unwrap();
        let from = centre + egui::vec2(50.0, 0.0);
        let to = centre + egui::vec2(150.0, 0.0);
        let scaled = modal_transform(Mode::Scale, &start, None, &v, from, to);
        let (s, _, _) = scaled.to_scale_rotation_translation();
        assert!((s - Vec3::splat(6.0)).length() < 1e-4, "{s:?}");
        let y = Constraint {
            axis: 1,
            orientation: Orientation::Local,
        };
        let scaled = modal_transform(Mode::Scale, &start, Some(y), &v, from, to);
        let (s, _, _) = scaled.to_scale_rotation_translation();
        assert!((s - Vec3::new(2.0, 6.0, 2.0)).length() < 1e-4, "{s:?}");
    }

    #[test]
    fn a_ring_is_found_on_its_circle() {
        let v = view();
        let rings = rings(&v, &Affine3A::IDENTITY, Orientation::Global).unwrap();
        // The Z ring faces the viewer: a circle of the arrow's length around the origin.
        let centre = v.project(Vec3::ZERO).unwrap();
        let on_circle = centre + egui::vec2(ARROW_POINTS, 0.0);
        assert_eq!(
            ring_at(&rings, on_circle + egui::vec2(0.0, -30.0), 6.0),
            Some(2)
        );
        assert_eq!(ring_at(&rings, centre + egui::vec2(20.0, -30.0), 6.0), None);
    }

    #[test]
    fn an_arrow_is_found_near_its_segment_and_not_far_from_it() {
        let v = view();
        let arrows = arrows(&v, &Affine3A::IDENTITY, Orientation::Global).unwrap();
        let (a, b) = arrows[0];
        let middle = a + (b - a) * 0.5;
        assert_eq!(
            arrow_at(&arrows, middle + egui::vec2(0.0, 3.0), 6.0),
            Some(0)
        );
        assert_eq!(arrow_at(&arrows, middle + egui::vec2(0.0, 30.0), 6.0), None);
        // The Z arrow points at the viewer: too short on screen to grab.
        let (a, b) = arrows[2];
        assert!((b - a).length() < 4.0);
    }
}
