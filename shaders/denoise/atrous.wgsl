// The edge-avoiding à-trous wavelet filter (Dammertz et al. 2010) with SVGF's luminance
// weight (Schied et al. 2017): one iteration per dispatch, taps `step` pixels apart on a
// 5×5 B3-spline footprint, `step` doubling from 1 to 16. It filters the illumination, the
// film divided by the albedo AOV (`src/render/denoise.rs` demodulates and remodulates), so
// texture detail never enters the filter. Edges stop it where the normal turns, the depth
// jumps, the albedo changes, or the luminance differs by more than its noise explains:
// a converged pixel (variance 0) keeps its value.
//
// Run on a band of rows at a time; taps outside the band are skipped, as outside the
// image, and the band carries enough rows beyond those it keeps that its kept rows are the
// same as for the whole image.

struct DenoiseParams {
    size: vec2<u32>,
    step: u32,
    _pad: u32,
    // Exponent of the normals' cosine, relative depth difference per pixel of distance,
    // albedo difference, and luminance difference in standard deviations.
    sigma_normal: f32,
    sigma_depth: f32,
    sigma_albedo: f32,
    sigma_luminance: f32,
};

@group(0) @binding(0) var<uniform> params: DenoiseParams;
// Per pixel: (albedo, depth), (normal, 0); a zero normal where the camera saw nothing.
@group(0) @binding(1) var<storage, read> guide: array<vec4<f32>>;
// Per pixel: (illumination, variance of its luminance's mean).
@group(0) @binding(2) var<storage, read> source: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> filtered: array<vec4<f32>>;

// The B3 spline's weights at offsets 0, ±1, ±2.
fn b3(k: i32) -> f32 {
    return select(select(0.0625, 0.25, abs(k) == 1), 0.375, k == 0);
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn pixel_index(p: vec2<i32>) -> u32 {
    return u32(p.y) * params.size.x + u32(p.x);
}

fn inside(p: vec2<i32>) -> bool {
    return all(p >= vec2<i32>(0)) && all(p < vec2<i32>(params.size));
}

// The variance of `p`'s luminance blurred over its 3×3 neighbours (SVGF's prefilter: a
// single pixel's variance estimate is too noisy to stop edges on).
fn blurred_variance(p: vec2<i32>) -> f32 {
    var sum = 0.0;
    var weight = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2<i32>(dx, dy);
            if (inside(q)) {
                let k = select(0.5, 1.0, dx == 0) * select(0.5, 1.0, dy == 0);
                sum += k * source[pixel_index(q)].w;
                weight += k;
            }
        }
    }
    return sum / weight;
}

@compute @workgroup_size(8, 8)
fn atrous(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.size.x || gid.y >= params.size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let i = pixel_index(p);
    let centre = source[i];
    let ga = guide[2u * i];
    let gn = guide[2u * i + 1u].xyz;
    let hit = dot(gn, gn) > 0.0;
    let l = luminance(centre.rgb);
    // Below this the luminance weight is a step: a pixel with no noise keeps its value.
    let spread = params.sigma_luminance * sqrt(max(blurred_variance(p), 0.0)) + 1.0e-10;
    var sum = vec4<f32>(0.0);
    var weights = 0.0;
    for (var dy = -2; dy <= 2; dy++) {
        for (var dx = -2; dx <= 2; dx++) {
            let q = p + vec2<i32>(dx, dy) * i32(params.step);
            if (!inside(q)) {
                continue;
            }
            let j = pixel_index(q);
            let c = source[j];
            let qa = guide[2u * j];
            let qn = guide[2u * j + 1u].xyz;
            var w = b3(dx) * b3(dy);
            if (hit != (dot(qn, qn) > 0.0)) {
                continue;
            }
            if (hit) {
                w *= pow(max(dot(gn, qn), 0.0), params.sigma_normal);
                let distance = length(vec2<f32>(vec2<i32>(dx, dy))) * f32(params.step);
                let depth_scale = params.sigma_depth * max(ga.w, 1.0e-4) * distance + 1.0e-6;
                w *= exp(-abs(ga.w - qa.w) / depth_scale);
                let da = ga.rgb - qa.rgb;
                w *= exp(-dot(da, da) / (params.sigma_albedo * params.sigma_albedo));
            }
            w *= exp(-abs(l - luminance(c.rgb)) / spread);
            // The filtered variance: weights squared (SVGF).
            sum += vec4<f32>(w * c.rgb, w * w * c.w);
            weights += w;
        }
    }
    // The centre tap's weight is b3(0)² > 0: never a division by zero.
    filtered[i] = vec4<f32>(sum.rgb / weights, sum.w / (weights * weights));
}
