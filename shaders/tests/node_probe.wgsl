// Test kernel: evaluates a compiled graph value, `probe_value(sp)`
// (src/material/compile.rs, `compile_value`), at shading points read from probe_in.
//
// probe_in: [0].x = point count (as f32), then three vec4s per point: (p.xyz, u),
// (n.xyz, v), (which compiled value to evaluate, 0, 0, 0).
// The point is its own object-space and generated position; dp/du = +x, dp/dv = +y.
// probe_out: the value per point.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn node_probe(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= u32(probe_in[0].x)) {
        return;
    }
    let a = probe_in[1u + 3u * i];
    let b = probe_in[2u + 3u * i];
    let which = u32(probe_in[3u + 3u * i].x);
    let n = normalize(b.xyz);
    let sp = ShadingPoint(
        a.xyz, n, n, vec2<f32>(a.w, b.w), vec2<f32>(b.w, a.w), vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), n,
        a.xyz, n, a.xyz, vec4<f32>(1.0), 0.5, vec3<f32>(0.0), false,
    );
    probe_out[i] = probe_value(which, sp);
}
