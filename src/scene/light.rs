//! Lights that are not geometry: point (optionally a sphere), spot and distant (sun)
//! lights. Emissive meshes are lights too, through their material's emission.
//!
//! Lights of zero size (a point or spot of radius 0, a distant light of angular diameter
//! 0) are reached by next-event estimation only. Sphere lights (point and spot lights with
//! a radius) and sun disks (distant lights with an angular diameter) are also hit by
//! camera and BSDF rays, and the two strategies are weighted by multiple importance
//! sampling (`shaders/lights/analytic.wgsl`). A sphere light is opaque to the rays that
//! hit it but, as in Cycles, casts no shadow.

use glam::Vec3;

/// A light placed in the scene: its emitter, with the name and visibility the outliner
/// shows for it (saved in the scene file, like an object's).
#[derive(Clone, Debug, PartialEq)]
pub struct LightObject {
    pub light: Light,
    /// Empty when the file gave none; the editor names such lights after their kind.
    pub name: String,
    /// Hidden lights stay in the scene and its file but do not shine
    /// ([`Scene::without_hidden`](super::Scene::without_hidden)).
    pub visible: bool,
}

impl From<Light> for LightObject {
    /// An unnamed, visible light.
    fn from(light: Light) -> Self {
        Self {
            light,
            name: String::new(),
            visible: true,
        }
    }
}

/// What a light emits, and from where.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity `intensity` (W/sr per channel) from `position`; with `radius` > 0
    /// a sphere of that radius and uniform radiance intensity / (π radius²).
    Point {
        position: Vec3,
        intensity: Vec3,
        radius: f32,
    },
    /// A point light limited to a cone around `direction`: full intensity within
    /// `cone_angle × (1 - blend)` of the axis, falling smoothly to 0 at `cone_angle`
    /// (half-angles, degrees).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cone_angle: f32,
        blend: f32,
        radius: f32,
    },
    /// Light arriving from infinitely far along `direction` (the way it travels), with
    /// irradiance `irradiance` (W/m² on a surface facing it) spread over a disk of
    /// `angular_diameter` degrees (the sun: 0.53).
    Distant {
        direction: Vec3,
        irradiance: Vec3,
        angular_diameter: f32,
    },
}

impl Light {
    pub fn validate(&self) -> Result<(), String> {
        let non_negative = |name: &str, c: Vec3| -> Result<(), String> {
            if c.is_finite() && c.min_element() >= 0.0 {
                Ok(())
            } else {
                Err(format!("{name} {c} must be finite and non-negative"))
            }
        };
        let direction = |d: Vec3| -> Result<(), String> {
            if d.is_finite() && d.length_squared() > 0.0 {
                Ok(())
            } else {
                Err(format!("direction {d} must be a finite non-zero vector"))
            }
        };
        let placement = |position: Vec3, radius: f32| -> Result<(), String> {
            if position.is_finite() && radius.is_finite() && radius >= 0.0 {
                Ok(())
            } else {
                Err("position and radius must be finite, radius ≥ 0".into())
            }
        };
        match *self {
            Light::Point {
                position,
                intensity,
                radius,
            } => {
                non_negative("intensity", intensity)?;
                placement(position, radius)
            }
            Light::Spot {
                position,
                direction: d,
                intensity,
                cone_angle,
                blend,
                radius,
            } => {
                non_negative("intensity", intensity)?;
                direction(d)?;
                placement(position, radius)?;
                if cone_angle > 0.0 && cone_angle <= 180.0 && (0.0..=1.0).contains(&blend) {
                    Ok(())
                } else {
                    Err(format!(
                        "cone_angle {cone_angle} must be in (0, 180] degrees and blend {blend} in [0, 1]"
                    ))
                }
            }
            Light::Distant {
                direction: d,
                irradiance,
                angular_diameter,
            } => {
                non_negative("irradiance", irradiance)?;
                direction(d)?;
                if (0.0..90.0).contains(&angular_diameter) {
                    Ok(())
                } else {
                    Err(format!(
                        "angular_diameter {angular_diameter} must be in [0, 90) degrees"
                    ))
                }
            }
        }
    }
}
