// Test kernel: closest hit through the two-level BVH next to a brute-force loop over every
// triangle of every instance, with the same ray-triangle test. Used by tests/bvh_traversal.rs.
//
// probe_in: [0] = (ray count, instance count, 0, 0); then per GPU instance
// (first triangle, triangle count, 0, 0); then per ray two vec4s (origin, direction) as f32 bits.
// probe_out per ray: (bvh t bits, bvh triangle, brute t bits, brute triangle); a miss is
// t = 0xffffffff.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<u32>>;

const MISS: u32 = 0xffffffffu;

fn brute_force(ray: Ray) -> SceneHit {
    var best = SceneHit(false, 3.0e38, 0u, 0u, 0.0, 0.0);
    let instance_count = probe_in[0].y;
    for (var i = 0u; i < instance_count; i++) {
        let inst = fetch_instance(i);
        let range = probe_in[1u + i];
        let local = Ray(transform_point(inst.to_object, ray.origin), transform_vector(inst.to_object, ray.dir));
        let rs = ray_shear(local.dir);
        for (var t = range.x; t < range.x + range.y; t++) {
            let tri = fetch_triangle(t);
            let h = intersect_triangle(local, rs, best.t, tri.p0.xyz, tri.p1.xyz, tri.p2.xyz);
            if (h.hit) {
                best = SceneHit(true, h.t, i, t, h.b1, h.b2);
            }
        }
    }
    return best;
}

@compute @workgroup_size(64)
fn bvh_probe(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    if (index >= header.x) {
        return;
    }
    let base = 1u + header.y + 2u * index;
    let ray = Ray(bitcast<vec3<f32>>(probe_in[base].xyz), bitcast<vec3<f32>>(probe_in[base + 1u].xyz));
    let a = intersect_scene(ray);
    let b = brute_force(ray);
    probe_out[index] = vec4<u32>(
        select(MISS, bitcast<u32>(a.t), a.hit),
        a.triangle,
        select(MISS, bitcast<u32>(b.t), b.hit),
        b.triangle,
    );
}
