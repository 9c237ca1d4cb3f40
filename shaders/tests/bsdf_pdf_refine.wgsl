// Test kernel: integrates a lobe's pdf over part of one chi-square cell with a dense
// midpoint rule in (θ, φ) weighted by sin θ, for lobes too sharp for bsdf_pdf.wgsl's
// bounded per-cell quadrature (GGX alpha 0.01, about a degree wide). Each invocation
// takes one of SUB_θ × SUB blocks of a cell with K × K points, so every invocation stays
// short however fine the rule (lavapipe returns wrong results from long ones); the host
// sums the blocks. The polar bands take more blocks in θ: a refraction lobe at normal
// incidence is a few milliradians wide.
//
// probe_in: [0] = (configs, tasks, theta bins, phi bins), [1] = (SUB, K, 0, 0), then
// CONFIG_STRIDE vec4s per configuration (tests/lobe_dispatch.wgsl), then the bands' θ
// edges (theta bins + 1, f32 bits in x, computed in f64 by the host: acos is no more
// precise than cos), then one vec4 per task: (configuration, cell, block, SUB_θ).
// probe_out: one probability (f32) per task.

//
// Vulkan only promises sin and cos to 2^-11 absolute, which near the poles and the horizon
// moves a direction by more than a sharp lobe is wide: this kernel computes its own, to
// f32 precision (Cody–Waite reduction and the minimax polynomials of Cephes' sinf/cosf).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<f32>;

// (sin x, cos x) for 0 <= x <= 2π + a little.
fn precise_sincos(x: f32) -> vec2<f32> {
    let q = floor(x * (2.0 / PI) + 0.5);
    // π/2 split in three so q · π/2 is subtracted exactly.
    let r = ((x - q * 1.5703125) - q * 4.837512969970703125e-4) - q * 7.54978995489188216e-8;
    let r2 = r * r;
    let s = r + r * r2 * (-1.6666654611e-1 + r2 * (8.3321608736e-3 + r2 * -1.9515295891e-4));
    let c = 1.0 - 0.5 * r2 + r2 * r2 * (4.166664568298827e-2 + r2 * (-1.388731625493765e-3 + r2 * 2.443315711809948e-5));
    switch (u32(q) & 3u) {
        case 0u: { return vec2<f32>(s, c); }
        case 1u: { return vec2<f32>(c, -s); }
        case 2u: { return vec2<f32>(-s, -c); }
        default: { return vec2<f32>(-c, s); }
    }
}

@compute @workgroup_size(64)
fn bsdf_pdf_refine(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    if (index >= header.y) {
        return;
    }
    let sub = probe_in[1].x;
    let k = probe_in[1].y;
    let edges = 2u + CONFIG_STRIDE * header.x;
    let task = probe_in[edges + header.z + 1u + index];
    let p = lobe_params(2u + CONFIG_STRIDE * task.x);
    let dphi = 2.0 * PI / f32(header.w);
    let band = task.y / header.w;
    let t0 = bitcast<f32>(probe_in[edges + band].x);
    let t1 = bitcast<f32>(probe_in[edges + band + 1u].x);
    let sub_theta = task.w;
    let dt = (t1 - t0) / f32(sub_theta * k);
    let dp = dphi / f32(sub * k);
    let phi0 = f32(task.y % header.w) * dphi;
    let bi = task.z / sub;
    let bj = task.z % sub;
    var sum = 0.0;
    for (var i = 0u; i < k; i++) {
        let theta = t0 + (f32(bi * k + i) + 0.5) * dt;
        let sc_t = precise_sincos(theta);
        let st = sc_t.x;
        let ct = sc_t.y;
        var row = 0.0;
        for (var j = 0u; j < k; j++) {
            let phi = phi0 + (f32(bj * k + j) + 0.5) * dp;
            let sc_p = precise_sincos(phi);
            row += lobe_pdf(p, vec3<f32>(st * sc_p.y, st * sc_p.x, ct));
        }
        sum += row * st;
    }
    probe_out[index] = sum * dt * dp;
}
