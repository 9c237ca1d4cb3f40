// Test kernel: integrates a lobe's pdf over part of one chi-square cell with a dense
// midpoint rule in (θ, φ) weighted by sin θ, for lobes too sharp for bsdf_pdf.wgsl's
// bounded per-cell quadrature (GGX alpha 0.01, about a degree wide). Each invocation
// takes one of SUB × SUB blocks of a cell with K × K points, so every invocation stays
// short however fine the rule (lavapipe returns wrong results from long ones); the host
// sums the blocks.
//
// probe_in: [0] = (configs, tasks, theta bins, phi bins), [1] = (SUB, K, 0, 0), then
// CONFIG_STRIDE vec4s per configuration (tests/lobe_dispatch.wgsl), then one vec4 per task:
// (configuration, cell, block, 0). probe_out: one probability (f32) per task.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<f32>;

@compute @workgroup_size(64)
fn bsdf_pdf_refine(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    if (index >= header.y) {
        return;
    }
    let sub = probe_in[1].x;
    let k = probe_in[1].y;
    let task = probe_in[2u + CONFIG_STRIDE * header.x + index];
    let p = lobe_params(2u + CONFIG_STRIDE * task.x);
    let dz = 2.0 / f32(header.z);
    let dphi = 2.0 * PI / f32(header.w);
    let z_top = 1.0 - f32(task.y / header.w) * dz;
    let t0 = acos(clamp(z_top, -1.0, 1.0));
    let t1 = acos(clamp(z_top - dz, -1.0, 1.0));
    let n = f32(sub * k);
    let dt = (t1 - t0) / n;
    let dp = dphi / n;
    let phi0 = f32(task.y % header.w) * dphi;
    let bi = task.z / sub;
    let bj = task.z % sub;
    var sum = 0.0;
    for (var i = 0u; i < k; i++) {
        let theta = t0 + (f32(bi * k + i) + 0.5) * dt;
        let st = sin(theta);
        let ct = cos(theta);
        var row = 0.0;
        for (var j = 0u; j < k; j++) {
            let phi = phi0 + (f32(bj * k + j) + 0.5) * dp;
            row += lobe_pdf(p, vec3<f32>(st * cos(phi), st * sin(phi), ct));
        }
        sum += row * st;
    }
    probe_out[index] = sum * dt * dp;
}
