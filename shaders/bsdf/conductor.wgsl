// Metal: GGX microfacet reflection with F82-tint Fresnel (OpenPBR's metal lobe). Local
// frame, z = normal; light and view both above the surface or nothing.
//
// Conventions of every lobe file: `*_eval` returns f·|cos θi|, `*_pdf` the solid-angle
// density of `*_sample`, and `*_sample` returns wi with weight = f·|cos θi| / pdf. Smooth
// lobes are deltas: their sample is flagged `delta`, `pdf` holds the discrete probability
// of having chosen it, and eval / pdf are 0 for every other direction.

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    delta: bool,
    valid: bool,
};

fn no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), 0.0, false, false);
}

fn conductor_eval(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>, f0: vec3<f32>, tint: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0 || ggx_is_smooth(alpha)) {
        return vec3<f32>(0.0);
    }
    let h = wo + wi;
    if (dot(h, h) == 0.0) {
        return vec3<f32>(0.0);
    }
    let m = normalize(h);
    let f = fresnel_f82(dot(wi, m), f0, tint);
    return f * (ggx_d(m, alpha) * ggx_g2(wo, wi, alpha) / (4.0 * wo.z));
}

fn conductor_pdf(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>) -> f32 {
    if (wo.z <= 0.0 || wi.z <= 0.0 || ggx_is_smooth(alpha)) {
        return 0.0;
    }
    let h = wo + wi;
    if (dot(h, h) == 0.0) {
        return 0.0;
    }
    let m = normalize(h);
    return ggx_vndf_pdf(wo, m, alpha) / (4.0 * dot(wo, m));
}

fn conductor_sample(wo: vec3<f32>, alpha: vec2<f32>, f0: vec3<f32>, tint: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (wo.z <= 0.0) {
        return no_sample();
    }
    if (ggx_is_smooth(alpha)) {
        let wi = vec3<f32>(-wo.x, -wo.y, wo.z);
        return BsdfSample(wi, fresnel_f82(wo.z, f0, tint), 1.0, true, true);
    }
    let m = ggx_sample_vndf(wo, alpha, u);
    let wi = reflect(-wo, m);
    if (wi.z <= 0.0) {
        return no_sample();
    }
    let pdf = ggx_vndf_pdf(wo, m, alpha) / (4.0 * dot(wo, m));
    // f cos / pdf simplifies to F G2 / G1(wo) for visible-normal sampling.
    let weight = fresnel_f82(dot(wi, m), f0, tint) * (ggx_g2(wo, wi, alpha) / ggx_g1(wo, alpha));
    return BsdfSample(wi, weight, pdf, false, pdf > 0.0);
}
