// What compiled material graphs read and return (src/material/compile.rs): the shading
// point, the input nodes' functions, and the material's result. Kernel assembly includes
// only the functions a scene's graphs call.

// Everything a graph may read about the point being shaded; world space unless named.
struct ShadingPoint {
    p: vec3<f32>,
    // Shading normal and geometric normal, on the side the surface's front faces.
    n: vec3<f32>,
    ng: vec3<f32>,
    uv: vec2<f32>,
    // The second UV set (zero where the mesh has none).
    uv1: vec2<f32>,
    // dp/du and dp/dv from the UVs (zero without UVs).
    dpdu: vec3<f32>,
    dpdv: vec3<f32>,
    // Unit direction toward the viewer (-ray direction).
    wo: vec3<f32>,
    p_object: vec3<f32>,
    n_object: vec3<f32>,
    // p_object scaled to the mesh's bounding box: 0 to 1.
    generated: vec3<f32>,
    vertex_color: vec4<f32>,
    instance_random: f32,
    instance_location: vec3<f32>,
    backfacing: bool,
};

// A material evaluated at a point: the principled parameters, emission, opacity and the
// shading normal (world space) its normal input gave.
struct MaterialEval {
    principled: Principled,
    emission: vec3<f32>,
    opacity: f32,
    normal: vec3<f32>,
    anisotropy_rotation: f32,
    // What fills the inside (shaders/nodes/volume.wgsl); read where a path enters.
    volume: VolumeEval,
};

// What the integrator reads of a principled surface with shading normal `normal`.
fn material_eval(p: Principled, normal: vec3<f32>) -> MaterialEval {
    return MaterialEval(p, p.emission_color * p.emission_strength, p.alpha, normal, p.anisotropy_rotation, nd_no_volume());
}

struct NdTextureCoordinate {
    generated: vec3<f32>,
    normal: vec3<f32>,
    uv: vec3<f32>,
    uv1: vec3<f32>,
    object: vec3<f32>,
    world: vec3<f32>,
    reflection: vec3<f32>,
};

fn nd_texture_coordinate(sp: ShadingPoint) -> NdTextureCoordinate {
    return NdTextureCoordinate(
        sp.generated,
        sp.n_object,
        vec3<f32>(sp.uv, 0.0),
        vec3<f32>(sp.uv1, 0.0),
        sp.p_object,
        sp.p,
        reflect(-sp.wo, sp.n),
    );
}

struct NdGeometry {
    p: vec3<f32>,
    n: vec3<f32>,
    ng: vec3<f32>,
    tangent: vec3<f32>,
    wo: vec3<f32>,
    backfacing: f32,
};

// The unit tangent along dp/du made orthogonal to n, or an arbitrary one.
fn nd_tangent(sp: ShadingPoint) -> vec3<f32> {
    return frame_from_normal_tangent(sp.n, sp.dpdu, 0.0).t;
}

fn nd_geometry(sp: ShadingPoint) -> NdGeometry {
    return NdGeometry(sp.p, sp.n, sp.ng, nd_tangent(sp), sp.wo, select(0.0, 1.0, sp.backfacing));
}

struct NdObjectInfo {
    random: f32,
    location: vec3<f32>,
};

fn nd_object_info(sp: ShadingPoint) -> NdObjectInfo {
    return NdObjectInfo(sp.instance_random, sp.instance_location);
}

fn nd_fresnel(ior: f32, normal: vec3<f32>, sp: ShadingPoint) -> f32 {
    let eta = max(ior, 1e-5);
    let c = dot(sp.wo, normal);
    // Seen from behind, the interface is crossed the other way.
    return fresnel_dielectric(abs(c), select(1.0 / eta, eta, c >= 0.0));
}

// Blender's Layer Weight: (fresnel, facing).
fn nd_layer_weight(blend: f32, normal: vec3<f32>, sp: ShadingPoint) -> vec2<f32> {
    let b = clamp(blend, 0.0, 0.99999);
    let eta = max(1.0 - b, 1e-5);
    let c = dot(sp.wo, normal);
    let fresnel = fresnel_dielectric(abs(c), select(eta, 1.0 / eta, c >= 0.0));
    var facing = abs(c);
    if (b != 0.5) {
        let e = select(0.5 / (1.0 - b), 2.0 * b, b < 0.5);
        facing = pow(facing, e);
    }
    return vec2<f32>(fresnel, 1.0 - facing);
}

fn nd_clamp_if(v: f32, on: bool) -> f32 {
    return select(v, clamp(v, 0.0, 1.0), on);
}

fn nd_clamp3_if(v: vec3<f32>, on: bool) -> vec3<f32> {
    return select(v, clamp(v, vec3<f32>(0.0), vec3<f32>(1.0)), on);
}

fn nd_separate_color(c: vec3<f32>, mode: u32) -> vec3<f32> {
    return select(c, nd_rgb_to_hsv(c), mode == 1u);
}

fn nd_combine_color(c: vec3<f32>, mode: u32) -> vec3<f32> {
    return select(c, nd_hsv_to_rgb(c), mode == 1u);
}

// A tangent-space normal map (OpenGL convention: +y along dp/dv) blended by strength.
fn nd_normal_map(strength: f32, color: vec3<f32>, sp: ShadingPoint) -> vec3<f32> {
    let f = frame_from_normal_tangent(sp.n, sp.dpdu, 0.0);
    let c = color * 2.0 - vec3<f32>(1.0);
    var b = f.b;
    // Mirrored UVs flip the bitangent.
    if (dot(cross(sp.dpdu, sp.dpdv), sp.n) < 0.0) {
        b = -b;
    }
    let mapped = c.x * f.t + c.y * b + c.z * f.n;
    return nd_safe_normal(mix(sp.n, nd_safe_normal(mapped, sp.n), max(strength, 0.0)), sp.n);
}

fn nd_safe_normal(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if (!(len2 > 1e-20) || !nd_is_finite3(v)) {
        return fallback;
    }
    return v * inverseSqrt(len2);
}

fn nd_is_finite3(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// A finite value, or `fallback` for NaN and infinities (graphs can compute anything).
fn nd_finite(v: f32, fallback: f32) -> f32 {
    return select(fallback, v, (bitcast<u32>(v) & 0x7f800000u) != 0x7f800000u);
}

fn nd_finite3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(nd_finite(v.x, 0.0), nd_finite(v.y, 0.0), nd_finite(v.z, 0.0));
}

fn nd_unit(v: f32) -> f32 {
    return clamp(nd_finite(v, 0.0), 0.0, 1.0);
}

fn nd_unit3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(nd_unit(v.x), nd_unit(v.y), nd_unit(v.z));
}

// The shading point moved by `d` along the surface (bump mapping's finite differences):
// the position moves by d · (t, b) and the UVs by the matching amount.
fn nd_displaced(sp: ShadingPoint, t: vec3<f32>, step: f32) -> ShadingPoint {
    var q = sp;
    let dp = t * step;
    q.p += dp;
    q.p_object += dp;
    q.generated += dp;
    let lu = dot(sp.dpdu, sp.dpdu);
    let lv = dot(sp.dpdv, sp.dpdv);
    if (lu > 0.0 && lv > 0.0) {
        q.uv += vec2<f32>(dot(dp, sp.dpdu) / lu, dot(dp, sp.dpdv) / lv);
    }
    return q;
}

// The step of bump mapping's finite differences: small against the scene's scale.
fn nd_bump_step(sp: ShadingPoint) -> f32 {
    return 1e-3 * max(1.0, max(abs(sp.p_object.x), max(abs(sp.p_object.y), abs(sp.p_object.z))));
}

// The bumped normal from heights at the point and one step along t and b.
fn nd_bump(strength: f32, distance: f32, h0: f32, ht: f32, hb: f32, step: f32, normal: vec3<f32>, f: Frame, invert: bool) -> vec3<f32> {
    let s = select(1.0, -1.0, invert) * distance / step;
    let g = (ht - h0) * s * f.t + (hb - h0) * s * f.b;
    let bumped = nd_safe_normal(normal - g, normal);
    return nd_safe_normal(mix(normal, bumped, clamp(strength, 0.0, 1.0)), normal);
}

// Colour-ramp interpolation between two stops.
fn nd_ramp_mix(a: vec4<f32>, b: vec4<f32>, pa: f32, pb: f32, t: f32, mode: u32) -> vec4<f32> {
    if (mode == 1u) {
        return a;
    }
    var f = clamp((t - pa) / max(pb - pa, 1e-8), 0.0, 1.0);
    if (mode == 2u) {
        f = f * f * (3.0 - 2.0 * f);
    }
    return mix(a, b, f);
}

// An unconnected material output: Blender's default principled surface.
fn nd_default_surface(sp: ShadingPoint) -> MaterialEval {
    return material_eval(principled_default(), sp.n);
}
