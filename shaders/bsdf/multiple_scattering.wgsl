// Multiple-scattering compensation for rough GGX metals (Kulla & Conty 2017, "Revisiting
// Physically Based Shading at Imageworks"): the energy a single-scattering microfacet lobe
// loses to light bouncing between microfacets, 1 - E(μ), is returned by a diffuse-like
// lobe
//   f_ms = F_ms (1 - E(μo)) (1 - E(μi)) / (π (1 - E_avg)),
// so a white metal reflects everything at any roughness. E(μ, roughness) and its cosine-
// weighted average E_avg are tabulated (16 × 16) from the shipped conductor lobe by
// `cargo run --example ggx_albedo_table`. Sampled cosine-weighted. Local frame, upper
// hemisphere.

const GGX_TABLE_SIZE: u32 = 16u;

// Bilinear lookup in a 16 × 16 table over [0, 1]² (rows y, columns x), and linear lookup
// in its 16-entry companion: shared by the GGX and rough-diffuse albedo tables.
fn table16_bilinear(table: ptr<private, array<f32, 256>>, x_in: f32, y_in: f32) -> f32 {
    let n = f32(GGX_TABLE_SIZE - 1u);
    let x = clamp(x_in, 0.0, 1.0) * n;
    let y = clamp(y_in, 0.0, 1.0) * n;
    let x0 = min(u32(x), GGX_TABLE_SIZE - 2u);
    let y0 = min(u32(y), GGX_TABLE_SIZE - 2u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let s = GGX_TABLE_SIZE;
    let row0 = mix((*table)[y0 * s + x0], (*table)[y0 * s + x0 + 1u], fx);
    let row1 = mix((*table)[(y0 + 1u) * s + x0], (*table)[(y0 + 1u) * s + x0 + 1u], fx);
    return clamp(mix(row0, row1, fy), 0.0, 1.0);
}

fn table16_linear(table: ptr<private, array<f32, 16>>, y_in: f32) -> f32 {
    let y = clamp(y_in, 0.0, 1.0) * f32(GGX_TABLE_SIZE - 1u);
    let y0 = min(u32(y), GGX_TABLE_SIZE - 2u);
    return clamp(mix((*table)[y0], (*table)[y0 + 1u], y - f32(y0)), 0.0, 1.0);
}

fn ggx_albedo(mu: f32, roughness: f32) -> f32 {
    return table16_bilinear(&GGX_ALBEDO, mu, roughness);
}

fn ggx_albedo_average(roughness: f32) -> f32 {
    return table16_linear(&GGX_ALBEDO_AVERAGE, roughness);
}

// The colour of the multiply-scattered light: Kulla–Conty's F_ms with the hemispherical
// average of Schlick's Fresnel, (20 f0 + 1) / 21.
fn conductor_ms_fresnel(f0: vec3<f32>, roughness: f32) -> vec3<f32> {
    let e_avg = ggx_albedo_average(roughness);
    let f_avg = clamp((20.0 * f0 + vec3<f32>(1.0)) / 21.0, vec3<f32>(0.0), vec3<f32>(1.0));
    return f_avg * f_avg * e_avg / (vec3<f32>(1.0) - f_avg * (1.0 - e_avg));
}

// Directional albedo of the compensation lobe: F_ms (1 - E(μo)).
fn conductor_ms_albedo(cos_o: f32, roughness: f32, f0: vec3<f32>) -> vec3<f32> {
    return conductor_ms_fresnel(f0, roughness) * (1.0 - ggx_albedo(cos_o, roughness));
}

fn conductor_ms_eval(wo: vec3<f32>, wi: vec3<f32>, roughness: f32, f0: vec3<f32>) -> vec3<f32> {
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3<f32>(0.0);
    }
    let e_avg = ggx_albedo_average(roughness);
    if (e_avg >= 1.0) {
        return vec3<f32>(0.0);
    }
    let f = (1.0 - ggx_albedo(wo.z, roughness)) * (1.0 - ggx_albedo(wi.z, roughness)) / (PI * (1.0 - e_avg));
    return conductor_ms_fresnel(f0, roughness) * (f * wi.z);
}
