//! Which light next-event estimation samples: the emissive triangles of the scene's
//! instances, picked in proportion to power through a CDF, and the split of samples
//! between the environment, those triangles and each analytic light.
//!
//! Power estimates only steer sampling: any positive split is unbiased, a good one
//! lowers noise. Not here: the sampling itself (`shaders/lights/`), the environment map's
//! own distribution (`environment_cdf`) and the upload (`gpu_scene`).

use glam::Vec3;

use super::environment_cdf::{luminance, mean_environment_luminance};
use crate::scene::{Light, Scene};
use crate::shader::gpu_types::BvhNode;
use crate::shader::gpu_types::{
    GpuAnalyticLight, GpuLightTriangle, LIGHT_DISTANT, LIGHT_POINT, LIGHT_SPOT,
};

/// Every front-facing emissive triangle in world space, with its pick distribution.
#[derive(Clone, Debug, Default)]
pub struct EmissiveTriangles {
    /// In instance order; `emission.w` is the triangle's pick probability.
    pub triangles: Vec<GpuLightTriangle>,
    /// Inclusive CDF over `triangles`, ending at exactly 1.
    pub cdf: Vec<f32>,
    /// Sum of luminance × area.
    pub power: f32,
}

/// The emissive triangles of every instance with an emissive material, picked by power
/// (luminance × area); triangles of zero or non-finite power are left out.
pub fn emissive_triangles(scene: &Scene) -> EmissiveTriangles {
    let mut lights = EmissiveTriangles::default();
    let mut powers = Vec::new();
    for inst in &scene.instances {
        let material = &scene.materials[inst.material];
        if !material.is_emissive() {
            continue;
        }
        let lum = luminance(material.emission());
        let mesh = &scene.meshes[inst.mesh];
        // A mirroring transform flips the winding; keep the emitting side where the
        // kernel's transformed normal says it is.
        let mirrored = inst.transform.matrix3.determinant() < 0.0;
        for t in 0..mesh.indices.len() {
            let [p0, mut p1, mut p2] = mesh.triangle(t).map(|p| inst.transform.transform_point3(p));
            if mirrored {
                std::mem::swap(&mut p1, &mut p2);
            }
            let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
            let power = lum * area;
            if !(power > 0.0 && power.is_finite()) {
                continue;
            }
            powers.push(power as f64);
            lights.triangles.push(GpuLightTriangle {
                p0: p0.extend(1.0).into(),
                p1: p1.extend(1.0).into(),
                p2: p2.extend(1.0).into(),
                emission: material.emission().extend(0.0).into(),
            });
        }
    }
    let total: f64 = powers.iter().sum();
    let mut running = 0.0f64;
    for (light, power) in lights.triangles.iter_mut().zip(&powers) {
        light.emission[3] = (power / total) as f32;
        running += power;
        lights.cdf.push((running / total) as f32);
    }
    if let Some(last) = lights.cdf.last_mut() {
        *last = 1.0;
    }
    lights.power = total as f32;
    lights
}

/// How next-event estimation splits its samples. All zero (and no analytic lights) when
/// the scene has no light of positive power.
#[derive(Clone, Debug, Default)]
pub struct LightSelection {
    /// Probability of sampling the environment.
    pub environment_pick: f32,
    /// Probability of sampling an emissive triangle.
    pub triangle_pick: f32,
    /// The scene's lights in order; `intensity.w` is each one's pick probability and
    /// `shape.w` the inclusive CDF over environment, triangles and lights (the last
    /// exactly 1).
    pub analytic_lights: Vec<GpuAnalyticLight>,
}

/// Splits next-event estimation between the environment, the emissive triangles (of
/// total power `triangle_power`, from [`emissive_triangles`]) and each analytic light in
/// proportion to estimated power. An environment or a distant light is weighed by the
/// area of the bounding sphere of `scene_root`, the top-level BVH's root (radius 1 when
/// there is none).
pub fn light_selection(
    scene: &Scene,
    scene_root: Option<&BvhNode>,
    triangle_power: f32,
) -> LightSelection {
    let radius = scene_root
        .map(|n| 0.5 * (Vec3::from(n.max) - Vec3::from(n.min)).length())
        .filter(|r| r.is_finite() && *r > 0.0)
        .unwrap_or(1.0) as f64;
    let pi = std::f64::consts::PI;
    let sky = match &scene.environment_map {
        Some(map) => mean_environment_luminance(map),
        None => luminance(scene.environment) as f64,
    };
    let environment = sky * 4.0 * pi * pi * radius * radius;
    let triangles = pi * triangle_power as f64;
    let analytic: Vec<(f64, GpuAnalyticLight)> = scene
        .lights
        .iter()
        .map(|object| analytic_light(&object.light, radius))
        .collect();
    let total = environment + triangles + analytic.iter().map(|(p, _)| p).sum::<f64>();
    let mut selection = LightSelection::default();
    if total <= 0.0 {
        return selection;
    }
    selection.environment_pick = (environment / total) as f32;
    selection.triangle_pick = (triangles / total) as f32;
    let mut cumulative = environment + triangles;
    for (power, mut gpu) in analytic {
        gpu.intensity[3] = (power / total) as f32;
        cumulative += power;
        gpu.shape[3] = (cumulative / total) as f32;
        selection.analytic_lights.push(gpu);
    }
    if let Some(last) = selection.analytic_lights.last_mut() {
        last.shape[3] = 1.0;
    }
    selection
}

/// A light's estimated power (luminance) and its GPU form, pick fields zero. A distant
/// light's power is its irradiance over a disc of the scene's radius.
fn analytic_light(light: &Light, scene_radius: f64) -> (f64, GpuAnalyticLight) {
    let pi = std::f64::consts::PI;
    match *light {
        Light::Point {
            position,
            intensity,
            radius,
        } => (
            4.0 * pi * luminance(intensity) as f64,
            GpuAnalyticLight {
                position: position.into(),
                kind: LIGHT_POINT,
                axis: [0.0, 0.0, 1.0, radius],
                intensity: intensity.extend(0.0).into(),
                shape: [0.0; 4],
            },
        ),
        Light::Spot {
            position,
            direction,
            intensity,
            cone_angle,
            blend,
            radius,
        } => {
            let outer = cone_angle.to_radians();
            let inner = outer * (1.0 - blend);
            (
                2.0 * pi * (1.0 - outer.cos() as f64) * luminance(intensity) as f64,
                GpuAnalyticLight {
                    position: position.into(),
                    kind: LIGHT_SPOT,
                    axis: direction.normalize().extend(radius).into(),
                    intensity: intensity.extend(0.0).into(),
                    shape: [outer.cos(), inner.cos(), 0.0, 0.0],
                },
            )
        }
        Light::Distant {
            direction,
            irradiance,
            angular_diameter,
        } => {
            let half = (0.5 * angular_diameter).to_radians();
            let s = (0.5 * half).sin();
            (
                luminance(irradiance) as f64 * pi * scene_radius * scene_radius,
                GpuAnalyticLight {
                    position: direction.normalize().into(),
                    kind: LIGHT_DISTANT,
                    // 1 - cos(half) without cancellation.
                    axis: [0.0, 0.0, 1.0, 2.0 * s * s],
                    intensity: irradiance.extend(0.0).into(),
                    shape: [0.0; 4],
                },
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Vec3};

    use super::*;
    use crate::scene::{Camera, Material, Mesh};

    /// A right triangle of area 0.5 in the z = 0 plane, facing +z.
    fn triangle() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        }
    }

    fn empty_scene() -> Scene {
        Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0))
    }

    #[test]
    fn emissive_triangles_are_picked_in_proportion_to_luminance_times_area() {
        let mut scene = empty_scene();
        let mesh = scene.add_mesh(triangle());
        let dim = scene.add_material(Material::emitter("dim", Vec3::ONE));
        let bright = scene.add_material(Material::emitter("bright", Vec3::splat(3.0)));
        let black = scene.add_material(Material::diffuse("black", Vec3::ZERO));
        scene.add_instance(mesh, dim, Affine3A::IDENTITY);
        scene.add_instance(mesh, black, Affine3A::IDENTITY);
        // Twice as wide (area 1) and mirrored: winding flips back to face the same way.
        scene.add_instance(
            mesh,
            bright,
            Affine3A::from_scale(Vec3::new(-2.0, 1.0, 1.0)),
        );
        let lights = emissive_triangles(&scene);
        assert_eq!(
            lights.triangles.len(),
            2,
            "the black instance emits nothing"
        );
        // Powers 1 × 0.5 and 3 × 1, of 3.5.
        assert!((lights.power - 3.5).abs() < 1e-5, "{}", lights.power);
        let picks: Vec<f32> = lights.triangles.iter().map(|t| t.emission[3]).collect();
        assert!((picks[0] - 0.5 / 3.5).abs() < 1e-6, "{picks:?}");
        assert!((picks[1] - 3.0 / 3.5).abs() < 1e-6, "{picks:?}");
        assert_eq!(lights.cdf.len(), 2);
        assert!((lights.cdf[0] - picks[0]).abs() < 1e-7);
        assert_eq!(lights.cdf[1], 1.0);
        // The mirrored triangle's corners are swapped so that its normal stays +z.
        let t = &lights.triangles[1];
        let [p0, p1, p2] = [t.p0, t.p1, t.p2].map(|p| Vec3::from_slice(&p[..3]));
        assert!((p1 - p0).cross(p2 - p0).z > 0.0);
    }

    #[test]
    fn light_selection_splits_by_power_with_a_cdf_ending_at_one() {
        let mut scene = empty_scene();
        scene.environment = Vec3::splat(0.5);
        scene.lights = [
            Light::Point {
                position: Vec3::ZERO,
                intensity: Vec3::splat(2.0),
                radius: 0.0,
            },
            Light::Distant {
                direction: -Vec3::Y,
                irradiance: Vec3::ONE,
                angular_diameter: 0.5,
            },
        ]
        .map(Into::into)
        .to_vec();
        // A scene of radius 1: a root node spanning a cube of diagonal 2.
        let root = BvhNode {
            min: [-1.0 / 3f32.sqrt(); 3],
            max: [1.0 / 3f32.sqrt(); 3],
            first: 0,
            count: 0,
        };
        let selection = light_selection(&scene, Some(&root), 1.0);
        let pi = std::f64::consts::PI;
        // Environment 0.5 · 4π², triangles π · 1, point 4π · 2, distant π · 1.
        let powers = [0.5 * 4.0 * pi * pi, pi, 8.0 * pi, pi];
        let total: f64 = powers.iter().sum();
        let expected = powers.map(|p| (p / total) as f32);
        let got = [
            selection.environment_pick,
            selection.triangle_pick,
            selection.analytic_lights[0].intensity[3],
            selection.analytic_lights[1].intensity[3],
        ];
        for (g, e) in got.iter().zip(expected) {
            assert!((g - e).abs() < 1e-5, "picks {got:?}, expected {expected:?}");
        }
        let cdf: Vec<f32> = selection
            .analytic_lights
            .iter()
            .map(|l| l.shape[3])
            .collect();
        assert!((cdf[0] - (expected[0] + expected[1] + expected[2])).abs() < 1e-5);
        assert_eq!(cdf[1], 1.0);
        assert_eq!(selection.analytic_lights[0].kind, LIGHT_POINT);
        assert_eq!(selection.analytic_lights[1].kind, LIGHT_DISTANT);
    }

    #[test]
    fn a_scene_without_light_selects_nothing() {
        let mut scene = empty_scene();
        scene.add_light(Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ZERO,
            radius: 0.0,
        });
        let selection = light_selection(&scene, None, 0.0);
        assert_eq!(selection.environment_pick, 0.0);
        assert_eq!(selection.triangle_pick, 0.0);
        assert!(selection.analytic_lights.is_empty());
    }
}
