// Lambertian diffuse reflection, two-sided: `n` is the shading normal already turned to
// the side the light arrives from.

fn lambert_eval(albedo: vec3<f32>, n: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (dot(n, wi) <= 0.0) {
        return vec3<f32>(0.0);
    }
    return albedo * INV_PI;
}

fn lambert_pdf(n: vec3<f32>, wi: vec3<f32>) -> f32 {
    return cosine_hemisphere_pdf(dot(n, wi));
}

fn lambert_sample(albedo: vec3<f32>, n: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let local = sample_cosine_hemisphere(u);
    let wi = normalize(frame_to_world(frame_from_normal(n), local));
    return BsdfSample(wi, albedo, cosine_hemisphere_pdf(local.z), false, true);
}

// The same lobe in the local frame (z = normal) with the lobe conventions of
// `bsdf/conductor.wgsl`: reflection on the side of wo only.
fn diffuse_eval(wo: vec3<f32>, wi: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    if (wo.z * wi.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    return albedo * (INV_PI * abs(wi.z));
}

fn diffuse_pdf(wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z * wi.z <= 0.0) {
        return 0.0;
    }
    return abs(wi.z) * INV_PI;
}

fn diffuse_sample(wo: vec3<f32>, albedo: vec3<f32>, u: vec2<f32>) -> DiffuseSample {
    var wi = sample_cosine_hemisphere(u);
    if (wo.z < 0.0) {
        wi.z = -wi.z;
    }
    return DiffuseSample(wi, albedo, abs(wi.z) * INV_PI);
}

struct DiffuseSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
};
