// The image-texture node: texels from the scene's texture buffer `texture_data`
// (src/material/texture.rs; declared by kernel assembly when the scene has textures),
// wrapped, decoded from sRGB where asked, and filtered bilinearly or by nearest texel.
// V runs up the image (row 0 of the file is at v = 1), as in Blender.

// One texel, linear: 8-bit sRGB is decoded per texel, before filtering, as Cycles does.
fn nd_texel(tex: u32, x: u32, y: u32, srgb: bool) -> vec4<f32> {
    let h = tex * 4u;
    let offset = texture_data[h];
    let i = y * texture_data[h + 1u] + x;
    if (texture_data[h + 3u] == 0u) {
        let c = unpack4x8unorm(texture_data[offset + i]);
        if (srgb) {
            return vec4<f32>(nd_srgb_to_linear(c.rgb), c.a);
        }
        return c;
    }
    let rg = texture_data[offset + 2u * i];
    let ba = texture_data[offset + 2u * i + 1u];
    return vec4<f32>(nd_half(rg & 0xffffu), nd_half(rg >> 16u), nd_half(ba & 0xffffu), nd_half(ba >> 16u));
}

// IEEE half bits to f32, decoded by hand: unpack2x16float needs a capability naga does not
// grant every adapter. Infinities (never stored) read as the largest half.
fn nd_half(h: u32) -> f32 {
    let e = (h >> 10u) & 31u;
    let m = h & 1023u;
    var v = bitcast<f32>(((e + 112u) << 23u) | (m << 13u));
    if (e == 0u) {
        v = f32(m) * 5.9604645e-8;
    } else if (e == 31u) {
        v = 65504.0;
    }
    return select(v, -v, (h & 0x8000u) != 0u);
}

fn nd_srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + vec3<f32>(0.055)) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

// Texel coordinate i wrapped into [0, n) by the extension mode; -1 outside for clip.
fn nd_wrap_texel(i: i32, n: i32, extension: u32) -> i32 {
    switch (extension) {
        case 1u: { return clamp(i, 0, n - 1); }
        case 2u: { return select(i, -1, i < 0 || i >= n); }
        case 3u: {
            let period = 2 * n;
            let m = ((i % period) + period) % period;
            return select(m, period - 1 - m, m >= n);
        }
        default: { return ((i % n) + n) % n; }
    }
}

fn nd_texel_wrapped(tex: u32, x: i32, y: i32, w: i32, h: i32, extension: u32, srgb: bool) -> vec4<f32> {
    let wx = nd_wrap_texel(x, w, extension);
    let wy = nd_wrap_texel(y, h, extension);
    if (wx < 0 || wy < 0) {
        return vec4<f32>(0.0);
    }
    return nd_texel(tex, u32(wx), u32(wy), srgb);
}

fn node_image(tex: u32, uv: vec2<f32>, color_space: u32, extension: u32, interpolation: u32) -> vec4<f32> {
    let h4 = tex * 4u;
    let w = i32(texture_data[h4 + 1u]);
    let h = i32(texture_data[h4 + 2u]);
    let srgb = color_space == 0u;
    // Texel centres at half-integers; rows counted from the top.
    let fx = select(0.0, uv.x, uv.x == uv.x) * f32(w);
    let fy = (1.0 - select(0.0, uv.y, uv.y == uv.y)) * f32(h);
    let bound = 1.0e7;
    if (interpolation == 1u) {
        return nd_texel_wrapped(tex, i32(floor(clamp(fx, -bound, bound))), i32(floor(clamp(fy, -bound, bound))), w, h, extension, srgb);
    }
    let px = clamp(fx - 0.5, -bound, bound);
    let py = clamp(fy - 0.5, -bound, bound);
    let x0 = i32(floor(px));
    let y0 = i32(floor(py));
    let tx = px - floor(px);
    let ty = py - floor(py);
    let a = nd_texel_wrapped(tex, x0, y0, w, h, extension, srgb);
    let b = nd_texel_wrapped(tex, x0 + 1, y0, w, h, extension, srgb);
    let c = nd_texel_wrapped(tex, x0, y0 + 1, w, h, extension, srgb);
    let d = nd_texel_wrapped(tex, x0 + 1, y0 + 1, w, h, extension, srgb);
    return mix(mix(a, b, tx), mix(c, d, tx), ty);
}

// The UV of direction `d` in an equirectangular image, as the environment map reads it
// (shaders/lights/environment.wgsl): u = φ / 2π + 1/2 with φ = atan2(x, −z), and v = 1 at
// +Y (the top row), 0 at −Y.
fn nd_equirectangular_uv(d: vec3<f32>) -> vec2<f32> {
    let n = select(vec3<f32>(0.0, 1.0, 0.0), normalize(d), dot(d, d) > 0.0);
    let u = fract(atan2(n.x, -n.z) / (2.0 * 3.14159265) + 0.5);
    return vec2<f32>(u, 1.0 - acos(clamp(n.y, -1.0, 1.0)) / 3.14159265);
}
