// Test kernel: samples of the Henyey–Greenstein phase function (shaders/media/phase.wgsl).
// probe_in: [0] = (samples per configuration, seed, configurations, 0), then one vec4
// per configuration: (g, d.x, d.y, d.z) as f32 bits, d the propagation direction.
// probe_out per sample: (wi, hg_phase(dot(d, wi), g)).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn phase_sample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let count = probe_in[0].x;
    if (index >= count * probe_in[0].z) {
        return;
    }
    let config = bitcast<vec4<f32>>(probe_in[1u + index / count]);
    let g = config.x;
    let d = normalize(config.yzw);
    rng_seed(index, 0u, probe_in[0].y);
    let wi = hg_sample(d, g, rand2());
    probe_out[index] = vec4<f32>(wi, hg_phase(dot(d, wi), g));
}
