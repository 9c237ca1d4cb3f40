// Warps from the unit square to the domains the integrator samples, with their pdfs.

// Malley's method: a concentric disk sample projected up (pbrt-v4 SampleCosineHemisphere).
fn sample_concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - vec2<f32>(1.0);
    if (o.x == 0.0 && o.y == 0.0) {
        return vec2<f32>(0.0);
    }
    var r: f32;
    var theta: f32;
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        theta = (PI / 4.0) * (o.y / o.x);
    } else {
        r = o.y;
        theta = (PI / 2.0) - (PI / 4.0) * (o.x / o.y);
    }
    return r * vec2<f32>(cos(theta), sin(theta));
}

// Local frame: z is the normal.
fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let d = sample_concentric_disk(u);
    let z = sqrt(max(0.0, 1.0 - dot(d, d)));
    return vec3<f32>(d.x, d.y, z);
}

fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    return max(cos_theta, 0.0) * INV_PI;
}

fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// Barycentrics (b1, b2) uniform over a triangle (Heitz 2019, "A Low-Distortion Map
// Between Triangle and Square"), which keeps stratification better than the sqrt map.
fn sample_uniform_triangle(u: vec2<f32>) -> vec2<f32> {
    var b0: f32;
    var b1: f32;
    if (u.x < u.y) {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    return vec2<f32>(b1, 1.0 - b0 - b1);
}

// Offset in pixels from a pixel's centre drawn from the pixel filter (filter importance
// sampling, so every sample weighs 1): x and y each from the filter's quantile function,
// tabulated in Params.filter_quantiles at the probabilities (1 - cos(π t)) / 2 of
// FILTER_TABLE_SIZE evenly spaced t (dense in the tails) and interpolated linearly in t
// (src/shader/sampling.rs).
fn filter_offset(u: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(filter_quantile(u.x), filter_quantile(u.y));
}

fn filter_quantile(u: f32) -> f32 {
    let t = acos(clamp(1.0 - 2.0 * u, -1.0, 1.0)) * INV_PI;
    let x = t * f32(FILTER_TABLE_SIZE - 1u);
    let i = min(u32(x), FILTER_TABLE_SIZE - 2u);
    let a = params.filter_quantiles[i / 4u][i % 4u];
    let b = params.filter_quantiles[(i + 1u) / 4u][(i + 1u) % 4u];
    return mix(a, b, x - f32(i));
}

fn power_heuristic(pdf_f: f32, pdf_g: f32) -> f32 {
    let f = pdf_f * pdf_f;
    let g = pdf_g * pdf_g;
    if (f + g == 0.0) {
        return 0.0;
    }
    // Guards the ratio when a pdf is so large that its square overflows.
    if (f > 3.0e38) {
        return 1.0;
    }
    return f / (f + g);
}

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
struct Frame {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
};

fn frame_from_normal(n: vec3<f32>) -> Frame {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return Frame(t, bt, n);
}

// The frame around unit `n` whose tangent is `t` (made orthogonal to n) turned by `turns`
// of a full turn about n; an arbitrary tangent where t is zero or parallel to n.
fn frame_from_normal_tangent(n: vec3<f32>, t_in: vec3<f32>, turns: f32) -> Frame {
    var t = t_in - n * dot(n, t_in);
    let len2 = dot(t, t);
    if (len2 > 1e-12 * max(dot(t_in, t_in), 1e-30)) {
        t = t * inverseSqrt(len2);
    } else {
        t = frame_from_normal(n).t;
    }
    let angle = 2.0 * PI * turns;
    t = cos(angle) * t + sin(angle) * cross(n, t);
    return Frame(t, cross(n, t), n);
}

fn frame_to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return v.x * f.t + v.y * f.b + v.z * f.n;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}
