// Test kernel: every lobe's sample, eval and pdf at random and extreme inputs. Each
// invocation draws parameters from lists that include the exact extremes (roughness 0 and
// 1, IOR 1, denormal colours), directions that are grazing, back-facing, exactly tangent
// or have a zero component, and counts outputs that are NaN or infinite. It also checks
// reciprocity of reflection: f(wo, wi) = f(wi, wo).
//
// probe_in: [0] = (invocations, seed, 0, 0). probe_out per invocation (f32):
// (non-finite count, relative reciprocity error, lobe kind, roughness).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

const ROUGHNESS: array<f32, 8> = array<f32, 8>(0.0, 1e-6, 0.001, 0.01, 0.1, 0.5, 0.999, 1.0);
const IORS: array<f32, 8> = array<f32, 8>(1.0, 1.0001, 1.001, 1.33, 1.5, 2.4, 4.0, 1e-3);
const COLOURS: array<f32, 5> = array<f32, 5>(0.0, 1e-40, 0.5, 1.0, 1.0);

fn extreme_direction(k: u32, u: vec2<f32>) -> vec3<f32> {
    switch (k) {
        case 0u: { return vec3<f32>(0.0, 0.0, 1.0); }
        case 1u: { return vec3<f32>(0.0, 0.0, -1.0); }
        case 2u: { return vec3<f32>(1.0, 0.0, 0.0); }
        case 3u: { return normalize(vec3<f32>(1.0, 0.0, 1e-7)); }
        case 4u: { return normalize(vec3<f32>(0.0, 1.0, -1e-7)); }
        case 5u: { return normalize(vec3<f32>(1e-30, 0.0, 1.0)); }
        default: { return sample_uniform_sphere(u); }
    }
}

fn extreme_principled(bits: u32, roughness: f32, anisotropy: f32, colour: f32) -> Principled {
    let h = pcg_hash(bits);
    let w = COLOURS[h % 5u];
    let v = COLOURS[(h >> 3u) % 5u];
    var p = principled_default();
    p.base_color = vec3<f32>(colour, v, 0.5);
    p.base_weight = w;
    p.metallic = COLOURS[(h >> 6u) % 5u];
    p.roughness = roughness;
    p.anisotropy = anisotropy;
    p.specular_weight = v;
    p.specular_color = vec3<f32>(1.0, colour, w);
    p.ior = IORS[(h >> 9u) & 7u];
    p.transmission_weight = COLOURS[(h >> 12u) % 5u];
    p.transmission_color = vec3<f32>(w, colour, 1.0);
    p.transmission_depth = select(0.0, 0.5, ((h >> 15u) & 1u) != 0u);
    p.coat_weight = COLOURS[(h >> 16u) % 5u];
    p.coat_roughness = ROUGHNESS[(h >> 19u) & 7u];
    p.coat_ior = IORS[(h >> 22u) & 7u];
    p.coat_color = vec3<f32>(v, 1.0, colour);
    p.sheen_weight = COLOURS[(h >> 25u) % 5u];
    p.sheen_color = vec3<f32>(1.0, w, colour);
    p.sheen_roughness = ROUGHNESS[(h >> 28u) & 7u];
    p.thin_walled = ((h >> 31u) & 1u) != 0u;
    p.diffuse_roughness = COLOURS[(h >> 27u) % 5u];
    return p;
}

@compute @workgroup_size(64)
fn bsdf_extremes(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    if (index >= probe_in[0].x) {
        return;
    }
    rng_seed(index, 7u, probe_in[0].y);
    let bits = pcg_hash(index ^ 0x9e3779b9u);
    let roughness = ROUGHNESS[bits & 7u];
    let anisotropy = select(0.0, 0.9, ((bits >> 3u) & 1u) != 0u);
    let colour = COLOURS[((bits >> 4u) & 7u) % 5u];
    let p = LobeParams(
        select((bits >> 7u) % 5u, 5u, ((bits >> 20u) & 3u) == 0u),
        ggx_alpha(roughness, anisotropy),
        IORS[(bits >> 9u) & 7u],
        ((bits >> 12u) & 1u) != 0u,
        vec3<f32>(colour, 1.0, 0.25),
        vec3<f32>(1.0, colour, 0.5),
        extreme_direction((bits >> 13u) % 10u, rand2()),
        extreme_principled(bits, roughness, anisotropy, colour),
    );
    let wi = extreme_direction((bits >> 17u) % 10u, rand2());
    var bad = 0.0;
    let s = lobe_sample(p);
    if (!all_finite(vec4<f32>(s.wi, s.pdf)) || !all_finite(vec4<f32>(s.weight, 0.0)) || s.pdf < 0.0) {
        bad += 1.0;
    }
    let f = lobe_eval(p, wi);
    let pdf = lobe_pdf(p, wi);
    if (!all_finite(vec4<f32>(f, pdf)) || pdf < 0.0 || any(f < vec3<f32>(0.0))) {
        bad += 1.0;
    }
    // Reciprocity of reflection: f(wo, wi) |cos o| ... written with eval = f |cos i|.
    var reciprocity = 0.0;
    // Reflection lobes only: glass and the principled surface scale their layers by
    // albedos seen from wo, which is not reciprocal.
    if (p.wo.z * wi.z > 1e-4 && p.kind != 2u && p.kind != 5u) {
        let a = f / abs(wi.z);
        let b = lobe_eval(LobeParams(p.kind, p.alpha, p.eta, p.thin, p.f0, p.tint, wi, p.principled), p.wo) / abs(p.wo.z);
        // Values below 1e-6 are rounding noise (e.g. Fresnel at IOR 1 is 0 or 1e-16).
        let scale = max(max(a.x, b.x), 1e-6);
        if (scale < 1e30) {
            reciprocity = abs(a.x - b.x) / scale;
        }
    }
    probe_out[index] = vec4<f32>(bad, reciprocity, f32(p.kind), roughness);
}
