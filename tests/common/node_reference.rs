//! CPU mirrors of the WGSL node library (`shaders/nodes/`), for tests that compare GPU
//! values against a reference: the lookup3 hashes bit for bit (they hash f32 bit
//! patterns, as Cycles does), a brute-force Voronoi that finds the true F1/F2 by searching
//! 7×7×7 cells, Blender's own 3×3×3 Voronoi search, the RGB↔HSV conversions and the Mix
//! node's colour blends. Plain `std`, no GPU. Not a second implementation of every node:
//! only what a value test needs as ground truth.
#![allow(dead_code)]

// ---- Jenkins lookup3 (Cycles' util/hash.h) ----

pub fn final_mix(mut a: u32, mut b: u32, mut c: u32) -> u32 {
    c ^= b;
    c = c.wrapping_sub(b.rotate_left(14));
    a ^= c;
    a = a.wrapping_sub(c.rotate_left(11));
    b ^= a;
    b = b.wrapping_sub(a.rotate_left(25));
    c ^= b;
    c = c.wrapping_sub(b.rotate_left(16));
    a ^= c;
    a = a.wrapping_sub(c.rotate_left(4));
    b ^= a;
    b = b.wrapping_sub(a.rotate_left(14));
    c ^= b;
    c = c.wrapping_sub(b.rotate_left(24));
    c
}

fn mix(mut a: u32, mut b: u32, mut c: u32) -> (u32, u32, u32) {
    a = a.wrapping_sub(c);
    a ^= c.rotate_left(4);
    c = c.wrapping_add(b);
    b = b.wrapping_sub(a);
    b ^= a.rotate_left(6);
    a = a.wrapping_add(c);
    c = c.wrapping_sub(b);
    c ^= b.rotate_left(8);
    b = b.wrapping_add(a);
    a = a.wrapping_sub(c);
    a ^= c.rotate_left(16);
    c = c.wrapping_add(b);
    b = b.wrapping_sub(a);
    b ^= a.rotate_left(19);
    a = a.wrapping_add(c);
    c = c.wrapping_sub(b);
    c ^= b.rotate_left(4);
    b = b.wrapping_add(a);
    (a, b, c)
}

/// lookup3's initial value for a key of `words` 32-bit words.
const fn seed(words: u32) -> u32 {
    0xdeadbeef_u32.wrapping_add(words << 2).wrapping_add(13)
}

pub fn hash_uint(kx: u32) -> u32 {
    let s = seed(1);
    final_mix(s.wrapping_add(kx), s, s)
}

pub fn hash_uint2(kx: u32, ky: u32) -> u32 {
    let s = seed(2);
    final_mix(s.wrapping_add(kx), s.wrapping_add(ky), s)
}

pub fn hash_uint3(kx: u32, ky: u32, kz: u32) -> u32 {
    let s = seed(3);
    final_mix(s.wrapping_add(kx), s.wrapping_add(ky), s.wrapping_add(kz))
}

pub fn hash_uint4(kx: u32, ky: u32, kz: u32, kw: u32) -> u32 {
    let s = seed(4);
    let (a, b, c) = mix(s.wrapping_add(kx), s.wrapping_add(ky), s.wrapping_add(kz));
    final_mix(a.wrapping_add(kw), b, c)
}

/// The top 24 bits scaled to [0, 1), exactly as `nd_uint_to_unit_float`.
pub fn uint_to_unit_float(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

pub fn hash_float_to_float(k: f32) -> f32 {
    uint_to_unit_float(hash_uint(k.to_bits()))
}

pub fn hash_vec2_to_float(k: [f32; 2]) -> f32 {
    uint_to_unit_float(hash_uint2(k[0].to_bits(), k[1].to_bits()))
}

pub fn hash_vec3_to_float(k: [f32; 3]) -> f32 {
    uint_to_unit_float(hash_uint3(k[0].to_bits(), k[1].to_bits(), k[2].to_bits()))
}

pub fn hash_vec4_to_float(k: [f32; 4]) -> f32 {
    uint_to_unit_float(hash_uint4(
        k[0].to_bits(),
        k[1].to_bits(),
        k[2].to_bits(),
        k[3].to_bits(),
    ))
}

pub fn hash_vec3_to_vec3(k: [f32; 3]) -> [f32; 3] {
    [
        hash_vec3_to_float(k),
        hash_vec4_to_float([k[0], k[1], k[2], 1.0]),
        hash_vec4_to_float([k[0], k[1], k[2], 2.0]),
    ]
}

pub fn hash_float_to_vec3(k: f32) -> [f32; 3] {
    [
        hash_float_to_float(k),
        hash_vec2_to_float([k, 1.0]),
        hash_vec2_to_float([k, 2.0]),
    ]
}

// ---- Voronoi ----

/// Metrics as in the kernel: 0 euclidean, 1 manhattan, 2 chebyshev, 3 minkowski.
pub fn voronoi_distance(d: [f32; 3], metric: u32, exponent: f32) -> f32 {
    let a = d.map(f32::abs);
    match metric {
        1 => a[0] + a[1] + a[2],
        2 => a[0].max(a[1]).max(a[2]),
        3 => {
            let e = exponent.max(0.05);
            let s: f32 = a
                .iter()
                .map(|&x| if x > 0.0 { x.powf(e) } else { 0.0 })
                .sum();
            if s > 0.0 { s.powf(1.0 / e) } else { 0.0 }
        }
        _ => (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt(),
    }
}

fn add3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale3(a: [f32; 3], s: f32) -> [f32; 3] {
    a.map(|x| x * s)
}

/// Position in input space: divided by scale, 0 for scale 0 (the kernel's safe divide).
fn unscale(a: [f32; 3], scale: f32) -> [f32; 3] {
    if scale == 0.0 {
        [0.0; 3]
    } else {
        a.map(|x| x / scale)
    }
}

/// The nearest and second-nearest feature points of `p`, searching the 7×7×7 cells around
/// p's cell in the scaled space `p · scale`: ground truth for Blender's 3×3×3 search. A
/// point three cells away is at least 2 away, and with randomness ≤ 1 the own cell's
/// point is nearer than √3 (euclidean), so F1 is exact; F2 is in all but contrived
/// configurations. Returns
/// (F1 distance, F2 distance, F1 position in input space). randomness is clamped to
/// [0, 1] as in the kernel.
pub fn voronoi_brute_force(
    p: [f32; 3],
    scale: f32,
    randomness: f32,
    metric: u32,
    exponent: f32,
) -> (f32, f32, [f32; 3]) {
    let rnd = randomness.clamp(0.0, 1.0);
    let coord = scale3(p, scale);
    let cell = coord.map(f32::floor);
    let local = sub3(coord, cell);
    let (mut d1, mut d2) = (f32::MAX, f32::MAX);
    let mut p1 = [0.0; 3];
    for k in -3..=3 {
        for j in -3..=3 {
            for i in -3..=3 {
                let offset = [i as f32, j as f32, k as f32];
                let point = add3(offset, scale3(hash_vec3_to_vec3(add3(cell, offset)), rnd));
                let d = voronoi_distance(sub3(point, local), metric, exponent);
                if d < d1 {
                    d2 = d1;
                    d1 = d;
                    p1 = point;
                } else if d < d2 {
                    d2 = d;
                }
            }
        }
    }
    (d1, d2, unscale(add3(cell, p1), scale))
}

/// What `node_voronoi` computes for F1 and F2: Blender's 3×3×3 search, same loop order and
/// tie-breaking. Returns (F1 distance, F2 distance, F1 position, F2 position, F1 cell
/// colour, F2 cell colour), positions in input space.
pub fn voronoi_blender(
    p: [f32; 3],
    scale: f32,
    randomness: f32,
    metric: u32,
    exponent: f32,
) -> (f32, f32, [f32; 3], [f32; 3], [f32; 3], [f32; 3]) {
    let rnd = randomness.clamp(0.0, 1.0);
    let coord = scale3(p, scale);
    let cell = coord.map(f32::floor);
    let local = sub3(coord, cell);
    let (mut d1, mut d2) = (f32::MAX, f32::MAX);
    let (mut o1, mut o2) = ([0.0; 3], [0.0; 3]);
    let (mut p1, mut p2) = ([0.0; 3], [0.0; 3]);
    for k in -1..=1 {
        for j in -1..=1 {
            for i in -1..=1 {
                let offset = [i as f32, j as f32, k as f32];
                let point = add3(offset, scale3(hash_vec3_to_vec3(add3(cell, offset)), rnd));
                let d = voronoi_distance(sub3(point, local), metric, exponent);
                if d < d1 {
                    (d2, o2, p2) = (d1, o1, p1);
                    (d1, o1, p1) = (d, offset, point);
                } else if d < d2 {
                    (d2, o2, p2) = (d, offset, point);
                }
            }
        }
    }
    (
        d1,
        d2,
        unscale(add3(cell, p1), scale),
        unscale(add3(cell, p2), scale),
        hash_vec3_to_vec3(add3(cell, o1)),
        hash_vec3_to_vec3(add3(cell, o2)),
    )
}

// ---- Colour ----

/// Cycles' rgb_to_hsv, hue in [0, 1) (a hue that rounds to 1.0 becomes 0, as in the kernel).
pub fn rgb_to_hsv(c: [f32; 3]) -> [f32; 3] {
    let cmax = c[0].max(c[1]).max(c[2]);
    let cmin = c[0].min(c[1]).min(c[2]);
    let delta = cmax - cmin;
    let s = if cmax != 0.0 { delta / cmax } else { 0.0 };
    let mut h = 0.0;
    if s != 0.0 {
        let k = c.map(|x| (cmax - x) / delta);
        h = if c[0] == cmax {
            k[2] - k[1]
        } else if c[1] == cmax {
            2.0 + k[0] - k[2]
        } else {
            4.0 + k[1] - k[0]
        };
        h /= 6.0;
        if h < 0.0 {
            h += 1.0;
        }
        if h >= 1.0 {
            h = 0.0;
        }
    }
    [h, s, cmax]
}

pub fn hsv_to_rgb(c: [f32; 3]) -> [f32; 3] {
    let [mut h, s, v] = c;
    if s == 0.0 {
        return [v; 3];
    }
    if h == 1.0 {
        h = 0.0;
    }
    h *= 6.0;
    let i = h.floor();
    let f = h - i;
    let p = v * (1.0 - s);
    let q = v * (1.0 - s * f);
    let t = v * (1.0 - s * (1.0 - f));
    match i as i32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

fn per_channel(a: [f32; 3], b: [f32; 3], f: impl Fn(f32, f32) -> f32) -> [f32; 3] {
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])]
}

/// The Mix node's colour blends, codes as `node_mix_color`: 0 mix, 1 multiply, 2 screen,
/// 3 overlay, 4 add, 5 subtract, 6 difference, 7 lighten, 8 darken, 9 divide, 10 dodge,
/// 11 burn, 12 hue, 13 saturation, 14 value, 15 color, 16 soft_light, 17 linear_light,
/// 18 exclusion. `fac` is used as given (the caller clamps it).
pub fn mix_color(blend: u32, fac: f32, a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let t = fac;
    let tm = 1.0 - t;
    match blend {
        0 => lerp3(a, b, t),
        1 => lerp3(a, per_channel(a, b, |x, y| x * y), t),
        2 => per_channel(a, b, |x, y| 1.0 - (tm + t * (1.0 - y)) * (1.0 - x)),
        3 => per_channel(a, b, |x, y| {
            if x < 0.5 {
                x * (tm + 2.0 * t * y)
            } else {
                1.0 - (tm + 2.0 * t * (1.0 - y)) * (1.0 - x)
            }
        }),
        4 => lerp3(a, per_channel(a, b, |x, y| x + y), t),
        5 => lerp3(a, per_channel(a, b, |x, y| x - y), t),
        6 => lerp3(a, per_channel(a, b, |x, y| (x - y).abs()), t),
        7 => lerp3(a, per_channel(a, b, f32::max), t),
        8 => lerp3(a, per_channel(a, b, f32::min), t),
        9 => per_channel(a, b, |x, y| if y == 0.0 { x } else { tm * x + t * x / y }),
        10 => per_channel(a, b, |x, y| {
            if x == 0.0 {
                return x;
            }
            let d = 1.0 - t * y;
            if d <= 0.0 { 1.0 } else { (x / d).min(1.0) }
        }),
        11 => per_channel(a, b, |x, y| {
            let d = tm + t * y;
            if d <= 0.0 {
                0.0
            } else {
                (1.0 - (1.0 - x) / d).clamp(0.0, 1.0)
            }
        }),
        12 | 15 => {
            let hb = rgb_to_hsv(b);
            if hb[1] == 0.0 {
                return a;
            }
            let ha = rgb_to_hsv(a);
            let s = if blend == 12 { ha[1] } else { hb[1] };
            lerp3(a, hsv_to_rgb([hb[0], s, ha[2]]), t)
        }
        13 => {
            let ha = rgb_to_hsv(a);
            if ha[1] == 0.0 {
                return a;
            }
            let hb = rgb_to_hsv(b);
            hsv_to_rgb([ha[0], tm * ha[1] + t * hb[1], ha[2]])
        }
        14 => {
            let (ha, hb) = (rgb_to_hsv(a), rgb_to_hsv(b));
            hsv_to_rgb([ha[0], ha[1], tm * ha[2] + t * hb[2]])
        }
        16 => per_channel(a, b, |x, y| {
            let scr = 1.0 - (1.0 - y) * (1.0 - x);
            tm * x + t * ((1.0 - x) * y * x + x * scr)
        }),
        17 => per_channel(a, b, |x, y| x + t * (2.0 * y - 1.0)),
        18 => lerp3(a, per_channel(a, b, |x, y| x + y - 2.0 * x * y), t).map(|x| x.max(0.0)),
        _ => [0.0; 3],
    }
}
