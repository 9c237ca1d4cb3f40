// The editor viewport's display pass: the film's mean radiance (its fixed-point sum over
// the sample count) → exposure → view transform → sRGB, written to an
// rgba8unorm texture that egui draws as it is (egui expects gamma-encoded textures).
// The view transforms are those of src/film/tonemap.rs, so the viewport shows what
// `kiln render` writes.

struct DisplayParams {
    size: vec2<u32>,
    // 2^exposure in stops.
    exposure_scale: f32,
    // Tonemap::gpu_id: 0 clip ("Standard"), 1 AgX, 2 ACES, 3 Khronos PBR Neutral.
    tonemap: u32,
}

@group(0) @binding(0) var<storage, read> film_sum: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> film_high: array<vec4<u32>>;
@group(0) @binding(2) var output: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var<uniform> display: DisplayParams;

fn agx(c: vec3<f32>) -> vec3<f32> {
    let min_ev = -12.47393;
    let max_ev = 4.026069;
    let inset = mat3x3<f32>(
        vec3<f32>(0.84247906, 0.042328242, 0.042375655),
        vec3<f32>(0.0784336, 0.8784686, 0.0784336),
        vec3<f32>(0.079223745, 0.07916613, 0.879143),
    );
    let outset = mat3x3<f32>(
        vec3<f32>(1.196879, -0.05289685, -0.052971635),
        vec3<f32>(-0.09802088, 1.1519031, -0.09804345),
        vec3<f32>(-0.09902974, -0.09896118, 1.1510737),
    );
    let v = log2(max(inset * c, vec3<f32>(1e-10)));
    let x = clamp((v - vec3<f32>(min_ev)) / (max_ev - min_ev), vec3<f32>(0.0), vec3<f32>(1.0));
    let x2 = x * x;
    let x4 = x2 * x2;
    let curve = 15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2
        + 0.1191 * x - vec3<f32>(0.00232);
    let shown = clamp(outset * curve, vec3<f32>(0.0), vec3<f32>(1.0));
    return pow(shown, vec3<f32>(2.2));
}

fn aces(c: vec3<f32>) -> vec3<f32> {
    let input = mat3x3<f32>(
        vec3<f32>(0.59719, 0.07600, 0.02840),
        vec3<f32>(0.35458, 0.90834, 0.13383),
        vec3<f32>(0.04823, 0.01566, 0.83777),
    );
    let output = mat3x3<f32>(
        vec3<f32>(1.60475, -0.10208, -0.00327),
        vec3<f32>(-0.53108, 1.10813, -0.07276),
        vec3<f32>(-0.07367, -0.00605, 1.07602),
    );
    let v = input * c;
    let fit = (v * (v + vec3<f32>(0.0245786)) - vec3<f32>(0.000090537))
        / (v * (0.983729 * v + vec3<f32>(0.432951)) + vec3<f32>(0.238081));
    return clamp(output * fit, vec3<f32>(0.0), vec3<f32>(1.0));
}

fn pbr_neutral(color: vec3<f32>) -> vec3<f32> {
    let start_compression = 0.8 - 0.04;
    let desaturation = 0.15;
    let x = min(color.r, min(color.g, color.b));
    var offset = 0.04;
    if (x < 0.08) {
        offset = x - 6.25 * x * x;
    }
    let c = color - vec3<f32>(offset);
    let peak = max(c.r, max(c.g, c.b));
    if (peak < start_compression) {
        return c;
    }
    let d = 1.0 - start_compression;
    let new_peak = 1.0 - d * d / (peak + d - start_compression);
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(c * (new_peak / peak), vec3<f32>(new_peak), g);
}

fn srgb_encode(v: vec3<f32>) -> vec3<f32> {
    let c = clamp(v, vec3<f32>(0.0), vec3<f32>(1.0));
    let low = 12.92 * c;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - vec3<f32>(0.055);
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8)
fn display_film(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= display.size.x || gid.y >= display.size.y) {
        return;
    }
    let pixel = gid.y * display.size.x + gid.x;
    // The film's 64-bit fixed-point sums (`crate::film::ExactFilm`): low words and the
    // count in film_sum, high words in film_high.
    let low = film_sum[pixel];
    let high = film_high[pixel];
    var radiance = vec3<f32>(0.0);
    if (low.w > 0u) {
        let sum = (vec3<f32>(bitcast<vec3<i32>>(high.xyz)) * 4294967296.0 + vec3<f32>(low.xyz))
            / 268435456.0;
        radiance = max(sum / f32(low.w), vec3<f32>(0.0)) * display.exposure_scale;
    }
    var shown = clamp(radiance, vec3<f32>(0.0), vec3<f32>(1.0));
    switch display.tonemap {
        case 1u: { shown = agx(radiance); }
        case 2u: { shown = aces(radiance); }
        case 3u: { shown = pbr_neutral(radiance); }
        default: {}
    }
    textureStore(output, vec2<i32>(gid.xy), vec4<f32>(srgb_encode(shown), 1.0));
}
