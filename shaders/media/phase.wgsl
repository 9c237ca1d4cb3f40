// The Henyey–Greenstein phase function (Henyey & Greenstein 1941; pbrt-v4 §11.3.1): the
// angular distribution of light scattered inside a medium, one parameter g in (-1, 1) =
// the mean cosine of the scattering angle (0 isotropic, > 0 forward, < 0 backward).
// Directions are propagation directions: `d` the way light travelled before the event,
// the sampled one the way it travels after; cos θ = dot(d, wi).

// |g| is kept below this: at ±1 the function is a delta and its pdf infinite.
const HG_MAX_G: f32 = 0.999;
// Below this |g| the sampling formula loses precision and isotropic sampling is exact
// within rounding.
const HG_ISOTROPIC_G: f32 = 1e-3;

fn hg_clamp(g: f32) -> f32 {
    return clamp(g, -HG_MAX_G, HG_MAX_G);
}

// Density per steradian of scattering by angle θ (cos_theta = cos θ); integrates to 1
// over the sphere, so it is also the sampling pdf.
fn hg_phase(cos_theta: f32, g_in: f32) -> f32 {
    let g = hg_clamp(g_in);
    // 1 + g² - 2g cos θ, written so that it does not cancel near the peak of g → ±1.
    let denom = max((1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - clamp(cos_theta, -1.0, 1.0)), 1e-12);
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// A direction scattered from propagation direction `d` (unit), distributed as hg_phase;
// the weight phase / pdf is exactly 1.
fn hg_sample(d: vec3<f32>, g_in: f32, u: vec2<f32>) -> vec3<f32> {
    let g = hg_clamp(g_in);
    var cos_theta: f32;
    if (abs(g) < HG_ISOTROPIC_G) {
        cos_theta = 1.0 - 2.0 * u.x;
    } else {
        // Inverse of the cumulative distribution in cos θ.
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_theta = (1.0 + g * g - s * s) / (2.0 * g);
    }
    cos_theta = clamp(cos_theta, -1.0, 1.0);
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = 2.0 * PI * u.y;
    let f = frame_from_normal(d);
    return normalize(frame_to_world(f, vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta)));
}
