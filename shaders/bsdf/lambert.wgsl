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

// Rough diffuse reflection: Fujii's improved Oren–Nayar model ("A tiny improvement of
// Oren-Nayar reflectance model", 2013), the base of OpenPBR's EON diffuse, with roughness
// sigma in [0, 1]; sigma = 0 is Lambert. Reciprocal, and its albedo never exceeds that
// of Lambert (it darkens toward retro-reflection's complement rather than compensating).
// Local frame, wo's hemisphere; returns f · |cos θi|.
fn rough_diffuse_eval(wo: vec3<f32>, wi: vec3<f32>, albedo: vec3<f32>, sigma: f32) -> vec3<f32> {
    if (wo.z * wi.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    let r = clamp(sigma, 0.0, 1.0);
    let ci = abs(wi.z);
    let co = abs(wo.z);
    let a = 1.0 / (1.0 + (0.5 * PI - 2.0 / 3.0) * r);
    let b = r * a;
    // s = cos(angle between wi and wo) - cos θi cos θo, the projected-azimuth term.
    let s = dot(wi.xy, wo.xy);
    let t = select(1.0, max(ci, co), s > 0.0);
    return albedo * (INV_PI * (a + b * s / t) * ci);
}

// The rough diffuse lobe made energy-preserving as OpenPBR's EON does (Portsmouth, Kutz &
// Hill 2025): what the single-scattering model loses, 1 - E(μ), returns through
//   f_ms = ρ_ms (1 - E(μo)) (1 - E(μi)) / (π (1 - E_avg)),  ρ_ms = ρ² E_avg / (1 - ρ (1 - E_avg)),
// so white reflects everything at any roughness. E(μ, sigma) and E_avg are tabulated
// (16 × 16) from `rough_diffuse_eval` by `cargo run --example albedo_tables`.
fn fon_albedo(mu: f32, sigma: f32) -> f32 {
    return table16_bilinear(&FON_ALBEDO, mu, sigma);
}

fn fon_albedo_average(sigma: f32) -> f32 {
    return table16_linear(&FON_ALBEDO_AVERAGE, sigma);
}

fn energy_preserving_diffuse_eval(wo: vec3<f32>, wi: vec3<f32>, albedo: vec3<f32>, sigma: f32) -> vec3<f32> {
    let single = rough_diffuse_eval(wo, wi, albedo, sigma);
    let e_avg = fon_albedo_average(sigma);
    if (sigma <= 0.0 || e_avg >= 1.0 || wo.z * wi.z <= 0.0) {
        return single;
    }
    let rho_ms = albedo * albedo * e_avg / (vec3<f32>(1.0) - albedo * (1.0 - e_avg));
    let f_ms = (1.0 - fon_albedo(abs(wo.z), sigma)) * (1.0 - fon_albedo(abs(wi.z), sigma)) / (PI * (1.0 - e_avg));
    return single + rho_ms * (f_ms * abs(wi.z));
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

// Lambertian transmission of albedo 1 (f · |cos θi| over the side opposite wo, local
// frame): the way into a subsurface random walk, and the diffuse transmission of a thin
// wall (a leaf, paper, a lampshade).
fn diffuse_transmission_eval(wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(diffuse_transmission_pdf(wo, wi));
}

fn diffuse_transmission_pdf(wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (wo.z * wi.z >= 0.0) {
        return 0.0;
    }
    return abs(wi.z) * INV_PI;
}

fn diffuse_transmission_sample(wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let d = sample_cosine_hemisphere(u);
    return vec3<f32>(d.x, d.y, select(d.z, -d.z, wo.z >= 0.0));
}
