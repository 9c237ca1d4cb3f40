//! BVH traversal on the GPU against brute force: for 10^5 random rays through random and
//! degenerate meshes under several instance transforms, the closest hit found through the
//! two-level BVH equals the closest hit of a loop over every triangle (same WGSL
//! ray-triangle test, run in the same kernel).

mod common;

use common::{gpu, settings};
use glam::{Affine3A, Quat, Vec3};
use kiln::accel::build_scene_accel;
use kiln::render::probe::{Probe, run_probe};
use kiln::scene::{Camera, Material, Mesh, Scene};
use kiln::shader::bindings::TexelReads;

const RAYS: u32 = 100_000;
const MISS: u32 = u32::MAX;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        // SplitMix64
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * 2.0 * scale - Vec3::splat(scale)
    }
}

fn soup(rng: &mut Rng, count: usize, extent: f32, size: f32) -> Mesh {
    let mut mesh = Mesh {
        name: "random soup".into(),
        ..Mesh::default()
    };
    for i in 0..count as u32 {
        let c = rng.vec(extent);
        for _ in 0..3 {
            mesh.positions.push(c + rng.vec(size));
        }
        mesh.indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    mesh
}

/// Zero-area triangles (repeated vertices, collinear points), axis-aligned triangles and
/// stacks of coplanar, overlapping triangles, mixed with ordinary ones.
fn degenerate(rng: &mut Rng) -> Mesh {
    let mut mesh = Mesh {
        name: "degenerate".into(),
        ..Mesh::default()
    };
    let push = |mesh: &mut Mesh, p: [Vec3; 3]| {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(p);
        mesh.indices.push([base, base + 1, base + 2]);
    };
    for _ in 0..200 {
        let a = rng.vec(1.0);
        let b = rng.vec(1.0);
        push(&mut mesh, [a, a, a]);
        push(&mut mesh, [a, b, a]);
        push(&mut mesh, [a, (a + b) * 0.5, b]);
    }
    for axis in 0..3 {
        for k in 0..60 {
            let c = -1.0 + k as f32 / 30.0;
            let mut p = [rng.vec(1.0), rng.vec(1.0), rng.vec(1.0)];
            for v in &mut p {
                v[axis] = c;
            }
            push(&mut mesh, p);
        }
    }
    // Coplanar, overlapping: 100 triangles in the plane z = 0.25.
    for _ in 0..100 {
        let mut p = [rng.vec(0.8), rng.vec(0.8), rng.vec(0.8)];
        for v in &mut p {
            v.z = 0.25;
        }
        push(&mut mesh, p);
    }
    for _ in 0..300 {
        let c = rng.vec(1.0);
        push(
            &mut mesh,
            [c + rng.vec(0.1), c + rng.vec(0.1), c + rng.vec(0.1)],
        );
    }
    mesh
}

fn test_scene(rng: &mut Rng) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 45.0));
    let m = scene.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
    let a = scene.add_mesh(soup(rng, 3000, 1.0, 0.15));
    let b = scene.add_mesh(degenerate(rng));
    scene.add_instance(a, m, Affine3A::IDENTITY);
    scene.add_instance(
        a,
        m,
        Affine3A::from_scale_rotation_translation(
            Vec3::new(0.5, 1.5, 0.7),
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.4),
            Vec3::new(1.5, -0.5, 0.3),
        ),
    );
    scene.add_instance(b, m, Affine3A::from_translation(Vec3::new(-1.2, 0.4, -0.3)));
    // A mirroring transform.
    scene.add_instance(
        b,
        m,
        Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0))
            * Affine3A::from_translation(Vec3::new(-1.0, 0.0, 0.5)),
    );
    scene
}

/// A vector as the f32 bits of a vec4 with w = 0.
fn bits4(v: Vec3) -> [u32; 4] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits(), 0]
}

#[test]
fn bvh_closest_hit_matches_brute_force_for_random_and_degenerate_meshes() {
    check_against_brute_force(None);
}

/// The same with 100 kB pages: triangles and BVH nodes are then split over several
/// pages, and traversal crosses page boundaries.
#[test]
fn paged_scene_buffers_give_the_same_hits() {
    check_against_brute_force(Some(100_000));
}

/// A scene is read as texel tables unless a page size asks for pages; the two give the
/// same film, bit for bit (the same values reach the same traversal).
#[test]
fn texel_tables_and_storage_pages_render_the_same_film() {
    let ctx = gpu();
    let scene = kiln::scene::default_scene().expect("bundled scene");
    let texels = settings(24, 24, 4);
    let pages = kiln::render::RenderSettings {
        page_bytes: Some(1 << 26),
        ..texels
    };
    let a = common::render(&ctx, &scene, texels);
    let b = common::render(&ctx, &scene, pages);
    assert!(
        a.radiance().iter().any(|c| c.max_element() > 0.0),
        "a lit film"
    );
    assert_eq!(
        film_bits(&a),
        film_bits(&b),
        "texel tables against storage pages"
    );
}

/// The bits of a film's radiance, for comparisons that must be exact.
fn film_bits(film: &kiln::film::Film) -> Vec<u32> {
    film.radiance()
        .iter()
        .flat_map(|c| c.to_array().map(f32::to_bits))
        .collect()
}

/// Texel tables read as sampled textures and as read-only storage textures (what each
/// adapter gets: `GpuContext::texel_reads`) give the same film, bit for bit.
#[test]
fn sampled_and_storage_texel_reads_render_the_same_film() {
    let ctx = gpu();
    assert!(
        ctx.storage_texels,
        "{} cannot read storage texels; this test needs an adapter that can (lavapipe can)",
        ctx.describe()
    );
    let scene = kiln::scene::default_scene().expect("bundled scene");
    let render = |reads| {
        let s = kiln::render::RenderSettings {
            texel_reads: Some(reads),
            ..settings(24, 24, 4)
        };
        common::render(&ctx, &scene, s)
    };
    let sampled = render(TexelReads::Sampled);
    assert!(
        sampled.radiance().iter().any(|c| c.max_element() > 0.0),
        "a lit film"
    );
    assert_eq!(
        film_bits(&sampled),
        film_bits(&render(TexelReads::Storage)),
        "sampled against storage reads"
    );
}

#[test]
fn scene_too_large_for_the_pages_is_a_clear_error() {
    let ctx = gpu();
    let scene = test_scene(&mut Rng(7));
    let mut s = settings(4, 4, 1);
    s.page_bytes = Some(4096);
    let err = match kiln::render::Renderer::new(ctx, &scene, s) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a scene four times the binding limit was accepted"),
    };
    assert!(
        err.contains("BLAS nodes") || err.contains("triangles"),
        "{err}"
    );
}

fn check_against_brute_force(page_bytes: Option<u64>) {
    let ctx = gpu();
    let mut rng = Rng(7);
    let scene = test_scene(&mut rng);

    // Triangle ranges per GPU instance: meshes are laid out in order, instances in TLAS
    // leaf order (the build is deterministic, so this matches the probe's own build).
    let accel = build_scene_accel(&scene).unwrap();
    let mut first = vec![0u32; scene.meshes.len()];
    let mut next = 0;
    for (m, mesh) in scene.meshes.iter().enumerate() {
        first[m] = next;
        next += mesh.indices.len() as u32;
    }
    let order = &accel.tlas.as_ref().unwrap().primitive_order;
    let mut input: Vec<[u32; 4]> = vec![[RAYS, order.len() as u32, 0, 0]];
    for &i in order {
        let mesh = scene.instances[i as usize].mesh;
        input.push([first[mesh], scene.meshes[mesh].indices.len() as u32, 0, 0]);
    }
    for i in 0..RAYS {
        // Rays from a sphere around the scene toward random points inside it; every tenth
        // ray is axis-parallel, which stresses slab tests with zero direction components.
        let origin = rng.vec(1.0).normalize() * 4.0;
        let mut dir = (rng.vec(1.2) - origin).normalize();
        if i % 10 == 0 {
            let axis = (i / 10 % 3) as usize;
            let mut d = Vec3::ZERO;
            d[axis] = -origin[axis].signum();
            dir = d;
        }
        input.push(bits4(origin));
        input.push(bits4(dir));
    }

    let mut probe_settings = settings(1, 1, 1);
    probe_settings.page_bytes = page_bytes;
    let out = run_probe(
        &ctx,
        &scene,
        &probe_settings,
        &Probe {
            name: "bvh probe",
            parts: &[(
                "shaders/tests/bvh_probe.wgsl",
                include_str!("../shaders/tests/bvh_probe.wgsl"),
            )],
            entry: "bvh_probe",
            input: bytemuck::cast_slice(&input),
            output_bytes: RAYS as u64 * 16,
            invocations: RAYS,
            material_params: &[],
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out: &[[u32; 4]] = bytemuck::cast_slice(&out);

    let mut hits = 0;
    let mut mismatches = Vec::new();
    for (i, &[bvh_t, bvh_tri, brute_t, brute_tri]) in out.iter().enumerate() {
        if brute_t != MISS {
            hits += 1;
        }
        // Equal t is enough where coplanar triangles tie.
        if bvh_t != brute_t {
            mismatches.push((
                i,
                f32::from_bits(bvh_t),
                bvh_tri,
                f32::from_bits(brute_t),
                brute_tri,
            ));
        }
    }
    assert!(
        mismatches.is_empty(),
        "{} of {RAYS} rays differ, e.g. {:?}",
        mismatches.len(),
        &mismatches[..mismatches.len().min(5)]
    );
    assert!(
        hits > RAYS / 4 && hits < RAYS,
        "only {hits} of {RAYS} rays hit: the test would prove little"
    );
}
