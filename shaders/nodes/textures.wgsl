// Node library: procedural textures, 3D only. Mirrors Blender's Checker, Gradient, Noise
// (fBM, normalized), White Noise, Voronoi (F1, F2, smooth F1; one octave), Wave and Brick
// texture nodes as Cycles evaluates them (intern/cycles/kernel/svm/checker.h,
// gradient.h, noise.h, fractal_noise.h, noisetex.h, white_noise.h, voronoi.h, wave.h,
// brick.h). `p` is the texture coordinate; every function is a pure function of its
// arguments. Uses hash.wgsl and math.wgsl. Not here: 1D/2D/4D variants, the other
// fractal types, Voronoi's detail octaves, distance-to-edge and n-sphere radius.

struct NodeTexOut {
    color: vec3<f32>,
    fac: f32,
}

// ---- Checker ----

// fac is 1 in color1's cells. The nudge keeps integer coordinates (a unit cube's faces)
// off the cell boundary, as in Cycles.
fn node_checker(p: vec3<f32>, color1: vec3<f32>, color2: vec3<f32>, scale: f32) -> NodeTexOut {
    let q = (p * scale + 0.000001) * 0.999999;
    // Parity of floor(q); Cycles takes abs() first, which does not change a parity.
    let parity = bitcast<vec3<u32>>(vec3<i32>(floor(q))) & vec3<u32>(1u);
    let in_color1 = (parity.x == parity.y) == (parity.z == 1u);
    if (in_color1) {
        return NodeTexOut(color1, 1.0);
    }
    return NodeTexOut(color2, 0.0);
}

// ---- Gradient ----

// Kinds: 0 linear, 1 quadratic, 2 easing, 3 diagonal, 4 radial, 5 quadratic_sphere,
// 6 spherical. fac is clamped to [0, 1]; color = vec3(fac).
fn node_gradient(p: vec3<f32>, kind: u32) -> NodeTexOut {
    var f = 0.0;
    switch kind {
        case 0u: { f = p.x; }
        case 1u: {
            let r = max(p.x, 0.0);
            f = r * r;
        }
        case 2u: {
            let r = clamp(p.x, 0.0, 1.0);
            let t = r * r;
            f = 3.0 * t - 2.0 * t * r;
        }
        case 3u: { f = (p.x + p.y) * 0.5; }
        case 4u: {
            let angle = select(atan2(p.y, p.x), 0.0, p.x == 0.0 && p.y == 0.0);
            f = angle / (2.0 * PI) + 0.5;
        }
        // The 0.999999 makes a unit vector give exactly 0, as in Cycles.
        case 5u: {
            let r = max(0.999999 - length(p), 0.0);
            f = r * r;
        }
        case 6u: { f = max(0.999999 - length(p), 0.0); }
        default: {}
    }
    f = clamp(f, 0.0, 1.0);
    return NodeTexOut(vec3<f32>(f), f);
}

// ---- Perlin noise (Cycles' noise.h, after OSL) ----

fn nd_fade(t: f32) -> f32 {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// One of 12 edge gradients (with 4 repeated) picked by the low four bits.
fn nd_grad3(hash: u32, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15u;
    let u = select(y, x, h < 8u);
    let vt = select(z, x, h == 12u || h == 14u);
    let v = select(vt, y, h < 4u);
    return select(u, -u, (h & 1u) != 0u) + select(v, -v, (h & 2u) != 0u);
}

fn nd_perlin3(p: vec3<f32>) -> f32 {
    let cell = floor(p);
    // The lattice is hashed as unsigned ints; X + 1 wraps exactly like Cycles' int X + 1.
    let i = bitcast<vec3<u32>>(vec3<i32>(cell));
    let j = i + vec3<u32>(1u);
    let f = p - cell;
    let g = f - vec3<f32>(1.0);
    let w = vec3<f32>(nd_fade(f.x), nd_fade(f.y), nd_fade(f.z));
    let v000 = nd_grad3(nd_hash_uint3(i.x, i.y, i.z), f.x, f.y, f.z);
    let v100 = nd_grad3(nd_hash_uint3(j.x, i.y, i.z), g.x, f.y, f.z);
    let v010 = nd_grad3(nd_hash_uint3(i.x, j.y, i.z), f.x, g.y, f.z);
    let v110 = nd_grad3(nd_hash_uint3(j.x, j.y, i.z), g.x, g.y, f.z);
    let v001 = nd_grad3(nd_hash_uint3(i.x, i.y, j.z), f.x, f.y, g.z);
    let v101 = nd_grad3(nd_hash_uint3(j.x, i.y, j.z), g.x, f.y, g.z);
    let v011 = nd_grad3(nd_hash_uint3(i.x, j.y, j.z), f.x, g.y, g.z);
    let v111 = nd_grad3(nd_hash_uint3(j.x, j.y, j.z), g.x, g.y, g.z);
    // Cycles' tri_mix, term for term.
    let x1 = 1.0 - w.x;
    let y1 = 1.0 - w.y;
    let z1 = 1.0 - w.z;
    return z1 * (y1 * (v000 * x1 + v100 * w.x) + w.y * (v010 * x1 + v110 * w.x))
        + w.z * (y1 * (v001 * x1 + v101 * w.x) + w.y * (v011 * x1 + v111 * w.x));
}

// Signed noise, about [-1, 1] (0.982 is OSL's experimentally found scale). Coordinates
// repeat every 100000 to keep float precision, with Cycles' half-cell shift beyond 1e6.
fn nd_snoise3(p: vec3<f32>) -> f32 {
    let shift = select(vec3<f32>(0.0), vec3<f32>(0.5), abs(p) >= vec3<f32>(1000000.0));
    return 0.9820 * nd_perlin3(p % vec3<f32>(100000.0) + shift);
}

// Normalized fractal Brownian motion, Blender 4.x's noise_fbm(normalize = true): octave
// i has frequency lacunarity^i and amplitude roughness^i, the sum is divided by the total
// amplitude and mapped to about [0, 1]; a fractional detail blends in one more octave.
// `detail` must already be in [0, 15].
fn nd_noise_fbm(p: vec3<f32>, detail: f32, roughness: f32, lacunarity: f32) -> f32 {
    var fscale = 1.0;
    var amp = 1.0;
    var maxamp = 0.0;
    var sum = 0.0;
    let octaves = i32(detail);
    for (var i = 0; i < 16; i++) {
        if (i > octaves) {
            break;
        }
        sum += nd_snoise3(fscale * p) * amp;
        maxamp += amp;
        amp *= roughness;
        fscale *= lacunarity;
    }
    let value = 0.5 * sum / maxamp + 0.5;
    let rmd = detail - floor(detail);
    if (rmd != 0.0) {
        let sum2 = sum + nd_snoise3(fscale * p) * amp;
        let value2 = 0.5 * sum2 / (maxamp + amp) + 0.5;
        return value + rmd * (value2 - value);
    }
    return value;
}

// Cycles' random_float3_offset: a per-seed shift in [100, 200)^3 that decorrelates the
// noise channels and the distortion field.
fn nd_noise_offset(seed: f32) -> vec3<f32> {
    return vec3<f32>(100.0) + 100.0 * vec3<f32>(
        nd_hash_vec2_to_float(vec2<f32>(seed, 0.0)),
        nd_hash_vec2_to_float(vec2<f32>(seed, 1.0)),
        nd_hash_vec2_to_float(vec2<f32>(seed, 2.0)),
    );
}

// ---- Noise ----

// Noise Texture, 3D, fBM, normalize on. detail is clamped to [0, 15] and roughness to
// >= 0 as in Cycles. fac = color.r; color.gb are the same fBm at offsets 3 and 4.
// Range: Blender's values lie in about [0, 1] but can overshoot it by ~1e-2 (Perlin's
// extremes); here fac and color are clamped to [0, 1].
fn node_noise(
    p: vec3<f32>,
    scale: f32,
    detail: f32,
    roughness: f32,
    lacunarity: f32,
    distortion: f32,
) -> NodeTexOut {
    let d = clamp(detail, 0.0, 15.0);
    let r = max(roughness, 0.0);
    var q = p * scale;
    if (distortion != 0.0) {
        q += distortion * vec3<f32>(
            nd_snoise3(q + nd_noise_offset(0.0)),
            nd_snoise3(q + nd_noise_offset(1.0)),
            nd_snoise3(q + nd_noise_offset(2.0)),
        );
    }
    let value = nd_noise_fbm(q, d, r, lacunarity);
    let color = vec3<f32>(
        value,
        nd_noise_fbm(q + nd_noise_offset(3.0), d, r, lacunarity),
        nd_noise_fbm(q + nd_noise_offset(4.0), d, r, lacunarity),
    );
    let c = clamp(color, vec3<f32>(0.0), vec3<f32>(1.0));
    return NodeTexOut(c, c.x);
}

// ---- White Noise ----

// White Noise Texture, 3D: hashes of p's bit patterns, each in [0, 1).
fn node_white_noise(p: vec3<f32>) -> NodeTexOut {
    return NodeTexOut(nd_hash_vec3_to_vec3(p), nd_hash_vec3_to_float(p));
}

// ---- Voronoi ----

struct NodeVoronoiOut {
    distance: f32,
    color: vec3<f32>,
    position: vec3<f32>,
}

// x^e for x >= 0 without WGSL's pow(0, e), which is undefined.
fn nd_pow_nonneg(x: vec3<f32>, e: f32) -> vec3<f32> {
    return select(vec3<f32>(0.0), pow(x, vec3<f32>(e)), x > vec3<f32>(0.0));
}

// Metrics: 0 euclidean, 1 manhattan, 2 chebyshev, 3 minkowski with `exponent`.
fn nd_voronoi_distance(d: vec3<f32>, metric: u32, exponent: f32) -> f32 {
    let a = abs(d);
    switch metric {
        case 1u: { return a.x + a.y + a.z; }
        case 2u: { return max(a.x, max(a.y, a.z)); }
        case 3u: {
            let s = dot(nd_pow_nonneg(a, exponent), vec3<f32>(1.0));
            return select(0.0, pow(s, 1.0 / exponent), s > 0.0);
        }
        default: { return length(d); }
    }
}

// Voronoi Texture, 3D, one octave. Features: 0 F1, 1 F2, 2 smooth F1. Metrics as
// nd_voronoi_distance. Cell c (integer, in the scaled space p · scale) holds the feature
// point c + nd_hash_vec3_to_vec3(c) · randomness. F1 and F2 search the 3×3×3 cells around
// p's cell, smooth F1 the 5×5×5, as Blender does. Like Blender's, the small window now
// and then misses a nearer point two cells away; at randomness 1, F1 never did in 1e5
// samples for euclidean and chebyshev and did for ~4e-4 of them for manhattan; F2 for
// 2e-5 (euclidean) and 4e-3 (manhattan) of them (tests/node_library_wgsl.rs).
// randomness is clamped to [0, 1]; smoothness is halved and clamped to [0, 0.5] as in
// Cycles, and smoothness 0 is F1 (the limit; Cycles divides by it). The Minkowski
// exponent is kept >= 0.05 (Blender allows 0, where the distance overflows).
// Outputs: distance in the scaled space; color = hash of the chosen cell (F1/F2, in
// [0, 1)) or the smooth blend of the cells' colours; position = the chosen feature point
// divided by scale (input space; 0 when scale is 0).
// Ranges (distance): F1 in [0, sqrt(3)] euclidean, [0, 3] manhattan, [0, 1] chebyshev;
// F2 in [0, sqrt(6)], [0, 4], [0, 2]; smooth F1 <= F1 and may dip slightly below 0
// where two feature points nearly coincide.
fn node_voronoi(
    p: vec3<f32>,
    scale: f32,
    smoothness: f32,
    exponent: f32,
    randomness: f32,
    feature: u32,
    metric: u32,
) -> NodeVoronoiOut {
    let rnd = clamp(randomness, 0.0, 1.0);
    let smooth_k = clamp(smoothness * 0.5, 0.0, 0.5);
    let e = max(exponent, 0.05);
    let coord = p * scale;
    let cell = floor(coord);
    let local = coord - cell;

    if (feature == 2u && smooth_k > 0.0) {
        // Inigo Quilez's smooth minimum folded over the 125 cells, in Cycles' loop order.
        var sd = 0.0;
        var scol = vec3<f32>(0.0);
        var spos = vec3<f32>(0.0);
        var is_first = true;
        for (var k = -2; k <= 2; k++) {
            for (var j = -2; j <= 2; j++) {
                for (var i = -2; i <= 2; i++) {
                    let offset = vec3<f32>(f32(i), f32(j), f32(k));
                    let h3 = nd_hash_vec3_to_vec3(cell + offset);
                    let pt = offset + h3 * rnd;
                    let dist = nd_voronoi_distance(pt - local, metric, e);
                    var h = 1.0;
                    if (!is_first) {
                        h = nd_smoothstep(0.0, 1.0, 0.5 + 0.5 * (sd - dist) / smooth_k);
                    }
                    is_first = false;
                    var correction = smooth_k * h * (1.0 - h);
                    sd = sd + h * (dist - sd) - correction;
                    correction /= 1.0 + 3.0 * smooth_k;
                    scol = scol + h * (h3 - scol) - vec3<f32>(correction);
                    spos = spos + h * (pt - spos) - vec3<f32>(correction);
                }
            }
        }
        return NodeVoronoiOut(sd, scol, nd_safe_divide3(cell + spos, vec3<f32>(scale)));
    }

    // F1 and F2 (smooth F1 with smoothness 0 lands here as F1). Strict < keeps the first
    // of equal candidates, as in Cycles.
    var d1 = 3.4e38;
    var d2 = 3.4e38;
    var o1 = vec3<f32>(0.0);
    var o2 = vec3<f32>(0.0);
    var p1 = vec3<f32>(0.0);
    var p2 = vec3<f32>(0.0);
    for (var k = -1; k <= 1; k++) {
        for (var j = -1; j <= 1; j++) {
            for (var i = -1; i <= 1; i++) {
                let offset = vec3<f32>(f32(i), f32(j), f32(k));
                let pt = offset + nd_hash_vec3_to_vec3(cell + offset) * rnd;
                let dist = nd_voronoi_distance(pt - local, metric, e);
                if (dist < d1) {
                    d2 = d1;
                    o2 = o1;
                    p2 = p1;
                    d1 = dist;
                    o1 = offset;
                    p1 = pt;
                } else if (dist < d2) {
                    d2 = dist;
                    o2 = offset;
                    p2 = pt;
                }
            }
        }
    }
    let s = vec3<f32>(scale);
    if (feature == 1u) {
        return NodeVoronoiOut(d2, nd_hash_vec3_to_vec3(cell + o2), nd_safe_divide3(cell + p2, s));
    }
    return NodeVoronoiOut(d1, nd_hash_vec3_to_vec3(cell + o1), nd_safe_divide3(cell + p1, s));
}

// ---- Wave ----

// Wave Texture. kind: 0 bands, 1 rings. direction for bands: 0 x, 1 y, 2 z, 3 diagonal;
// for rings: 0 x, 1 y, 2 z, 3 spherical. profile: 0 sine, 1 saw, 2 triangle. The
// distortion is Blender's: distortion · (2 · fBm(p · detail_scale) - 1) added to the
// phase, with the Noise texture's normalized fBm at lacunarity 2 (detail clamped to
// [0, 15], roughness to >= 0). Range: fac in [0, 1] for every profile (saw reaches 1
// only by rounding); color = vec3(fac).
fn node_wave(
    p: vec3<f32>,
    scale: f32,
    distortion: f32,
    detail: f32,
    detail_scale: f32,
    detail_roughness: f32,
    phase: f32,
    kind: u32,
    direction: u32,
    profile: u32,
) -> NodeTexOut {
    // Keeps unit coordinates off the band edges, as in Cycles.
    let q = (p * scale + 0.000001) * 0.999999;
    var n = 0.0;
    if (kind == 0u) {
        switch direction {
            case 0u: { n = q.x * 20.0; }
            case 1u: { n = q.y * 20.0; }
            case 2u: { n = q.z * 20.0; }
            default: { n = (q.x + q.y + q.z) * 10.0; }
        }
    } else {
        var mask = vec3<f32>(1.0);
        switch direction {
            case 0u: { mask = vec3<f32>(0.0, 1.0, 1.0); }
            case 1u: { mask = vec3<f32>(1.0, 0.0, 1.0); }
            case 2u: { mask = vec3<f32>(1.0, 1.0, 0.0); }
            default: {}
        }
        n = length(q * mask) * 20.0;
    }
    n += phase;
    if (distortion != 0.0) {
        let octaves = clamp(detail, 0.0, 15.0);
        let fbm = nd_noise_fbm(q * detail_scale, octaves, max(detail_roughness, 0.0), 2.0);
        n += distortion * (fbm * 2.0 - 1.0);
    }
    var f = 0.0;
    switch profile {
        case 1u: {
            let t = n / (2.0 * PI);
            f = t - floor(t);
        }
        case 2u: {
            let t = n / (2.0 * PI);
            f = abs(t - floor(t + 0.5)) * 2.0;
        }
        default: {
            // 0.5 + 0.5 sin(n - π/2), with the argument reduced to [0, 2π) first: WGSL
            // promises sin's accuracy only on [-π, π], and n grows with the coordinate.
            let t = (n - 0.5 * PI) / (2.0 * PI);
            f = 0.5 + 0.5 * sin((t - floor(t)) * (2.0 * PI));
        }
    }
    f = clamp(f, 0.0, 1.0);
    return NodeTexOut(vec3<f32>(f), f);
}

// ---- Brick ----

// Cycles' brick_noise: a fast integer hash to [0, 1) that tints each brick.
fn nd_brick_noise(seed: u32) -> f32 {
    var n = (seed + 1013u) & 0x7fffffffu;
    n = (n >> 13u) ^ n;
    let nn = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
    return 0.5 * (f32(nn) / 1073741824.0);
}

// Brick Texture. Rows are row_height tall; a row whose index is a multiple of
// offset_frequency is shifted by offset · brick_width and one whose index is a multiple
// of squash_frequency has its bricks squash times as wide; as in Blender, neither happens
// unless both frequencies are non-zero. The frequencies are integers passed as f32
// (rounded). fac is the mortar factor (1 in the mortar, 0 inside a brick, smooth in
// between); color is the brick colour (color1 → color2 by a per-brick tint + bias) under
// the mortar colour. brick_width and row_height are kept >= 1e-6 (Blender's UI stops at
// 0.01) so that a zero never divides.
fn node_brick(
    p: vec3<f32>,
    color1: vec3<f32>,
    color2: vec3<f32>,
    mortar: vec3<f32>,
    scale: f32,
    mortar_size: f32,
    mortar_smooth: f32,
    bias: f32,
    brick_width: f32,
    row_height: f32,
    offset: f32,
    offset_frequency: f32,
    squash: f32,
    squash_frequency: f32,
) -> NodeTexOut {
    let q = p * scale;
    let rh = max(row_height, 1e-6);
    var bw = brick_width;
    var shift = 0.0;
    let row = i32(floor(q.y / rh));
    let off_freq = i32(round(offset_frequency));
    let squash_freq = i32(round(squash_frequency));
    if (off_freq != 0 && squash_freq != 0) {
        if (row % squash_freq == 0) {
            bw *= squash;
        }
        if (row % off_freq == 0) {
            shift = bw * offset;
        }
    }
    bw = max(bw, 1e-6);
    let brick = i32(floor((q.x + shift) / bw));
    let x = (q.x + shift) - bw * f32(brick);
    let y = q.y - rh * f32(row);

    let seed = (bitcast<u32>(row) << 16u) + (bitcast<u32>(brick) & 0xffffu);
    let tint = clamp(nd_brick_noise(seed) + bias, 0.0, 1.0);
    let min_dist = min(min(x, y), min(bw - x, rh - y));
    var f = 0.0;
    if (min_dist >= mortar_size) {
        f = 0.0;
    } else if (mortar_smooth == 0.0) {
        f = 1.0;
    } else {
        // A zero mortar size reaches here only by rounding (min_dist < 0): full mortar.
        f = nd_smoothstep(0.0, 1.0, (1.0 - nd_safe_divide(min_dist, mortar_size)) / mortar_smooth);
    }
    var brick_color = color1;
    if (f != 1.0) {
        brick_color = (1.0 - tint) * color1 + tint * color2;
    }
    return NodeTexOut(brick_color * (1.0 - f) + mortar * f, f);
}
