// Test kernel: individual samples of one lobe configuration, for checks on single
// directions (smooth lobes, debugging). probe_in: [0] = (count, seed, 0, 0), then one
// configuration (tests/lobe_dispatch.wgsl) from [2]. probe_out per sample, 3 vec4:
// (wi, pdf), (weight, flags: 1 valid, 2 delta), (eval(wi), pdf(wi)).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn bsdf_raw(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    if (index >= probe_in[0].x * probe_in[0].z) {
        return;
    }
    let p = lobe_params(2u + CONFIG_STRIDE * (index / probe_in[0].x));
    rng_seed(index, 0u, probe_in[0].y);
    let s = lobe_sample(p);
    let flags = select(0u, 1u, s.valid) | select(0u, 2u, s.delta);
    probe_out[3u * index] = vec4<f32>(s.wi, s.pdf);
    probe_out[3u * index + 1u] = vec4<f32>(s.weight, f32(flags));
    probe_out[3u * index + 2u] = vec4<f32>(lobe_eval(p, s.wi), lobe_pdf(p, s.wi));
}
