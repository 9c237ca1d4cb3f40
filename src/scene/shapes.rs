//! Generated meshes: the primitives a scene file can name instead of listing vertices,
//! and the large procedural meshes benchmarks use instead of committed files.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::Mesh;

/// A unit square in the XZ plane, centred on the origin, facing +Y.
pub fn quad() -> Mesh {
    Mesh {
        name: "quad".into(),
        positions: vec![
            Vec3::new(-0.5, 0.0, -0.5),
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, -0.5),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    }
}

/// The cube [-0.5, 0.5]³ with flat faces facing outwards.
pub fn cube() -> Mesh {
    let mut mesh = Mesh {
        name: "cube".into(),
        ..Mesh::default()
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                mesh.positions.push(n * 0.5 + u * a + v * b);
                mesh.normals.push(n);
                mesh.uvs.push(Vec2::new(a + 0.5, b + 0.5));
            }
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base, base + 2, base + 3]);
        }
    }
    mesh
}

/// A unit-radius UV sphere with `segments` around and `rings` from pole to pole; smooth
/// normals unless `smooth` is false (then the mesh has none and renders faceted).
pub fn uv_sphere(segments: u32, rings: u32, smooth: bool) -> Mesh {
    let segments = segments.max(3);
    let rings = rings.max(2);
    let mut mesh = Mesh {
        name: "sphere".into(),
        ..Mesh::default()
    };
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let theta = v * PI;
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            let phi = u * TAU;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            mesh.positions.push(p);
            mesh.uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            if r != 0 {
                mesh.indices.push([a, b, a + 1]);
            }
            if r != rings - 1 {
                mesh.indices.push([a + 1, b, b + 1]);
            }
        }
    }
    if smooth {
        mesh.normals = mesh.positions.clone();
    }
    mesh
}

/// A sphere of about `target_triangles` triangles whose radius is displaced by a sum of
/// sines, so its BVH is not trivially regular. For benchmarks.
pub fn displaced_sphere(target_triangles: u32) -> Mesh {
    // A UV sphere has 2 * segments * (rings - 1) triangles; use segments = 2 * rings.
    let rings = ((target_triangles as f64 / 4.0).sqrt().ceil() as u32).max(2);
    let mut mesh = uv_sphere(2 * rings, rings, true);
    mesh.name = "displaced sphere".into();
    for p in &mut mesh.positions {
        let d = 1.0
            + 0.05 * (7.0 * p.x).sin() * (9.0 * p.y).sin() * (11.0 * p.z).sin()
            + 0.02 * (31.0 * p.x + 17.0 * p.z).sin();
        *p *= d;
    }
    mesh.normals = compute_vertex_normals(&mesh.positions, &mesh.indices);
    mesh
}

/// Area-weighted vertex normals.
pub fn compute_vertex_normals(positions: &[Vec3], indices: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in indices {
        let (pa, pb, pc) = (
            positions[a as usize],
            positions[b as usize],
            positions[c as usize],
        );
        let n = (pb - pa).cross(pc - pa);
        for i in [a, b, c] {
            normals[i as usize] += n;
        }
    }
    normals
        .into_iter()
        .map(|n| n.try_normalize().unwrap_or(Vec3::Y))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signed_volume(mesh: &Mesh) -> f32 {
        (0..mesh.indices.len())
            .map(|i| {
                let [a, b, c] = mesh.triangle(i);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn cube_is_closed_outward_and_unit_volume() {
        let v = signed_volume(&cube());
        assert!((v - 1.0).abs() < 1e-5, "volume {v}");
    }

    #[test]
    fn uv_sphere_volume_approaches_four_thirds_pi() {
        let v = signed_volume(&uv_sphere(256, 128, true));
        let exact = 4.0 / 3.0 * PI;
        assert!((v - exact).abs() / exact < 1e-3, "volume {v} vs {exact}");
        assert!(uv_sphere(8, 4, true).validate().is_ok());
    }

    #[test]
    fn displaced_sphere_hits_its_triangle_budget() {
        let mesh = displaced_sphere(100_000);
        let n = mesh.indices.len() as f64;
        assert!((n / 100_000.0 - 1.0).abs() < 0.02, "{n} triangles");
        assert!(mesh.validate().is_ok());
    }
}
