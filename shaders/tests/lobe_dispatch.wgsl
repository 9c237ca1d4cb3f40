// Shared by the BSDF test kernels: one lobe's parameters read from the probe input, and
// dispatch to that lobe's shipped sample / eval / pdf. No bindings of its own: the kernel
// including it declares `probe_in: array<vec4<u32>>`.
//
// A lobe configuration is CONFIG_STRIDE vec4s starting at `base`: (kind, thin, 0, 0),
// (alpha.x, alpha.y, eta, 0) as f32 bits, f0 or albedo, tint, wo, then the principled
// surface's PRINCIPLED_VEC4S packed vec4s (principled_unpack).
// Kinds: 0 diffuse, 1 conductor, 2 dielectric, 3 sheen (roughness in alpha.x), 4 dielectric
// reflection only (scale in tint), 5 the principled surface, 6 single-scattering rough
// diffuse (sigma in alpha.x), 7 the subsurface entry (its IOR in eta).
//
// The kernel including this file also declares `const LOBE_KIND: u32`: the one kind its
// configurations all have, or ANY_KIND. Lavapipe runs both sides of every branch for a
// whole SIMD batch, so a kernel that switches on the kind at run time pays for every lobe
// (the principled mixture's included) at each evaluation; a constant kind folds the switch
// away.

const CONFIG_STRIDE: u32 = 5u + PRINCIPLED_VEC4S;
const ANY_KIND: u32 = 0xffffffffu;

struct LobeParams {
    kind: u32,
    alpha: vec2<f32>,
    eta: f32,
    thin: bool,
    f0: vec3<f32>,
    tint: vec3<f32>,
    wo: vec3<f32>,
    principled: Principled,
};

fn lobe_params(base: u32) -> LobeParams {
    let a = bitcast<vec4<f32>>(probe_in[base + 1u]);
    var packed: array<vec4<f32>, PRINCIPLED_VEC4S>;
    for (var i = 0u; i < PRINCIPLED_VEC4S; i++) {
        packed[i] = bitcast<vec4<f32>>(probe_in[base + 5u + i]);
    }
    return LobeParams(
        select(probe_in[base].x, LOBE_KIND, LOBE_KIND != ANY_KIND),
        a.xy,
        a.z,
        probe_in[base].y != 0u,
        bitcast<vec3<f32>>(probe_in[base + 2u].xyz),
        bitcast<vec3<f32>>(probe_in[base + 3u].xyz),
        bitcast<vec3<f32>>(probe_in[base + 4u].xyz),
        principled_unpack(packed),
    );
}

fn lobe_eval(p: LobeParams, wi: vec3<f32>) -> vec3<f32> {
    switch (p.kind) {
        case 0u: { return diffuse_eval(p.wo, wi, p.f0); }
        case 1u: { return conductor_eval(p.wo, wi, p.alpha, p.f0, p.tint); }
        case 3u: { return sheen_eval(p.wo, wi, p.alpha.x, p.f0); }
        case 4u: { return dielectric_reflection_eval(p.wo, wi, p.alpha, p.eta, p.tint); }
        case 5u: { return principled_eval(p.principled, p.wo, wi).value; }
        case 6u: { return rough_diffuse_eval(p.wo, wi, p.f0, p.alpha.x); }
        case 7u: { return vec3<f32>(subsurface_entry_pdf(p.wo, wi, p.eta)); }
        default: { return dielectric_eval(p.wo, wi, p.alpha, p.eta, p.tint, p.thin); }
    }
}

fn lobe_pdf(p: LobeParams, wi: vec3<f32>) -> f32 {
    switch (p.kind) {
        case 0u: { return diffuse_pdf(p.wo, wi); }
        case 1u: { return conductor_pdf(p.wo, wi, p.alpha); }
        case 3u: { return sheen_pdf(p.wo, wi); }
        case 4u: { return dielectric_reflection_pdf(p.wo, wi, p.alpha); }
        case 5u: { return principled_eval(p.principled, p.wo, wi).pdf; }
        case 6u: { return diffuse_pdf(p.wo, wi); }
        case 7u: { return subsurface_entry_pdf(p.wo, wi, p.eta); }
        default: { return dielectric_pdf(p.wo, wi, p.alpha, p.eta, p.thin); }
    }
}

fn lobe_sample(p: LobeParams) -> BsdfSample {
    let uc = rand();
    let u = rand2();
    switch (p.kind) {
        case 0u: {
            let d = diffuse_sample(p.wo, p.f0, u);
            return BsdfSample(d.wi, d.weight, d.pdf, false, d.pdf > 0.0);
        }
        case 1u: { return conductor_sample(p.wo, p.alpha, p.f0, p.tint, u); }
        case 3u: { return sheen_sample(p.wo, p.alpha.x, p.f0, u); }
        case 4u: { return dielectric_reflection_sample(p.wo, p.alpha, p.eta, p.tint, u); }
        case 5u: { return principled_sample(p.principled, p.wo, uc, rand(), u); }
        case 6u: {
            let d = diffuse_sample(p.wo, vec3<f32>(1.0), u);
            let f = rough_diffuse_eval(p.wo, d.wi, p.f0, p.alpha.x);
            return BsdfSample(d.wi, f / max(d.pdf, 1e-30), d.pdf, false, d.pdf > 0.0);
        }
        case 7u: {
            let wi = subsurface_entry_sample(p.wo, p.eta, uc, u);
            let pdf = subsurface_entry_pdf(p.wo, wi, p.eta);
            return BsdfSample(wi, vec3<f32>(1.0), pdf, false, pdf > 0.0);
        }
        default: { return dielectric_sample(p.wo, p.alpha, p.eta, p.tint, p.thin, uc, u); }
    }
}

// The cell of tests/common/chi2.rs SphereBins: band uniform in cos θ from +Z (closed
// toward +Z), sector uniform in φ from +X toward +Y.
fn sphere_cell(d: vec3<f32>, theta_bins: u32, phi_bins: u32) -> u32 {
    let w = normalize(d);
    let dz = 2.0 / f32(theta_bins);
    let band = min(u32(max(ceil((1.0 - clamp(w.z, -1.0, 1.0)) / dz) - 1.0, 0.0)), theta_bins - 1u);
    var phi = atan2(w.y, w.x);
    if (phi < 0.0) {
        phi += 2.0 * PI;
    }
    let sector = min(u32(floor(phi / (2.0 * PI / f32(phi_bins)))), phi_bins - 1u);
    return band * phi_bins + sector;
}

fn all_finite(v: vec4<f32>) -> bool {
    let e = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(e != vec4<u32>(0x7f800000u));
}
