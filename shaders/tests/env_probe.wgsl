// Test kernel for environment-map sampling (tests/environment.rs). Needs
// tests/lobe_dispatch.wgsl for `sphere_cell`.
//
// probe_in: [0] = (samples, seed, theta bins, phi bins), [1] = (0, 0, k, 0).
// env_sample: one sample per invocation into a histogram of cells (atomic counts), then
// the count of invalid samples at index cells.
// env_pdf: one invocation per cell, the k × k midpoint integral of environment_pdf over
// it, stored as f32 bits.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<atomic<u32>>;

@compute @workgroup_size(64)
fn env_sample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let h = probe_in[0];
    if (index >= h.x) {
        return;
    }
    rng_seed(index, 3u, h.y);
    let s = sample_environment(rand2());
    if (s.pdf <= 0.0 || !all_finite(vec4<f32>(s.wi, s.pdf))) {
        atomicAdd(&probe_out[h.z * h.w], 1u);
        return;
    }
    atomicAdd(&probe_out[sphere_cell(s.wi, h.z, h.w)], 1u);
}

@compute @workgroup_size(64)
fn env_pdf(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let h = probe_in[0];
    if (index >= h.z * h.w) {
        return;
    }
    let k = probe_in[1].z;
    let dz = 2.0 / f32(h.z);
    let dphi = 2.0 * PI / f32(h.w);
    let z_top = 1.0 - f32(index / h.w) * dz;
    let f0 = f32(index % h.w) * dphi;
    var sum = 0.0;
    for (var i = 0u; i < k; i++) {
        let z = z_top - (f32(i) + 0.5) * dz / f32(k);
        let r = sqrt(max(0.0, 1.0 - z * z));
        for (var j = 0u; j < k; j++) {
            let phi = f0 + (f32(j) + 0.5) * dphi / f32(k);
            sum += environment_pdf(vec3<f32>(r * cos(phi), r * sin(phi), z));
        }
    }
    atomicStore(&probe_out[index], bitcast<u32>(sum * dz * dphi / f32(k * k)));
}
