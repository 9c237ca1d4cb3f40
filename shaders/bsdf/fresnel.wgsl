// Fresnel reflectance: exact for dielectrics, and the F82-tint model for metals
// (Hoffman 2023, "Generalization of Adobe's Fresnel Model", as used by OpenPBR).

// Unpolarised reflectance of a dielectric interface; `cos_i` may be negative (light from
// inside), `eta` is the relative IOR inside / outside. Returns 1 under total internal
// reflection.
fn fresnel_dielectric(cos_i_in: f32, eta_in: f32) -> f32 {
    var cos_i = clamp(cos_i_in, -1.0, 1.0);
    var eta = eta_in;
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    let cos_t = sqrt(max(0.0, 1.0 - sin2_t));
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

fn schlick_weight(cos_i: f32) -> f32 {
    let m = clamp(1.0 - cos_i, 0.0, 1.0);
    let m2 = m * m;
    return m2 * m2 * m;
}

// F82-tint: Schlick's curve from `f0`, pulled down near grazing so that at cos = 1/7
// (82°) the reflectance is `tint` times Schlick's there.
fn fresnel_f82(cos_i: f32, f0: vec3<f32>, tint: vec3<f32>) -> vec3<f32> {
    let mu = clamp(cos_i, 0.0, 1.0);
    let mu_bar = 1.0 / 7.0;
    let one_minus_bar = 1.0 - mu_bar;
    let f_bar = f0 + (vec3<f32>(1.0) - f0) * schlick_weight(mu_bar);
    let b = mu_bar * pow(one_minus_bar, 6.0);
    let a = f_bar * (vec3<f32>(1.0) - tint) / b;
    let f = f0 + (vec3<f32>(1.0) - f0) * schlick_weight(mu) - a * mu * pow(1.0 - mu, 6.0);
    return clamp(f, vec3<f32>(0.0), vec3<f32>(1.0));
}

// Refraction of w about n (both pointing the same side or not): returns false under total
// internal reflection. `eta` is inside / outside relative to n's side being outside.
struct Refraction {
    ok: bool,
    wt: vec3<f32>,
    // The relative IOR the ray crossed (eta or 1 / eta).
    etap: f32,
};

fn refract_dir(w: vec3<f32>, n_in: vec3<f32>, eta_in: f32) -> Refraction {
    var n = n_in;
    var eta = eta_in;
    var cos_i = dot(n, w);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = max(0.0, 1.0 - cos_i * cos_i);
    let sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0) {
        return Refraction(false, vec3<f32>(0.0), eta);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return Refraction(true, -w / eta + (cos_i / eta - cos_t) * n, eta);
}
