//! The node hierarchy flattened to world transforms, and the objects nodes carry that are
//! not meshes: the perspective camera and KHR_lights_punctual lights, converted to
//! Kiln's conventions.
//!
//! The walk visits each node once, whatever the file claims: a node listed under two
//! parents or in a cycle (both forbidden) is reported and not revisited, so a malicious
//! hierarchy cannot make the import exponential or endless.

use std::collections::HashSet;

use glam::{Mat4, Quat, Vec3};
use gltf::json;
use gltf::json::extensions::scene::khr_lights_punctual::Type as LightType;
use gltf::json::validation::Checked;
use kiln_plugin_api::{CameraData, LIGHT_DISTANT, LIGHT_POINT, LIGHT_SPOT, LightData};

/// Luminous efficacy of the photometric-to-radiometric conversion (lm/W at 555 nm),
/// as KHR_lights_punctual's candela and lux assume.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// A node's local transform: its matrix, or translation · rotation · scale.
pub fn local_transform(node: &json::Node) -> Mat4 {
    if let Some(m) = node.matrix {
        return Mat4::from_cols_array(&m);
    }
    let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
    let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
    let q = node
        .rotation
        .map_or(Quat::IDENTITY, |r| Quat::from_array(r.0));
    // Exporters write slightly denormalised quaternions; a zero one means nothing.
    let q = if q.length_squared() > 1e-12 && q.is_finite() {
        q.normalize()
    } else {
        Quat::IDENTITY
    };
    Mat4::from_scale_rotation_translation(s, q, t)
}

/// The nodes the import starts from: the default scene's, else scene 0's, else every
/// node that is no node's child.
pub fn root_nodes(root: &json::Root, warnings: &mut Vec<String>) -> Vec<usize> {
    let scene = match root.scene {
        Some(s) if s.value() < root.scenes.len() => Some(s.value()),
        Some(s) => {
            warnings.push(format!("the default scene {} does not exist", s.value()));
            (!root.scenes.is_empty()).then_some(0)
        }
        None => (!root.scenes.is_empty()).then_some(0),
    };
    if let Some(s) = scene {
        if root.scenes.len() > 1 {
            warnings.push(format!(
                "the file has {} scenes; only scene {s} is imported",
                root.scenes.len()
            ));
        }
        return root.scenes[s].nodes.iter().map(|n| n.value()).collect();
    }
    let mut is_child = vec![false; root.nodes.len()];
    for node in &root.nodes {
        for c in node.children.iter().flatten() {
            if let Some(flag) = is_child.get_mut(c.value()) {
                *flag = true;
            }
        }
    }
    (0..root.nodes.len()).filter(|&i| !is_child[i]).collect()
}

/// Whether KHR_node_visibility hides `node` (and so its subtree).
fn hidden(node: &json::Node) -> bool {
    node.extensions
        .as_ref()
        .and_then(|e| e.others.get("KHR_node_visibility"))
        .and_then(|v| v.get("visible"))
        .and_then(json::Value::as_bool)
        == Some(false)
}

/// Calls `visit(node, world)` for every visible node reachable from `roots`, parents
/// before children, each node at most once.
pub fn walk(
    root: &json::Root,
    roots: &[usize],
    warnings: &mut Vec<String>,
    mut visit: impl FnMut(usize, &Mat4),
) {
    let mut seen = HashSet::new();
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&n| (n, Mat4::IDENTITY)).collect();
    let mut revisits = 0usize;
    while let Some((index, parent)) = stack.pop() {
        let Some(node) = root.nodes.get(index) else {
            warnings.push(format!("node {index} does not exist"));
            continue;
        };
        if !seen.insert(index) {
            revisits += 1;
            continue;
        }
        if hidden(node) {
            continue;
        }
        let world = parent * local_transform(node);
        visit(index, &world);
        for child in node.children.iter().flatten().rev() {
            stack.push((child.value(), world));
        }
    }
    if revisits > 0 {
        warnings.push(format!(
            "the node hierarchy is not a tree ({revisits} references to nodes already placed); each node is placed once"
        ));
    }
}

/// The perspective camera of `camera`, placed at `world`.
pub fn camera(root: &json::Root, camera: usize, world: &Mat4) -> Result<CameraData, String> {
    let c = root
        .cameras
        .get(camera)
        .ok_or_else(|| format!("camera {camera} does not exist"))?;
    let Some(p) = c.perspective.as_ref() else {
        return Err(format!(
            "camera {camera} is orthographic (not supported) or has no projection"
        ));
    };
    let fov = p.yfov.to_degrees();
    if !(fov > 0.0 && fov < 180.0) {
        return Err(format!("camera {camera} has an invalid yfov of {}", p.yfov));
    }
    Ok(CameraData {
        to_world: world.to_cols_array(),
        fov_y_degrees: fov,
        aperture_radius: 0.0,
        focus_distance: 0.0,
    })
}

/// KHR_lights_punctual light `light`, placed at `world`. Lights shine down the node's −z.
pub fn light(root: &json::Root, light: usize, world: &Mat4) -> Result<LightData, String> {
    let lights = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(&[][..], |l| &l.lights[..]);
    let l = lights
        .get(light)
        .ok_or_else(|| format!("light {light} does not exist"))?;
    let Checked::Valid(kind) = l.type_ else {
        return Err(format!("light {light} has an unknown type"));
    };
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if direction == Vec3::ZERO || !direction.is_finite() {
        return Err(format!("light {light}: its node's transform is degenerate"));
    }
    let position = world.w_axis.truncate();
    // Candela (point, spot) → W/sr and lux (directional) → W/m², by 683 lm/W.
    let scale = l.intensity.max(0.0) / LUMENS_PER_WATT;
    let intensity = l.color.map(|c| c.max(0.0) * scale);
    let mut data = LightData {
        kind: LIGHT_POINT,
        position: position.to_array(),
        direction: direction.to_array(),
        intensity,
        cone_angle_degrees: 0.0,
        blend: 0.0,
        radius: 0.0,
    };
    match kind {
        LightType::Point => {}
        LightType::Directional => data.kind = LIGHT_DISTANT,
        LightType::Spot => {
            let (inner, outer) = l
                .spot
                .as_ref()
                .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| {
                    (s.inner_cone_angle, s.outer_cone_angle)
                });
            let outer = if outer.is_finite() {
                outer.clamp(1e-4, std::f32::consts::FRAC_PI_2)
            } else {
                std::f32::consts::FRAC_PI_4
            };
            let inner = if inner.is_finite() {
                inner.clamp(0.0, outer)
            } else {
                0.0
            };
            data.kind = LIGHT_SPOT;
            data.cone_angle_degrees = outer.to_degrees();
            data.blend = 1.0 - inner / outer;
        }
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trs_is_translation_after_rotation_after_scale() {
        let node: json::Node = json::deserialize::from_str(
            r#"{"translation":[1,2,3],"rotation":[0,0,0.7071068,0.7071068],"scale":[2,2,2]}"#,
        )
        .expect("node JSON");
        let m = local_transform(&node);
        // x scaled to 2, turned 90° about z to +y, moved by (1, 2, 3).
        let p = m.transform_point3(Vec3::X);
        assert!((p - Vec3::new(1.0, 4.0, 3.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn cyclic_hierarchy_visits_each_node_once() {
        let root: json::Root = json::deserialize::from_str(
            r#"{"asset":{"version":"2.0"},"nodes":[{"children":[1]},{"children":[0]}]}"#,
        )
        .expect("root JSON");
        let mut warnings = Vec::new();
        let mut visited = Vec::new();
        walk(&root, &[0], &mut warnings, |n, _| visited.push(n));
        assert_eq!(visited, vec![0, 1]);
        assert_eq!(warnings.len(), 1);
    }
}
