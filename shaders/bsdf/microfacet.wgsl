// The anisotropic GGX (Trowbridge–Reitz) microfacet distribution in the local shading
// frame (z = normal): height-correlated Smith masking (Heitz 2014, "Understanding the
// Masking-Shadowing Function") and visible-normal sampling (Heitz 2018, "Sampling the
// GGX Distribution of Visible Normals"). Directions below the surface are handled by the
// callers, which pass directions mirrored into the upper hemisphere where needed.

// Below this alpha a lobe is treated as perfectly smooth (a delta), as pbrt-v4 does: the
// distribution's peak would otherwise exceed what f32 sampling can resolve.
const ALPHA_SMOOTH: f32 = 1e-3;

// Perceptual roughness in [0, 1] to GGX alpha (Burley 2012), with anisotropy in [0, 1]
// stretching the lobe along the tangent (as Blender and OpenPBR do).
fn ggx_alpha(roughness: f32, anisotropy: f32) -> vec2<f32> {
    let r = clamp(roughness, 0.0, 1.0);
    let a = r * r;
    let aniso = clamp(anisotropy, 0.0, 1.0);
    let k = sqrt(1.0 - 0.9 * aniso);
    return vec2<f32>(max(a / k, 0.0), max(a * k, 0.0));
}

fn ggx_is_smooth(alpha: vec2<f32>) -> bool {
    return max(alpha.x, alpha.y) < ALPHA_SMOOTH;
}

fn ggx_d(m: vec3<f32>, alpha: vec2<f32>) -> f32 {
    if (m.z <= 0.0) {
        return 0.0;
    }
    let e = vec3<f32>(m.x / alpha.x, m.y / alpha.y, m.z);
    let d2 = dot(e, e);
    return 1.0 / (PI * alpha.x * alpha.y * d2 * d2);
}

// Smith Lambda, written as t / (sqrt(1 + t) + 1) so it stays accurate for small t.
fn ggx_lambda(w: vec3<f32>, alpha: vec2<f32>) -> f32 {
    let z2 = w.z * w.z;
    if (z2 == 0.0) {
        return 3.0e38;
    }
    let t = (alpha.x * alpha.x * w.x * w.x + alpha.y * alpha.y * w.y * w.y) / z2;
    return 0.5 * t / (sqrt(1.0 + t) + 1.0);
}

fn ggx_g1(w: vec3<f32>, alpha: vec2<f32>) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

fn ggx_g2(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

// Density of visible normals seen from w (either hemisphere): G1(w) |w·m| D(m) / |w.z|.
fn ggx_vndf_pdf(w: vec3<f32>, m: vec3<f32>, alpha: vec2<f32>) -> f32 {
    let cos_w = abs(w.z);
    if (cos_w == 0.0) {
        return 0.0;
    }
    return ggx_g1(w, alpha) * abs(dot(w, m)) * ggx_d(m, alpha) / cos_w;
}

// A visible normal for the direction w; w may be in either hemisphere (it is mirrored up).
fn ggx_sample_vndf(w: vec3<f32>, alpha: vec2<f32>, u: vec2<f32>) -> vec3<f32> {
    let wu = select(w, -w, w.z < 0.0);
    // Stretch to the isotropic unit-roughness configuration.
    let vh = normalize(vec3<f32>(alpha.x * wu.x, alpha.y * wu.y, wu.z));
    let len2 = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (len2 > 0.0) {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) * inverseSqrt(len2);
    }
    let t2 = cross(vh, t1);
    // Uniform disk, warped to the projected hemisphere visible from vh.
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    // Unstretch.
    return normalize(vec3<f32>(alpha.x * nh.x, alpha.y * nh.y, max(1e-7, nh.z)));
}
