//! Renders split across processes and machines: the parts of a render by sample range
//! (`kiln render --samples A..B`) and their exact merge (`kiln merge`, [`part`]), the
//! frames of a turntable ([`Turntable`]), and the Slurm job arrays that render them
//! (`kiln farm`, [`slurm`]). Kiln brings no scheduler of its own: it makes a render
//! splittable and mergeable and drives the one a cluster has (docs/SCALE_OUT.md).

pub mod part;
pub mod slurm;

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

use crate::scene::Camera;

/// An animation of the camera orbiting its target: `degrees` about the camera's up axis
/// through the point it looks at, spread evenly over `frames` (frame `frames.start` is the
/// scene's own camera).
#[derive(Clone, Debug, PartialEq)]
pub struct Turntable {
    pub degrees: f32,
    pub frames: Range<u32>,
}

impl Turntable {
    /// The camera of `frame`.
    pub fn camera(&self, camera: &Camera, frame: u32) -> Camera {
        let steps = self.frames.len().max(1) as f32;
        let angle = (self.degrees * (frame as f32 - self.frames.start as f32) / steps).to_radians();
        let turn = Quat::from_axis_angle(camera.up.normalize_or(Vec3::Y), angle);
        Camera {
            position: camera.look_at + turn * (camera.position - camera.look_at),
            ..*camera
        }
    }
}

/// The output path of `frame`: a run of `#` in the file name becomes the frame number
/// padded to the run's length (`shot_####.png` → `shot_0007.png`, as Blender names
/// frames); without one, `_NNNN` goes before the extension.
pub fn frame_path(path: &Path, frame: u32) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let named = match name.find('#') {
        Some(start) => {
            let run = name[start..].chars().take_while(|&c| c == '#').count();
            format!("{}{frame:0run$}{}", &name[..start], &name[start + run..])
        }
        None => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            match path.extension() {
                Some(ext) => format!("{stem}_{frame:04}.{}", ext.to_string_lossy()),
                None => format!("{stem}_{frame:04}"),
            }
        }
    };
    path.with_file_name(named)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_numbered_as_blender_numbers_them() {
        assert_eq!(
            frame_path(Path::new("out/shot_####.png"), 7),
            Path::new("out/shot_0007.png")
        );
        assert_eq!(
            frame_path(Path::new("shot_##.exr"), 123),
            Path::new("shot_123.exr")
        );
        assert_eq!(
            frame_path(Path::new("a/b.png"), 12),
            Path::new("a/b_0012.png")
        );
    }

    #[test]
    fn a_turntable_orbits_the_target_evenly() {
        let camera = Camera::look_at(Vec3::new(0.0, 1.0, 4.0), Vec3::new(0.0, 1.0, 0.0), 40.0);
        let t = Turntable {
            degrees: 360.0,
            frames: 10..14,
        };
        assert!(
            t.camera(&camera, 10)
                .position
                .abs_diff_eq(camera.position, 1e-6)
        );
        let quarter = t.camera(&camera, 11);
        assert!(
            quarter.position.abs_diff_eq(Vec3::new(4.0, 1.0, 0.0), 1e-5),
            "{}",
            quarter.position
        );
        assert_eq!(quarter.look_at, camera.look_at);
        assert!(
            t.camera(&camera, 12)
                .position
                .abs_diff_eq(Vec3::new(0.0, 1.0, -4.0), 1e-5)
        );
    }
}
