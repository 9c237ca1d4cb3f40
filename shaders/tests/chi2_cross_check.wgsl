// Test kernel: the GPU halves of the BSDF chi-square, one direction at a time, so the host
// can compare them with the self-tested CPU harness (tests/common/chi2.rs SphereBins):
// mode 0 gives the cell `sphere_cell` (tests/lobe_dispatch.wgsl) bins a direction into,
// mode 1 the configuration's `lobe_pdf` at the direction (f32 bits).
//
// probe_in: [0] = (count, theta bins, phi bins, mode), then one configuration
// (CONFIG_STRIDE vec4s, tests/lobe_dispatch.wgsl) from [1], then one direction per vec4
// (xyz as f32 bits). probe_out: one u32 per direction.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<u32>;

@compute @workgroup_size(64)
fn chi2_cross_check(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    if (index >= header.x) {
        return;
    }
    let dir = bitcast<vec3<f32>>(probe_in[1u + CONFIG_STRIDE + index].xyz);
    if (header.w == 0u) {
        probe_out[index] = sphere_cell(dir, header.y, header.z);
    } else {
        probe_out[index] = bitcast<u32>(lobe_pdf(lobe_params(1u), dir));
    }
}
