// Node library: hashing. Bob Jenkins' lookup3 integer hash, as Cycles uses it
// (intern/cycles/util/hash.h), and the float helpers that hash an f32's *bit pattern*,
// which is what makes the White Noise, Voronoi and Noise-seed outputs match Blender cell
// for cell. Pure functions; no state. Not a random-number generator for sampling: that
// is rng.wgsl.
//
// One deliberate difference: Cycles maps a hash to a float as `f32(h) / f32(0xffffffff)`,
// which is [0, 1] and depends on how the u32 -> f32 conversion rounds. Here the top 24
// bits are scaled instead, which is exact on every GPU, lies in [0, 1) and differs from
// Cycles by less than 2^-24.

fn nd_rot(x: u32, k: u32) -> u32 {
    return (x << k) | (x >> (32u - k));
}

// lookup3's final(a, b, c); only c is used by the callers.
fn nd_jenkins_final(abc: vec3<u32>) -> u32 {
    var a = abc.x;
    var b = abc.y;
    var c = abc.z;
    c ^= b;
    c -= nd_rot(b, 14u);
    a ^= c;
    a -= nd_rot(c, 11u);
    b ^= a;
    b -= nd_rot(a, 25u);
    c ^= b;
    c -= nd_rot(b, 16u);
    a ^= c;
    a -= nd_rot(c, 4u);
    b ^= a;
    b -= nd_rot(a, 14u);
    c ^= b;
    c -= nd_rot(b, 24u);
    return c;
}

// lookup3's mix(a, b, c), needed only by the four-word hash.
fn nd_jenkins_mix(abc: vec3<u32>) -> vec3<u32> {
    var a = abc.x;
    var b = abc.y;
    var c = abc.z;
    a -= c;
    a ^= nd_rot(c, 4u);
    c += b;
    b -= a;
    b ^= nd_rot(a, 6u);
    a += c;
    c -= b;
    c ^= nd_rot(b, 8u);
    b += a;
    a -= c;
    a ^= nd_rot(c, 16u);
    c += b;
    b -= a;
    b ^= nd_rot(a, 19u);
    a += c;
    c -= b;
    c ^= nd_rot(b, 4u);
    b += a;
    return vec3<u32>(a, b, c);
}

// The seed is 0xdeadbeef + (number of words << 2) + 13, as in lookup3's hashword().
fn nd_hash_uint(kx: u32) -> u32 {
    let s = 0xdeadbeefu + (1u << 2u) + 13u;
    return nd_jenkins_final(vec3<u32>(s + kx, s, s));
}

fn nd_hash_uint2(kx: u32, ky: u32) -> u32 {
    let s = 0xdeadbeefu + (2u << 2u) + 13u;
    return nd_jenkins_final(vec3<u32>(s + kx, s + ky, s));
}

fn nd_hash_uint3(kx: u32, ky: u32, kz: u32) -> u32 {
    let s = 0xdeadbeefu + (3u << 2u) + 13u;
    return nd_jenkins_final(vec3<u32>(s + kx, s + ky, s + kz));
}

fn nd_hash_uint4(kx: u32, ky: u32, kz: u32, kw: u32) -> u32 {
    let s = 0xdeadbeefu + (4u << 2u) + 13u;
    let m = nd_jenkins_mix(vec3<u32>(s + kx, s + ky, s + kz));
    return nd_jenkins_final(vec3<u32>(m.x + kw, m.y, m.z));
}

// [0, 2^32) -> [0, 1): the top 24 bits, exactly representable.
fn nd_uint_to_unit_float(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

fn nd_hash_float_to_float(k: f32) -> f32 {
    return nd_uint_to_unit_float(nd_hash_uint(bitcast<u32>(k)));
}

fn nd_hash_vec2_to_float(k: vec2<f32>) -> f32 {
    let b = bitcast<vec2<u32>>(k);
    return nd_uint_to_unit_float(nd_hash_uint2(b.x, b.y));
}

fn nd_hash_vec3_to_float(k: vec3<f32>) -> f32 {
    let b = bitcast<vec3<u32>>(k);
    return nd_uint_to_unit_float(nd_hash_uint3(b.x, b.y, b.z));
}

fn nd_hash_vec4_to_float(k: vec4<f32>) -> f32 {
    let b = bitcast<vec4<u32>>(k);
    return nd_uint_to_unit_float(nd_hash_uint4(b.x, b.y, b.z, b.w));
}

// Cycles' hash_float3_to_float3: the extra components append 1.0 and 2.0 as a fourth word.
fn nd_hash_vec3_to_vec3(k: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        nd_hash_vec3_to_float(k),
        nd_hash_vec4_to_float(vec4<f32>(k, 1.0)),
        nd_hash_vec4_to_float(vec4<f32>(k, 2.0)),
    );
}

fn nd_hash_float_to_vec3(k: f32) -> vec3<f32> {
    return vec3<f32>(
        nd_hash_float_to_float(k),
        nd_hash_vec2_to_float(vec2<f32>(k, 1.0)),
        nd_hash_vec2_to_float(vec2<f32>(k, 2.0)),
    );
}
