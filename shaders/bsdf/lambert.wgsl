// Lambertian diffuse reflection, two-sided: `n` is the shading normal already turned to
// the side the light arrives from.

struct BsdfSample {
    wi: vec3<f32>,
    // f * |cos| / pdf
    weight: vec3<f32>,
    pdf: f32,
};

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
    return BsdfSample(wi, albedo, cosine_hemisphere_pdf(local.z));
}
