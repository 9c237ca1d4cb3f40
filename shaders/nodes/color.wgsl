// Node library: colour nodes. Mirrors Blender's Mix (colour mode), Hue/Saturation/Value,
// Invert, Gamma, Brightness/Contrast and RGB to BW shader nodes with Cycles' formulas
// (intern/cycles/kernel/svm/color_util.h, hsv.h, invert.h, gamma.h, util/color.h).
// Colours are linear RGB and are not clamped unless Blender clamps them.

// Cycles' rgb_to_hsv: hue and saturation are 0 for greys (and for black). Hue is in
// [0, 1): where Cycles can round a tiny negative hue up to exactly 1.0, this returns 0,
// the same colour (hsv_to_rgb treats 1 as 0).
fn nd_rgb_to_hsv(c: vec3<f32>) -> vec3<f32> {
    let cmax = max(c.x, max(c.y, c.z));
    let cmin = min(c.x, min(c.y, c.z));
    let delta = cmax - cmin;
    var s = 0.0;
    if (cmax != 0.0) {
        s = delta / cmax;
    }
    var h = 0.0;
    if (s != 0.0) {
        let k = (vec3<f32>(cmax) - c) / delta;
        if (c.x == cmax) {
            h = k.z - k.y;
        } else if (c.y == cmax) {
            h = 2.0 + k.x - k.z;
        } else {
            h = 4.0 + k.y - k.x;
        }
        h /= 6.0;
        if (h < 0.0) {
            h += 1.0;
        }
        if (h >= 1.0) {
            h = 0.0;
        }
    }
    return vec3<f32>(h, s, cmax);
}

// Cycles' hsv_to_rgb. Hue is expected in [0, 1] (1 is red again); a hue outside that
// lands in the last sextant, as in Cycles.
fn nd_hsv_to_rgb(c: vec3<f32>) -> vec3<f32> {
    let s = c.y;
    let v = c.z;
    if (s == 0.0) {
        return vec3<f32>(v);
    }
    var h = c.x;
    if (h == 1.0) {
        h = 0.0;
    }
    h *= 6.0;
    let i = floor(h);
    let f = h - i;
    let p = v * (1.0 - s);
    let q = v * (1.0 - s * f);
    let t = v * (1.0 - s * (1.0 - f));
    if (i == 0.0) {
        return vec3<f32>(v, t, p);
    } else if (i == 1.0) {
        return vec3<f32>(q, v, p);
    } else if (i == 2.0) {
        return vec3<f32>(p, v, t);
    } else if (i == 3.0) {
        return vec3<f32>(p, q, v);
    } else if (i == 4.0) {
        return vec3<f32>(t, p, v);
    }
    return vec3<f32>(v, p, q);
}

// Cycles' interp(a, b, t) = a + t (b - a); not WGSL's mix, which rounds differently.
fn nd_lerp3(a: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> {
    return a + t * (b - a);
}

fn nd_overlay1(t: f32, a: f32, b: f32) -> f32 {
    let tm = 1.0 - t;
    if (a < 0.5) {
        return a * (tm + 2.0 * t * b);
    }
    return 1.0 - (tm + 2.0 * t * (1.0 - b)) * (1.0 - a);
}

// A zero divisor leaves that channel of `a` unchanged.
fn nd_divide1(t: f32, a: f32, b: f32) -> f32 {
    if (b == 0.0) {
        return a;
    }
    return (1.0 - t) * a + t * a / b;
}

fn nd_dodge1(t: f32, a: f32, b: f32) -> f32 {
    if (a == 0.0) {
        return a;
    }
    let d = 1.0 - t * b;
    if (d <= 0.0) {
        return 1.0;
    }
    return min(a / d, 1.0);
}

fn nd_burn1(t: f32, a: f32, b: f32) -> f32 {
    let d = 1.0 - t + t * b;
    if (d <= 0.0) {
        return 0.0;
    }
    return clamp(1.0 - (1.0 - a) / d, 0.0, 1.0);
}

// Mix node, colour mode: blends `b` over `a` by `fac` (already clamped to [0, 1] by the
// caller when the node clamps its factor). Blend codes (0-based), 19 modes:
//  0 mix          1 multiply     2 screen       3 overlay      4 add
//  5 subtract     6 difference   7 lighten      8 darken       9 divide
// 10 dodge       11 burn        12 hue         13 saturation  14 value
// 15 color       16 soft_light  17 linear_light 18 exclusion
// Unknown codes give black.
fn node_mix_color(blend: u32, fac: f32, a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let t = fac;
    let tm = 1.0 - t;
    let one = vec3<f32>(1.0);
    switch blend {
        case 0u: { return nd_lerp3(a, b, t); }
        case 1u: { return nd_lerp3(a, a * b, t); }
        case 2u: { return one - (vec3<f32>(tm) + t * (one - b)) * (one - a); }
        case 3u: {
            return vec3<f32>(nd_overlay1(t, a.x, b.x), nd_overlay1(t, a.y, b.y), nd_overlay1(t, a.z, b.z));
        }
        case 4u: { return nd_lerp3(a, a + b, t); }
        case 5u: { return nd_lerp3(a, a - b, t); }
        case 6u: { return nd_lerp3(a, abs(a - b), t); }
        case 7u: { return nd_lerp3(a, max(a, b), t); }
        case 8u: { return nd_lerp3(a, min(a, b), t); }
        case 9u: {
            return vec3<f32>(nd_divide1(t, a.x, b.x), nd_divide1(t, a.y, b.y), nd_divide1(t, a.z, b.z));
        }
        case 10u: {
            return vec3<f32>(nd_dodge1(t, a.x, b.x), nd_dodge1(t, a.y, b.y), nd_dodge1(t, a.z, b.z));
        }
        case 11u: {
            return vec3<f32>(nd_burn1(t, a.x, b.x), nd_burn1(t, a.y, b.y), nd_burn1(t, a.z, b.z));
        }
        // Hue and Color do nothing when `b` is grey (it has no hue to give).
        case 12u: {
            let hsv_b = nd_rgb_to_hsv(b);
            if (hsv_b.y == 0.0) {
                return a;
            }
            let hsv_a = nd_rgb_to_hsv(a);
            return nd_lerp3(a, nd_hsv_to_rgb(vec3<f32>(hsv_b.x, hsv_a.y, hsv_a.z)), t);
        }
        // Saturation does nothing when `a` is grey (there is no hue to saturate).
        case 13u: {
            let hsv_a = nd_rgb_to_hsv(a);
            if (hsv_a.y == 0.0) {
                return a;
            }
            let hsv_b = nd_rgb_to_hsv(b);
            return nd_hsv_to_rgb(vec3<f32>(hsv_a.x, tm * hsv_a.y + t * hsv_b.y, hsv_a.z));
        }
        case 14u: {
            let hsv_a = nd_rgb_to_hsv(a);
            let hsv_b = nd_rgb_to_hsv(b);
            return nd_hsv_to_rgb(vec3<f32>(hsv_a.x, hsv_a.y, tm * hsv_a.z + t * hsv_b.z));
        }
        case 15u: {
            let hsv_b = nd_rgb_to_hsv(b);
            if (hsv_b.y == 0.0) {
                return a;
            }
            let hsv_a = nd_rgb_to_hsv(a);
            return nd_lerp3(a, nd_hsv_to_rgb(vec3<f32>(hsv_b.x, hsv_b.y, hsv_a.z)), t);
        }
        case 16u: {
            let scr = one - (one - b) * (one - a);
            return tm * a + t * ((one - a) * b * a + a * scr);
        }
        case 17u: { return a + t * (2.0 * b - one); }
        case 18u: { return max(nd_lerp3(a, a + b - 2.0 * a * b, t), vec3<f32>(0.0)); }
        default: { return vec3<f32>(0.0); }
    }
}

// Hue/Saturation/Value node: hue 0.5 is no shift (the hue is shifted by hue + 0.5 and
// wrapped), saturation and value scale; the result is blended with the input by `fac`
// and clamped at 0 as in Cycles (over-saturation can push channels negative).
fn node_hue_saturation_value(
    hue: f32,
    saturation: f32,
    value: f32,
    fac: f32,
    color: vec3<f32>,
) -> vec3<f32> {
    var hsv = nd_rgb_to_hsv(color);
    let h = hsv.x + hue + 0.5;
    hsv.x = h - floor(h);
    hsv.y = clamp(hsv.y * saturation, 0.0, 1.0);
    hsv.z *= value;
    let shifted = nd_hsv_to_rgb(hsv);
    return max(fac * shifted + (1.0 - fac) * color, vec3<f32>(0.0));
}

fn node_invert(fac: f32, color: vec3<f32>) -> vec3<f32> {
    return fac * (vec3<f32>(1.0) - color) + (1.0 - fac) * color;
}

// Gamma node: only positive channels are raised; gamma 0 gives white (x^0), as in Cycles.
fn node_gamma(color: vec3<f32>, gamma: f32) -> vec3<f32> {
    if (gamma == 0.0) {
        return vec3<f32>(1.0);
    }
    // max() keeps pow's argument positive; select() then keeps non-positive channels.
    let raised = pow(max(color, vec3<f32>(1e-30)), vec3<f32>(gamma));
    return select(color, raised, color > vec3<f32>(0.0));
}

// Brightness/Contrast node: (1 + contrast) · c + bright - contrast / 2, clamped at 0.
fn node_bright_contrast(color: vec3<f32>, bright: f32, contrast: f32) -> vec3<f32> {
    let a = 1.0 + contrast;
    let b = bright - contrast * 0.5;
    return max(a * color + vec3<f32>(b), vec3<f32>(0.0));
}

// RGB to BW node: Rec.709 luminance (Cycles uses the scene's colour space; Kiln's
// working space is linear Rec.709).
fn node_rgb_to_bw(color: vec3<f32>) -> f32 {
    return dot(color, vec3<f32>(0.2126, 0.7152, 0.0722));
}
