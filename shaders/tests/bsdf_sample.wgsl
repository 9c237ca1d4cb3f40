// Test kernel: samples many lobe configurations at once. Each invocation takes
// SAMPLES_PER_INVOCATION samples of one configuration, adds their directions to that
// configuration's histogram (atomics), and writes its partial sums.
//
// probe_in: [0] = (configs, samples per config, theta bins, phi bins), [1] = (seed, first,
// 0, 0), then CONFIG_STRIDE vec4s per configuration (tests/lobe_dispatch.wgsl). `first` is
// the index of the first configuration in the whole set, which the random numbers follow:
// a set sampled in parts (one per lobe kind) draws what it would draw in one dispatch.
// probe_out (u32): configs × cells histogram counts, then per invocation 8 words:
// valid, delta, non-finite, weight sum r, g, b (f32 bits),
// samples whose weight or pdf disagrees with eval / pdf(wi) by over 1e-2 relative, and the
// largest such disagreement (f32 bits).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<atomic<u32>>;

const SAMPLES_PER_INVOCATION: u32 = 256u;

fn relative_error(a: f32, b: f32) -> f32 {
    let scale = max(abs(a), abs(b));
    if (scale == 0.0) {
        return 0.0;
    }
    return abs(a - b) / scale;
}

@compute @workgroup_size(64)
fn bsdf_sample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    let configs = header.x;
    let per_config = header.y / SAMPLES_PER_INVOCATION;
    if (index >= configs * per_config) {
        return;
    }
    let config = index / per_config;
    let first = probe_in[1].y;
    let cells = header.z * header.w;
    let p = lobe_params(2u + CONFIG_STRIDE * config);
    var valid = 0u;
    var delta = 0u;
    var non_finite = 0u;
    var weight_sum = vec3<f32>(0.0);
    var inconsistent = 0u;
    var max_error = 0.0;
    for (var i = 0u; i < SAMPLES_PER_INVOCATION; i++) {
        rng_seed((index + first * per_config) * SAMPLES_PER_INVOCATION + i, config + first, probe_in[1].x);
        let s = lobe_sample(p);
        if (!all_finite(vec4<f32>(s.wi, s.pdf)) || !all_finite(vec4<f32>(s.weight, 0.0))) {
            non_finite++;
            continue;
        }
        if (!s.valid) {
            continue;
        }
        valid++;
        // Energy, not radiance: undo the 1/etap² radiance scaling of refraction, which
        // legitimately makes radiance weights exceed 1 when leaving a dense medium.
        var energy = s.weight;
        var eta = p.eta;
        if (p.kind == 5u) {
            eta = p.principled.ior;
        }
        let transmissive = p.kind == 2u || (p.kind == 5u && p.principled.transmission_weight > 0.0);
        if (transmissive && !p.thin && s.wi.z * p.wo.z < 0.0 && eta != 1.0) {
            let etap = select(1.0 / eta, eta, p.wo.z > 0.0);
            energy *= etap * etap;
        }
        weight_sum += energy;
        if (s.delta) {
            delta++;
            continue;
        }
        atomicAdd(&probe_out[config * cells + sphere_cell(s.wi, header.z, header.w)], 1u);
        let f = lobe_eval(p, s.wi);
        let pdf = lobe_pdf(p, s.wi);
        if (!all_finite(vec4<f32>(f, pdf))) {
            non_finite++;
            continue;
        }
        var error = relative_error(pdf, s.pdf);
        if (pdf > 0.0) {
            let w = f / pdf;
            error = max(error, max(relative_error(w.x, s.weight.x), max(relative_error(w.y, s.weight.y), relative_error(w.z, s.weight.z))));
        }
        if (error > 1e-2) {
            inconsistent++;
        }
        max_error = max(max_error, error);
    }
    let stats = configs * cells + 8u * index;
    atomicStore(&probe_out[stats], valid);
    atomicStore(&probe_out[stats + 1u], delta);
    atomicStore(&probe_out[stats + 2u], non_finite);
    atomicStore(&probe_out[stats + 3u], bitcast<u32>(weight_sum.x));
    atomicStore(&probe_out[stats + 4u], bitcast<u32>(weight_sum.y));
    atomicStore(&probe_out[stats + 5u], bitcast<u32>(weight_sum.z));
    atomicStore(&probe_out[stats + 6u], inconsistent);
    atomicStore(&probe_out[stats + 7u], bitcast<u32>(max_error));
}
