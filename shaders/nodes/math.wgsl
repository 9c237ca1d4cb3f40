// Node library: the converter nodes that do arithmetic. Mirrors Blender's Math, Vector
// Math, Map Range (float), Clamp and Mapping shader nodes with Cycles' semantics
// (intern/cycles/kernel/svm/math_util.h, map_range.h, clamp.h, mapping_util.h), including
// its "safe" variants: a division by zero, the log of a non-positive number, the root of
// a negative one, a fractional power of a negative base and a modulo by zero all give 0,
// never NaN. Operations that overflow in Blender (exp, sinh, cosh, a large power) may
// still overflow here. Op codes are the order of the lists below, not Blender's enum values.

fn nd_safe_divide(a: f32, b: f32) -> f32 {
    return select(0.0, a / b, b != 0.0);
}

fn nd_safe_divide3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(nd_safe_divide(a.x, b.x), nd_safe_divide(a.y, b.y), nd_safe_divide(a.z, b.z));
}

fn nd_safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(vec3<f32>(0.0), v / l, l > 0.0);
}

// Cycles' safe_powf on top of compatible_powf (its GPU branch): x^0 = 1 even for x = 0,
// 0^y = 0 otherwise (also for y < 0, where C's powf would give inf), a negative base
// needs an integer exponent and takes its sign from the exponent's parity. WGSL's pow is
// undefined for x <= 0, so those cases never reach it.
fn nd_safe_pow(a: f32, b: f32) -> f32 {
    if (b == 0.0) {
        return 1.0;
    }
    if (a == 0.0) {
        return 0.0;
    }
    if (a < 0.0) {
        if (b != floor(b)) {
            return 0.0;
        }
        let m = pow(-a, b);
        return select(-m, m, (-b) % 2.0 == 0.0);
    }
    return pow(a, b);
}

fn nd_safe_log(a: f32, base: f32) -> f32 {
    if (a <= 0.0 || base <= 0.0) {
        return 0.0;
    }
    return nd_safe_divide(log(a), log(base));
}

// C's fmodf: the remainder truncated toward zero, which is WGSL's float `%`.
fn nd_safe_modulo(a: f32, b: f32) -> f32 {
    return select(0.0, a % b, b != 0.0);
}

fn nd_safe_floored_modulo(a: f32, b: f32) -> f32 {
    return select(0.0, a - floor(a / b) * b, b != 0.0);
}

// Cycles' wrapf(value, max, min): wraps into [min, max); a zero-width range gives min.
fn nd_wrap(value: f32, max_v: f32, min_v: f32) -> f32 {
    let range = max_v - min_v;
    if (range == 0.0) {
        return min_v;
    }
    return value - range * floor((value - min_v) / range);
}

fn nd_pingpong(a: f32, b: f32) -> f32 {
    if (b == 0.0) {
        return 0.0;
    }
    let t = (a - b) / (b * 2.0);
    return abs((t - floor(t)) * b * 2.0 - b);
}

// Polynomial smooth minimum with blend distance k (Cycles' smoothminf).
fn nd_smooth_min(a: f32, b: f32, k: f32) -> f32 {
    if (k == 0.0) {
        return min(a, b);
    }
    let h = max(k - abs(a - b), 0.0) / k;
    return min(a, b) - h * h * h * k * (1.0 / 6.0);
}

// tanh saturated by hand: some drivers evaluate it as a quotient of exponentials, which
// is inf / inf = NaN for |x| beyond ~44. tanh(10) already rounds to 1 in f32.
fn nd_tanh(x: f32) -> f32 {
    return select(tanh(x), sign(x), abs(x) > 10.0);
}

// Math node. Op codes (0-based), 41 ops:
//  0 add            1 subtract       2 multiply       3 divide         4 multiply_add
//  5 power          6 logarithm      7 sqrt           8 inverse_sqrt   9 absolute
// 10 exponent      11 minimum       12 maximum       13 less_than     14 greater_than
// 15 sign          16 compare       17 smooth_min    18 smooth_max    19 round
// 20 floor         21 ceil          22 truncate      23 fraction      24 truncated_modulo
// 25 floored_modulo 26 wrap         27 snap          28 pingpong      29 sine
// 30 cosine        31 tangent       32 arcsine       33 arccosine     34 arctangent
// 35 arctan2       36 sinh          37 cosh          38 tanh          39 radians
// 40 degrees
// `b` is the second operand (base of the logarithm, exponent of power, increment of snap,
// scale of pingpong, max of wrap); `c` is the third (addend of multiply_add, epsilon of
// compare, distance of smooth min/max, min of wrap). Unknown codes give 0.
fn node_math(op: u32, a: f32, b: f32, c: f32) -> f32 {
    switch op {
        case 0u: { return a + b; }
        case 1u: { return a - b; }
        case 2u: { return a * b; }
        case 3u: { return nd_safe_divide(a, b); }
        case 4u: { return a * b + c; }
        case 5u: { return nd_safe_pow(a, b); }
        case 6u: { return nd_safe_log(a, b); }
        case 7u: { return sqrt(max(a, 0.0)); }
        case 8u: { return select(0.0, 1.0 / sqrt(a), a > 0.0); }
        case 9u: { return abs(a); }
        case 10u: { return exp(a); }
        case 11u: { return min(a, b); }
        case 12u: { return max(a, b); }
        case 13u: { return select(0.0, 1.0, a < b); }
        case 14u: { return select(0.0, 1.0, a > b); }
        // sign(0) = 0, as Cycles' compatible_signf.
        case 15u: { return sign(a); }
        // The tolerance is at least FLT_EPSILON (1.1920929e-7), as in Cycles.
        case 16u: { return select(0.0, 1.0, a == b || abs(a - b) <= max(c, 1.1920929e-7)); }
        case 17u: { return nd_smooth_min(a, b, c); }
        case 18u: { return -nd_smooth_min(-a, -b, c); }
        // Halves round up, also for negatives (floor(a + 0.5)), unlike WGSL's round.
        case 19u: { return floor(a + 0.5); }
        case 20u: { return floor(a); }
        case 21u: { return ceil(a); }
        case 22u: { return trunc(a); }
        case 23u: { return a - floor(a); }
        case 24u: { return nd_safe_modulo(a, b); }
        case 25u: { return nd_safe_floored_modulo(a, b); }
        case 26u: { return nd_wrap(a, b, c); }
        case 27u: { return floor(nd_safe_divide(a, b)) * b; }
        case 28u: { return nd_pingpong(a, b); }
        case 29u: { return sin(a); }
        case 30u: { return cos(a); }
        case 31u: { return tan(a); }
        case 32u: { return asin(clamp(a, -1.0, 1.0)); }
        case 33u: { return acos(clamp(a, -1.0, 1.0)); }
        case 34u: { return atan(a); }
        // atan2(0, 0) is undefined in WGSL; C gives 0 for it.
        case 35u: { return select(atan2(a, b), 0.0, a == 0.0 && b == 0.0); }
        case 36u: { return sinh(a); }
        case 37u: { return cosh(a); }
        case 38u: { return nd_tanh(a); }
        case 39u: { return a * (PI / 180.0); }
        case 40u: { return a * (180.0 / PI); }
        default: { return 0.0; }
    }
}

struct NodeVectorMathOut {
    vector: vec3<f32>,
    value: f32,
}

fn nd_vector_out(v: vec3<f32>) -> NodeVectorMathOut {
    return NodeVectorMathOut(v, 0.0);
}

fn nd_value_out(x: f32) -> NodeVectorMathOut {
    return NodeVectorMathOut(vec3<f32>(0.0), x);
}

// Cycles' refract with a unit normal: zero on total internal reflection.
fn nd_refract(i: vec3<f32>, n: vec3<f32>, eta: f32) -> vec3<f32> {
    let d = dot(n, i);
    let k = 1.0 - eta * eta * (1.0 - d * d);
    if (k < 0.0) {
        return vec3<f32>(0.0);
    }
    return eta * i - (eta * d + sqrt(k)) * n;
}

// Vector Math node. Op codes (0-based), 27 ops:
//  0 add            1 subtract       2 multiply       3 divide         4 multiply_add
//  5 cross          6 project        7 reflect        8 refract        9 faceforward
// 10 dot           11 distance      12 length        13 scale         14 normalize
// 15 absolute      16 minimum       17 maximum       18 floor         19 ceil
// 20 fraction      21 modulo        22 wrap          23 snap          24 sine
// 25 cosine        26 tangent
// dot, distance and length write `value` (vector = 0); the rest write `vector`
// (value = 0). `s` is the scale of `scale` and the IOR ratio of `refract`; `c` is the
// addend of multiply_add, the reference of faceforward and the min of wrap (b is max).
fn node_vector_math(
    op: u32,
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    s: f32,
) -> NodeVectorMathOut {
    switch op {
        case 0u: { return nd_vector_out(a + b); }
        case 1u: { return nd_vector_out(a - b); }
        case 2u: { return nd_vector_out(a * b); }
        case 3u: { return nd_vector_out(nd_safe_divide3(a, b)); }
        case 4u: { return nd_vector_out(a * b + c); }
        case 5u: { return nd_vector_out(cross(a, b)); }
        case 6u: {
            let bb = dot(b, b);
            return nd_vector_out(select(vec3<f32>(0.0), b * (dot(a, b) / bb), bb != 0.0));
        }
        // Blender normalizes the normal of reflect and refract; a zero normal stays zero
        // here instead of turning into NaN.
        case 7u: {
            let n = nd_safe_normalize(b);
            return nd_vector_out(a - 2.0 * dot(a, n) * n);
        }
        case 8u: { return nd_vector_out(nd_refract(a, nd_safe_normalize(b), s)); }
        // faceforward(N = a, I = b, Nref = c): a if dot(c, b) < 0, else -a.
        case 9u: { return nd_vector_out(select(-a, a, dot(c, b) < 0.0)); }
        case 10u: { return nd_value_out(dot(a, b)); }
        case 11u: { return nd_value_out(length(a - b)); }
        case 12u: { return nd_value_out(length(a)); }
        case 13u: { return nd_vector_out(a * s); }
        case 14u: { return nd_vector_out(nd_safe_normalize(a)); }
        case 15u: { return nd_vector_out(abs(a)); }
        case 16u: { return nd_vector_out(min(a, b)); }
        case 17u: { return nd_vector_out(max(a, b)); }
        case 18u: { return nd_vector_out(floor(a)); }
        case 19u: { return nd_vector_out(ceil(a)); }
        case 20u: { return nd_vector_out(a - floor(a)); }
        case 21u: {
            return nd_vector_out(vec3<f32>(
                nd_safe_modulo(a.x, b.x),
                nd_safe_modulo(a.y, b.y),
                nd_safe_modulo(a.z, b.z),
            ));
        }
        case 22u: {
            return nd_vector_out(vec3<f32>(
                nd_wrap(a.x, b.x, c.x),
                nd_wrap(a.y, b.y, c.y),
                nd_wrap(a.z, b.z, c.z),
            ));
        }
        case 23u: { return nd_vector_out(floor(nd_safe_divide3(a, b)) * b); }
        case 24u: { return nd_vector_out(sin(a)); }
        case 25u: { return nd_vector_out(cos(a)); }
        case 26u: { return nd_vector_out(tan(a)); }
        default: { return NodeVectorMathOut(vec3<f32>(0.0), 0.0); }
    }
}

// Smoothstep of Cycles' util: 0 below edge0, 1 from edge1 on, 3t² - 2t³ between.
fn nd_smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    if (x < edge0) {
        return 0.0;
    }
    if (x >= edge1) {
        return 1.0;
    }
    let t = (x - edge0) / (edge1 - edge0);
    return (3.0 - 2.0 * t) * t * t;
}

fn nd_smootherstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = clamp(nd_safe_divide(x - edge0, edge1 - edge0), 0.0, 1.0);
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// Map Range node (float). Modes: 0 linear, 1 stepped, 2 smoothstep, 3 smootherstep.
// As in Cycles, a zero-width source range (from_min == from_max) yields 0, and stepped
// with steps <= 0 yields to_min. `clamp_result` clamps into [to_min, to_max] (either
// order) and, as in Blender, only applies to linear and stepped: the smooth modes never
// leave that range anyway.
fn node_map_range(
    mode: u32,
    value: f32,
    from_min: f32,
    from_max: f32,
    to_min: f32,
    to_max: f32,
    steps: f32,
    clamp_result: bool,
) -> f32 {
    var result = 0.0;
    if (from_max != from_min) {
        var factor = (value - from_min) / (from_max - from_min);
        switch mode {
            case 1u: {
                factor = select(0.0, floor(factor * (steps + 1.0)) / steps, steps > 0.0);
            }
            case 2u: {
                if (from_min > from_max) {
                    factor = 1.0 - nd_smoothstep(from_max, from_min, value);
                } else {
                    factor = nd_smoothstep(from_min, from_max, value);
                }
            }
            case 3u: {
                if (from_min > from_max) {
                    factor = 1.0 - nd_smootherstep(from_max, from_min, value);
                } else {
                    factor = nd_smootherstep(from_min, from_max, value);
                }
            }
            default: {}
        }
        result = to_min + factor * (to_max - to_min);
    }
    if (clamp_result && mode <= 1u) {
        result = min(max(result, min(to_min, to_max)), max(to_min, to_max));
    }
    return result;
}

// Clamp node. Modes: 0 min_max (max wins when min > max, as in Blender), 1 range (the
// bounds are swapped when min > max).
fn node_clamp(mode: u32, value: f32, min_v: f32, max_v: f32) -> f32 {
    if (mode == 1u && min_v > max_v) {
        return min(max(value, max_v), min_v);
    }
    // Not WGSL's clamp, whose result is undefined when the bounds are inverted.
    return min(max(value, min_v), max_v);
}

// Rows of Cycles' euler_to_transform: R = Rz · Ry · Rx, so X is applied first.
struct NdRotation {
    r0: vec3<f32>,
    r1: vec3<f32>,
    r2: vec3<f32>,
}

fn nd_euler_xyz(e: vec3<f32>) -> NdRotation {
    let c = cos(e);
    let s = sin(e);
    return NdRotation(
        vec3<f32>(c.y * c.z, s.y * s.x * c.z - c.x * s.z, s.y * c.x * c.z + s.x * s.z),
        vec3<f32>(c.y * s.z, s.y * s.x * s.z + c.x * c.z, s.y * c.x * s.z - s.x * c.z),
        vec3<f32>(-s.y, c.y * s.x, c.y * c.x),
    );
}

fn nd_rotate(r: NdRotation, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(r.r0, v), dot(r.r1, v), dot(r.r2, v));
}

fn nd_rotate_inverse(r: NdRotation, v: vec3<f32>) -> vec3<f32> {
    return r.r0 * v.x + r.r1 * v.y + r.r2 * v.z;
}

// Mapping node. Kinds: 0 point (scale, rotate, translate), 1 texture (the inverse of
// point: untranslate, unrotate, unscale; a zero scale component gives 0), 2 vector
// (scale, rotate; location ignored), 3 normal (divide by scale, rotate, normalize).
// `rotation` is XYZ Euler in radians.
fn node_mapping(
    kind: u32,
    v: vec3<f32>,
    location: vec3<f32>,
    rotation: vec3<f32>,
    scale: vec3<f32>,
) -> vec3<f32> {
    let r = nd_euler_xyz(rotation);
    switch kind {
        case 0u: { return nd_rotate(r, v * scale) + location; }
        case 1u: { return nd_safe_divide3(nd_rotate_inverse(r, v - location), scale); }
        case 2u: { return nd_rotate(r, v * scale); }
        case 3u: { return nd_safe_normalize(nd_rotate(r, nd_safe_divide3(v, scale))); }
        default: { return vec3<f32>(0.0); }
    }
}
