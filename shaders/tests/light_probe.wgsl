// Test kernel for next-event estimation's light selection (tests/lights.rs): the density
// sample_light gives its sample must be the one the integrator weighs a BSDF ray that
// reaches the same light by (environment_light_pdf, triangle_light_pdf and
// analytic_light_hit in shaders/lights/), or MIS is biased.
//
// probe_in: [0] = (samples, seed, 0, 0), [1] = the lower corner of the box the shading
// points are drawn from, [2] = its upper corner (f32 bits).
// probe_out per sample: (what was sampled: LIGHT_SAMPLED_*, or 0xffffffff for no sample;
// the sample's pdf; the integrator's pdf for its direction; 0), pdfs as f32 bits.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<u32>>;

@compute @workgroup_size(64)
fn light_probe(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let h = probe_in[0];
    if (index >= h.x) {
        return;
    }
    rng_seed(index, 5u, h.y);
    let lo = bitcast<vec3<f32>>(probe_in[1].xyz);
    let hi = bitcast<vec3<f32>>(probe_in[2].xyz);
    let p = mix(lo, hi, vec3<f32>(rand(), rand(), rand()));
    let ls = sample_light(p);
    if (!(ls.pdf > 0.0) || !ls.mis) {
        probe_out[index] = vec4<u32>(0xffffffffu, 0u, 0u, 0u);
        return;
    }
    var pdf = 0.0;
    switch (light_sampled) {
        case LIGHT_SAMPLED_ENVIRONMENT: {
            pdf = environment_light_pdf(p, ls.wi);
        }
        case LIGHT_SAMPLED_TRIANGLE: {
            let hit = intersect_scene(Ray(p, ls.wi));
            if (hit.hit) {
                let s = surface_at(hit);
                let emission = fetch_material(s.material).emission.rgb;
                pdf = triangle_light_pdf(p, emission, hit.t, -dot(ls.wi, s.ng));
            }
        }
        default: {
            pdf = analytic_light_hit(p, ls.wi, 3.0e38, infinite_light_pick(p)).pdf;
        }
    }
    probe_out[index] = vec4<u32>(light_sampled, bitcast<u32>(ls.pdf), bitcast<u32>(pdf), 0u);
}
