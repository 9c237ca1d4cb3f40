//! Which light next-event estimation samples: the emissive triangles of the scene's
//! instances, picked in proportion to power through a CDF, and the split of samples
//! between the lights at infinity (the environment, distant lights) and the local ones
//! (those triangles, point and spot lights).
//!
//! The split is made at each shading point (`infinite_light_pick` in
//! shaders/integrator/path.wgsl), as the root of a light tree would (pbrt-v4's
//! BVHLightSampler, Cycles' light tree): the irradiance the lights at infinity give a
//! surface facing them against the local lights' summed intensity over the squared
//! distance to their bounds, each side kept at 10 % at least. Within each side lights
//! are picked by power. A global split by power alone weighed the environment by the area
//! of the scene's bounding sphere: under a dim sky, `materials.kiln`'s 30 m floor gave it
//! 94 % of the light samples while the lamp lit the spheres four times as brightly.
//!
//! Estimates only steer sampling: any positive split is unbiased, a good one lowers
//! noise. Not here: the sampling itself (`shaders/lights/`), the environment map's own
//! distribution (`environment_cdf`) and the upload (`gpu_scene`).

use glam::Vec3;

use super::environment_cdf::{luminance, mean_environment_luminance};
use crate::scene::{Light, Scene};
use crate::shader::gpu_types::{
    GpuAnalyticLight, GpuLightTriangle, LIGHT_DISTANT, LIGHT_POINT, LIGHT_SPOT,
};

/// Every front-facing emissive triangle in world space, with its pick distribution.
#[derive(Clone, Debug)]
pub struct EmissiveTriangles {
    /// In instance order; `emission.w` is the triangle's pick probability.
    pub triangles: Vec<GpuLightTriangle>,
    /// Inclusive CDF over `triangles`, ending at exactly 1.
    pub cdf: Vec<f32>,
    /// Sum of luminance × area.
    pub power: f32,
    /// The corners' bounds, empty (min > max) without triangles.
    pub bounds: [Vec3; 2],
}

impl Default for EmissiveTriangles {
    /// No triangles, and bounds that any point grows.
    fn default() -> Self {
        Self {
            triangles: Vec::new(),
            cdf: Vec::new(),
            power: 0.0,
            bounds: [Vec3::INFINITY, Vec3::NEG_INFINITY],
        }
    }
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
            for p in [p0, p1, p2] {
                lights.bounds = [lights.bounds[0].min(p), lights.bounds[1].max(p)];
            }
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
    /// Probability of sampling the environment among the lights at infinity.
    pub environment_pick: f32,
    /// Probability of sampling an emissive triangle among the local lights.
    pub triangle_pick: f32,
    /// The scene's lights in order; `intensity.w` is each one's pick probability among
    /// the lights on its side (at infinity or local) and `shape.w` the inclusive CDF over
    /// its side, counting from the environment's or the triangles' probability (the last
    /// of each side exactly 1).
    pub analytic_lights: Vec<GpuAnalyticLight>,
    /// x: the irradiance of the lights at infinity on a surface facing them (luminance);
    /// y: the local lights' summed intensity (luminance × area for triangles); zw: 0.
    pub split: [f32; 4],
    /// The local lights' bounding sphere: centre and squared radius.
    pub local_bounds: [f32; 4],
}

/// Splits next-event estimation between the lights at infinity and the local ones
/// (emissive triangles `triangles`, from [`emissive_triangles`]), and within each side
/// in proportion to estimated power.
pub fn light_selection(scene: &Scene, triangles: &EmissiveTriangles) -> LightSelection {
    let pi = std::f64::consts::PI;
    let sky = match &scene.environment_map {
        Some(map) => mean_environment_luminance(map),
        None => luminance(scene.environment) as f64,
    };
    // A uniform sky of radiance L gives a surface facing it π L.
    let environment = pi * sky;
    let triangle_power = pi * triangles.power as f64;
    let analytic: Vec<AnalyticLight> = scene
        .lights
        .iter()
        .map(|object| analytic_light(&object.light))
        .collect();
    let at_infinity = |l: &AnalyticLight| l.gpu.kind == LIGHT_DISTANT;
    let analytic_power = |infinite: bool| -> f64 {
        analytic
            .iter()
            .filter(|l| at_infinity(l) == infinite)
            .map(|l| l.power)
            .sum()
    };
    let infinite_total = environment + analytic_power(true);
    let local_total = triangle_power + analytic_power(false);
    let mut selection = LightSelection::default();
    if infinite_total + local_total <= 0.0 {
        return selection;
    }
    if infinite_total > 0.0 {
        selection.environment_pick = (environment / infinite_total) as f32;
    }
    if local_total > 0.0 {
        selection.triangle_pick = (triangle_power / local_total) as f32;
    }
    let mut bounds = triangles.bounds;
    let mut intensity = triangles.power as f64;
    let (mut infinite_cdf, mut local_cdf) = (environment, triangle_power);
    for light in analytic {
        let mut gpu = light.gpu;
        let (total, cdf) = if at_infinity(&light) {
            (infinite_total, &mut infinite_cdf)
        } else {
            let position = Vec3::from(gpu.position);
            let radius = Vec3::splat(gpu.axis[3].max(0.0));
            if light.power > 0.0 {
                bounds = [
                    bounds[0].min(position - radius),
                    bounds[1].max(position + radius),
                ];
            }
            intensity += light.intensity;
            (local_total, &mut local_cdf)
        };
        if total > 0.0 {
            *cdf += light.power;
            gpu.intensity[3] = (light.power / total) as f32;
            gpu.shape[3] = (*cdf / total) as f32;
        }
        selection.analytic_lights.push(gpu);
    }
    // The last light of each side ends its CDF at exactly 1.
    for side in [true, false] {
        if let Some(last) = selection
            .analytic_lights
            .iter_mut()
            .rev()
            .find(|l| (l.kind == LIGHT_DISTANT) == side && l.intensity[3] > 0.0)
        {
            last.shape[3] = 1.0;
        }
    }
    if local_total > 0.0 && bounds[0].cmple(bounds[1]).all() {
        let centre = 0.5 * (bounds[0] + bounds[1]);
        let radius2 = (0.5 * (bounds[1] - bounds[0])).length_squared();
        selection.local_bounds = centre.extend(radius2).into();
        selection.split[1] = intensity as f32;
    }
    selection.split[0] = infinite_total as f32;
    selection
}

/// An analytic light's GPU form (pick fields zero) with what light selection weighs it
/// by: its power (luminance), or for a distant light its irradiance; and for a local one
/// its intensity, what it gives a point at unit distance.
struct AnalyticLight {
    gpu: GpuAnalyticLight,
    power: f64,
    intensity: f64,
}

fn analytic_light(light: &Light) -> AnalyticLight {
    let pi = std::f64::consts::PI;
    match *light {
        Light::Point {
            position,
            intensity,
            radius,
        } => {
            let i = luminance(intensity) as f64;
            AnalyticLight {
                gpu: GpuAnalyticLight {
                    position: position.into(),
                    kind: LIGHT_POINT,
                    axis: [0.0, 0.0, 1.0, radius],
                    intensity: intensity.extend(0.0).into(),
                    shape: [0.0; 4],
                },
                power: 4.0 * pi * i,
                intensity: i,
            }
        }
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
            let i = luminance(intensity) as f64;
            AnalyticLight {
                gpu: GpuAnalyticLight {
                    position: position.into(),
                    kind: LIGHT_SPOT,
                    axis: direction.normalize().extend(radius).into(),
                    intensity: intensity.extend(0.0).into(),
                    shape: [outer.cos(), inner.cos(), 0.0, 0.0],
                },
                power: 2.0 * pi * (1.0 - outer.cos() as f64) * i,
                intensity: i,
            }
        }
        Light::Distant {
            direction,
            irradiance,
            angular_diameter,
        } => {
            let half = (0.5 * angular_diameter).to_radians();
            let s = (0.5 * half).sin();
            AnalyticLight {
                gpu: GpuAnalyticLight {
                    position: direction.normalize().into(),
                    kind: LIGHT_DISTANT,
                    // 1 - cos(half) without cancellation.
                    axis: [0.0, 0.0, 1.0, 2.0 * s * s],
                    intensity: irradiance.extend(0.0).into(),
                    shape: [0.0; 4],
                },
                power: luminance(irradiance) as f64,
                intensity: 0.0,
            }
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
    fn light_selection_splits_each_side_by_power_with_cdfs_ending_at_one() {
        let mut scene = empty_scene();
        scene.environment = Vec3::splat(0.5);
        scene.lights = [
            Light::Point {
                position: Vec3::new(0.0, 0.0, 4.0),
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
        // One emissive triangle of luminance × area 1, spanning x, y in [0, 2].
        let mesh = scene.add_mesh(triangle());
        let lamp = scene.add_material(Material::emitter("lamp", Vec3::ONE));
        scene.add_instance(mesh, lamp, Affine3A::from_scale(Vec3::new(2.0, 2.0, 1.0)));
        let triangles = emissive_triangles(&scene);
        assert!((triangles.power - 2.0).abs() < 1e-6, "{}", triangles.power);
        let selection = light_selection(&scene, &triangles);
        let pi = std::f64::consts::PI;
        // At infinity: the sky's irradiance 0.5 π and the sun's 1. Local: the triangle's
        // power π · 2 and the point light's 4π · 2.
        let infinite = 0.5 * pi + 1.0;
        let local = 2.0 * pi + 8.0 * pi;
        let expected = [0.5 * pi / infinite, 0.2, 0.8, 1.0 / infinite].map(|p| p as f32);
        let got = [
            selection.environment_pick,
            selection.triangle_pick,
            selection.analytic_lights[0].intensity[3],
            selection.analytic_lights[1].intensity[3],
        ];
        for (g, e) in got.iter().zip(expected) {
            assert!((g - e).abs() < 1e-5, "picks {got:?}, expected {expected:?}");
        }
        assert!(((2.0 * pi / local) as f32 - expected[1]).abs() < 1e-6);
        // Each side's CDF counts on from the environment's or the triangles' share.
        assert_eq!(selection.analytic_lights[0].shape[3], 1.0);
        assert_eq!(selection.analytic_lights[1].shape[3], 1.0);
        assert_eq!(selection.analytic_lights[0].kind, LIGHT_POINT);
        assert_eq!(selection.analytic_lights[1].kind, LIGHT_DISTANT);
        // The split: irradiance at infinity; the local intensities (2 + 2) and their
        // bounds, from (0, 0, 0) to (2, 2, 4).
        let [e, i, _, _] = selection.split;
        assert!((e - infinite as f32).abs() < 1e-5, "{:?}", selection.split);
        assert!((i - 4.0).abs() < 1e-5, "{:?}", selection.split);
        let [x, y, z, r2] = selection.local_bounds;
        assert_eq!([x, y, z], [1.0, 1.0, 2.0]);
        assert!((r2 - 6.0).abs() < 1e-5, "{r2}");
    }

    #[test]
    fn one_side_alone_takes_every_sample() {
        let mut scene = empty_scene();
        scene.environment = Vec3::splat(0.5);
        let selection = light_selection(&scene, &emissive_triangles(&scene));
        assert_eq!(selection.environment_pick, 1.0);
        assert_eq!(selection.split[1], 0.0, "no local lights");
        scene.environment = Vec3::ZERO;
        scene.add_light(Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
            radius: 0.0,
        });
        let selection = light_selection(&scene, &emissive_triangles(&scene));
        assert_eq!(selection.split[0], 0.0, "nothing at infinity");
        assert_eq!(selection.triangle_pick, 0.0);
        assert_eq!(selection.analytic_lights[0].intensity[3], 1.0);
    }

    #[test]
    fn a_scene_without_light_selects_nothing() {
        let mut scene = empty_scene();
        scene.add_light(Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ZERO,
            radius: 0.0,
        });
        let selection = light_selection(&scene, &emissive_triangles(&scene));
        assert_eq!(selection.environment_pick, 0.0);
        assert_eq!(selection.triangle_pick, 0.0);
        assert!(selection.analytic_lights.is_empty());
    }
}
