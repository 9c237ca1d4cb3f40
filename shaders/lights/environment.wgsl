// The environment: a uniform colour, or an equirectangular HDR map sampled in proportion
// to luminance × sin θ (the marginal/conditional CDF method, pbrt-v4 §A.5), with strength
// and rotation about +Y. Direction ↔ (u, v): v = θ / π from +Y down, u = φ / 2π + 1/2 with
// φ = atan2(x, −z) − rotation. Texels are piecewise constant, so lookup and pdf agree
// exactly.
//
// env_data: [0] = (width, height, strength, rotation in radians); then width × height
// texels (rgb radiance, w = the row's inclusive conditional CDF); then `height` entries
// whose x is the inclusive marginal CDF over rows.

fn has_environment_map() -> bool {
    return FEATURE_ENVIRONMENT_MAP && (params.flags & FLAG_ENVIRONMENT_MAP) != 0u;
}

fn environment_uv(d: vec3<f32>) -> vec2<f32> {
    let phi = atan2(d.x, -d.z) - env_data[0].w;
    let u = fract(phi / (2.0 * PI) + 0.5);
    let v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    return vec2<f32>(u, v);
}

fn environment_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = (uv.x - 0.5) * 2.0 * PI + env_data[0].w;
    let theta = uv.y * PI;
    let s = sin(theta);
    return vec3<f32>(s * sin(phi), cos(theta), -s * cos(phi));
}

fn environment_texel(uv: vec2<f32>) -> vec2<u32> {
    let size = vec2<u32>(env_data[0].xy);
    return min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
}

fn environment_radiance(dir: vec3<f32>) -> vec3<f32> {
    if (!has_environment_map()) {
        return params.environment.rgb;
    }
    let t = environment_texel(environment_uv(dir));
    let width = u32(env_data[0].x);
    return env_data[1u + t.y * width + t.x].rgb * env_data[0].z;
}

fn environment_marginal(y: u32) -> f32 {
    let size = vec2<u32>(env_data[0].xy);
    return env_data[1u + size.x * size.y + y].x;
}

fn environment_conditional(x: u32, y: u32) -> f32 {
    return env_data[1u + y * u32(env_data[0].x) + x].w;
}

// Probability of texel (x, y) under the map's discrete distribution.
fn environment_texel_probability(x: u32, y: u32) -> f32 {
    let row = environment_marginal(y) - select(0.0, environment_marginal(y - 1u), y > 0u);
    let column = environment_conditional(x, y) - select(0.0, environment_conditional(x - 1u, y), x > 0u);
    return row * column;
}

fn environment_pdf(dir: vec3<f32>) -> f32 {
    if (!has_environment_map()) {
        return INV_4PI;
    }
    let uv = environment_uv(dir);
    let sin_theta = sin(uv.y * PI);
    if (sin_theta <= 0.0) {
        return 0.0;
    }
    let t = environment_texel(uv);
    let texels = env_data[0].x * env_data[0].y;
    return environment_texel_probability(t.x, t.y) * texels / (2.0 * PI * PI * sin_theta);
}

// The first index in [0, count) whose inclusive CDF exceeds u, and u's position within it.
fn environment_search_rows(u: f32) -> u32 {
    var lo = 0u;
    var hi = u32(env_data[0].y) - 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (environment_marginal(mid) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn environment_search_columns(y: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = u32(env_data[0].x) - 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (environment_conditional(mid, y) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn sample_environment(u: vec2<f32>) -> LightSample {
    if (!has_environment_map()) {
        let wi = sample_uniform_sphere(u);
        return LightSample(wi, 3.0e38, environment_radiance(wi), INV_4PI, true);
    }
    let y = environment_search_rows(u.x);
    let x = environment_search_columns(y, u.y);
    // Reuse where u fell inside the chosen row and column as the position in the texel.
    let row_lo = select(0.0, environment_marginal(y - 1u), y > 0u);
    let row_hi = environment_marginal(y);
    let col_lo = select(0.0, environment_conditional(x - 1u, y), x > 0u);
    let col_hi = environment_conditional(x, y);
    // Strictly inside the texel, so sin θ > 0 even in the top row.
    let fy = clamp((u.x - row_lo) / max(row_hi - row_lo, 1e-30), 1e-4, 1.0 - 1e-4);
    let fx = clamp((u.y - col_lo) / max(col_hi - col_lo, 1e-30), 0.0, 1.0 - 1e-4);
    let size = env_data[0].xy;
    let uv = (vec2<f32>(f32(x), f32(y)) + vec2<f32>(fx, fy)) / size;
    let wi = environment_direction(uv);
    // Density and radiance of the chosen texel itself: the direction's round trip to
    // (u, v) is only as exact as the GPU's sin and cos (Vulkan allows 2^-11), which near a
    // texel edge can land in the neighbour.
    let sin_theta = sin(uv.y * PI);
    let pdf = environment_texel_probability(x, y) * size.x * size.y / (2.0 * PI * PI * sin_theta);
    if (!(pdf > 0.0)) {
        return LightSample(wi, 3.0e38, vec3<f32>(0.0), 0.0, true);
    }
    let radiance = env_data[1u + y * u32(size.x) + x].rgb * env_data[0].z;
    return LightSample(wi, 3.0e38, radiance, pdf, true);
}
