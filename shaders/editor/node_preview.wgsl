// The node editor's per-node previews (src/editor/node_previews.rs): `node_preview(sp)`,
// generated per preview from the node's output, evaluated at one shading point per pixel
// of a unit sphere seen head-on through an orthographic camera. No rays, no lights, no
// accumulation: the kernel is small, so it compiles in a fraction of the path tracer's
// time.
//
// probe_in: [0].x = pixel count (as f32), then three vec4s per pixel: (p.xyz, u),
// (n.xyz, v), (generated.xyz, coverage). The point is its own object-space position; dp/du
// and dp/dv are the sphere's, from its UVs (shapes::uv_sphere's convention).
// probe_out: the linear colour per pixel, alpha = coverage (0 off the sphere).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

const PREVIEW_PI: f32 = 3.14159265358979;

@compute @workgroup_size(64)
fn node_preview_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= u32(probe_in[0].x)) {
        return;
    }
    let a = probe_in[1u + 3u * i];
    let b = probe_in[2u + 3u * i];
    let c = probe_in[3u + 3u * i];
    if (c.w <= 0.0) {
        probe_out[i] = vec4<f32>(0.0);
        return;
    }
    let n = normalize(b.xyz);
    // p = (sin θ cos φ, cos θ, -sin θ sin φ) with u = φ / 2π, v = θ / π.
    let theta = b.w * PREVIEW_PI;
    let phi = a.w * 2.0 * PREVIEW_PI;
    let dpdu = 2.0 * PREVIEW_PI * vec3<f32>(-sin(theta) * sin(phi), 0.0, -sin(theta) * cos(phi));
    let dpdv = PREVIEW_PI * vec3<f32>(cos(theta) * cos(phi), -sin(theta), -cos(theta) * sin(phi));
    let sp = ShadingPoint(
        a.xyz, n, n, vec2<f32>(a.w, b.w), vec2<f32>(0.0), dpdu, dpdv, vec3<f32>(0.0, 0.0, 1.0),
        a.xyz, n, c.xyz, vec4<f32>(1.0), 0.5, vec3<f32>(0.0), false,
    );
    probe_out[i] = vec4<f32>(nd_finite3(node_preview(sp)), c.w);
}
