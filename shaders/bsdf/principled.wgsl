// The principled surface: Blender's Principled BSDF / OpenPBR Surface parameters over the
// lobes of this folder, layered by albedo scaling (each layer takes its estimated
// directional albedo off the energy of the layers beneath):
//
//   coat (dielectric reflection, tinting what passes through it)
//   └ sheen (Charlie microfibers)
//     └ metal (GGX, F82 tint)                               weight metallic
//       └ dielectric base                                   weight 1 - metallic
//         ├ glass (rough or smooth, thin or solid)         weight transmission
//         └ specular reflection over diffuse               weight 1 - transmission
//             └ diffuse split with subsurface              weight subsurface
//               (in a thin wall: with diffuse transmission)
//
// A sample picks one lobe with probability proportional to its estimated albedo toward wo;
// the pdf for MIS is the mixture of every non-delta lobe's pdf, so any direction any lobe
// can produce gets one consistent density. Local frame, z = shading normal; for
// transmissive or thin-walled materials z is the outside (front) of the surface, for
// opaque ones the caller turns it toward wo.
//
// Rough metal and rough glass carry multiple-scattering energy compensation
// (multiple_scattering.wgsl, dielectric_energy.wgsl), so white ones stay white at every
// roughness. Not yet: coat/base layering beyond albedo scaling.
//
// The subsurface lobe is a transmission of albedo 1 into the object (half Lambertian, half
// refracted through a rough interface of the subsurface IOR): the colour comes from the
// random walk that follows (shaders/media/subsurface.wgsl), which the
// integrator starts when this lobe was the one sampled (`principled_sampled_lobe`).
// A thin wall has no inside to walk in: there the subsurface weight is diffuse
// transmission through the wall, tinted by the transmission colour (OpenPBR's thin-walled
// subsurface; glTF's KHR_materials_diffuse_transmission).

// `struct Principled`, its packed form and defaults are generated from the parameter table
// (src/shader/principled.rs).

const LOBE_COAT: u32 = 0u;
const LOBE_SHEEN: u32 = 1u;
const LOBE_METAL: u32 = 2u;
const LOBE_GLASS: u32 = 3u;
const LOBE_SPECULAR: u32 = 4u;
const LOBE_DIFFUSE: u32 = 5u;
// The metal's multiple-scattering compensation (shaders/bsdf/multiple_scattering.wgsl).
const LOBE_METAL_MS: u32 = 6u;
// Into the object, for a random walk (shaders/media/subsurface.wgsl).
const LOBE_SUBSURFACE: u32 = 7u;
// Through a thin wall, to its other side.
const LOBE_TRANSLUCENT: u32 = 8u;
const LOBE_COUNT: u32 = 9u;

// The lobe the last principled_sample drew from.
var<private> principled_sampled_lobe: u32;

// Per-lobe colour scale (layering) and selection probability for one wo.
struct LobeWeights {
    scale: array<vec3<f32>, LOBE_COUNT>,
    probability: array<f32, LOBE_COUNT>,
};

fn principled_glass_tint(p: Principled) -> vec3<f32> {
    if (p.transmission_depth > 0.0 && !p.thin_walled) {
        return vec3<f32>(1.0);
    }
    return p.transmission_color;
}

fn principled_weights(p: Principled, wo: vec3<f32>) -> LobeWeights {
    var w: LobeWeights;
    let cos_o = abs(wo.z);
    // Coat: its Fresnel reflectance stands in for its albedo (exact when smooth).
    // Lobes the kernel was built without (src/render/kernel.rs, KernelFeatures) have no
    // weight, so the driver drops their code.
    let coat = select(0.0, clamp(p.coat_weight, 0.0, 1.0), FEATURE_COAT);
    let coat_albedo = fresnel_dielectric(cos_o, max(p.coat_ior, 1.0));
    w.scale[LOBE_COAT] = vec3<f32>(coat);
    var below = (1.0 - coat * coat_albedo) * mix(vec3<f32>(1.0), p.coat_color, coat);
    // Sheen: normalised where the Charlie lobe would reflect more than it receives.
    let sheen = select(0.0, clamp(p.sheen_weight, 0.0, 1.0), FEATURE_SHEEN);
    let sheen_e = sheen_albedo(cos_o, p.sheen_roughness);
    w.scale[LOBE_SHEEN] = below * sheen * p.sheen_color / max(sheen_e, 1.0);
    below *= 1.0 - sheen * min(sheen_e, 1.0) * max(p.sheen_color.r, max(p.sheen_color.g, p.sheen_color.b));
    let metal = select(0.0, clamp(p.metallic, 0.0, 1.0), FEATURE_METAL);
    w.scale[LOBE_METAL] = below * metal;
    w.scale[LOBE_METAL_MS] = below * metal;
    let dielectric = below * (1.0 - metal);
    let glass = select(0.0, clamp(p.transmission_weight, 0.0, 1.0), FEATURE_GLASS);
    w.scale[LOBE_GLASS] = dielectric * glass;
    let opaque = dielectric * (1.0 - glass);
    let spec = select(0.0, max(p.specular_weight, 0.0), FEATURE_SPECULAR) * p.specular_color;
    w.scale[LOBE_SPECULAR] = opaque * spec;
    let spec_albedo = fresnel_dielectric(cos_o, max(p.ior, 1.0)) * min(max(spec.r, max(spec.g, spec.b)), 1.0);
    let under_spec = opaque * (1.0 - spec_albedo);
    let walk = subsurface_enabled(p);
    let translucent = FEATURE_TRANSLUCENT && p.thin_walled;
    let sss = select(0.0, clamp(p.subsurface_weight, 0.0, 1.0), walk || translucent);
    w.scale[LOBE_DIFFUSE] = select(vec3<f32>(0.0), under_spec * (1.0 - sss), FEATURE_DIFFUSE);
    w.scale[LOBE_SUBSURFACE] = select(vec3<f32>(0.0), under_spec * (sss * clamp(p.base_weight, 0.0, 1.0)), walk);
    w.scale[LOBE_TRANSLUCENT] = select(vec3<f32>(0.0), under_spec * sss * p.transmission_color, translucent);

    // Selection by estimated albedo toward wo.
    var e: array<f32, LOBE_COUNT>;
    e[LOBE_COAT] = luminance(w.scale[LOBE_COAT]) * coat_albedo;
    e[LOBE_SHEEN] = luminance(w.scale[LOBE_SHEEN]) * min(sheen_e, 1.0);
    let f82 = fresnel_f82(cos_o, p.base_color * p.base_weight, p.specular_color);
    e[LOBE_METAL] = luminance(w.scale[LOBE_METAL] * f82);
    e[LOBE_METAL_MS] = luminance(w.scale[LOBE_METAL_MS] * conductor_ms_albedo(cos_o, p.roughness, p.base_color * p.base_weight));
    e[LOBE_GLASS] = luminance(w.scale[LOBE_GLASS] * max(principled_glass_tint(p), vec3<f32>(0.05)));
    e[LOBE_SPECULAR] = luminance(w.scale[LOBE_SPECULAR]) * fresnel_dielectric(cos_o, max(p.ior, 1.0));
    e[LOBE_DIFFUSE] = luminance(w.scale[LOBE_DIFFUSE] * p.base_color * clamp(p.base_weight, 0.0, 1.0));
    // The walk returns about the base colour (its multiple-scattering albedo) from a
    // thick object, more from a thin one (a dark medium with a long radius is nearly
    // clear): the floor keeps such walks from being rare and heavily weighted.
    e[LOBE_SUBSURFACE] = luminance(w.scale[LOBE_SUBSURFACE]) * max(luminance(p.base_color), 0.2);
    e[LOBE_TRANSLUCENT] = luminance(w.scale[LOBE_TRANSLUCENT]);
    var total = 0.0;
    for (var i = 0u; i < LOBE_COUNT; i++) {
        // Every lobe with any weight keeps some probability, so its pdf is never 0 where
        // its eval is not.
        if (any(w.scale[i] > vec3<f32>(0.0))) {
            e[i] = max(e[i], 1e-3);
        } else {
            e[i] = 0.0;
        }
        total += e[i];
    }
    for (var i = 0u; i < LOBE_COUNT; i++) {
        w.probability[i] = select(0.0, e[i] / total, total > 0.0);
    }
    return w;
}

// Whether the kernel has the code of `lobe`.
fn principled_lobe_compiled(lobe: u32) -> bool {
    switch (lobe) {
        case LOBE_COAT: { return FEATURE_COAT; }
        case LOBE_SHEEN: { return FEATURE_SHEEN; }
        case LOBE_METAL, LOBE_METAL_MS: { return FEATURE_METAL; }
        case LOBE_GLASS: { return FEATURE_GLASS; }
        case LOBE_SPECULAR: { return FEATURE_SPECULAR; }
        case LOBE_SUBSURFACE: { return FEATURE_SUBSURFACE; }
        case LOBE_TRANSLUCENT: { return FEATURE_TRANSLUCENT; }
        default: { return FEATURE_DIFFUSE; }
    }
}

fn principled_lobe_eval(p: Principled, lobe: u32, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (!principled_lobe_compiled(lobe)) {
        return vec3<f32>(0.0);
    }
    let alpha = ggx_alpha(p.roughness, p.anisotropy);
    switch (lobe) {
        case LOBE_COAT: {
            return dielectric_reflection_eval(wo, wi, ggx_alpha(p.coat_roughness, 0.0), p.coat_ior, vec3<f32>(1.0));
        }
        case LOBE_SHEEN: { return sheen_eval(wo, wi, p.sheen_roughness, vec3<f32>(1.0)); }
        case LOBE_METAL: { return conductor_eval(vec3<f32>(wo.xy, abs(wo.z)), vec3<f32>(wi.xy, wi.z * sign(wo.z)), alpha, p.base_color * p.base_weight, p.specular_color); }
        case LOBE_GLASS: {
            let c = dielectric_compensation(wo.z, p.roughness, p.ior, p.thin_walled);
            return c * dielectric_eval(wo, wi, alpha, p.ior, principled_glass_tint(p), p.thin_walled);
        }
        case LOBE_SPECULAR: { return dielectric_reflection_eval(wo, wi, alpha, p.ior, vec3<f32>(1.0)); }
        case LOBE_METAL_MS: {
            return conductor_ms_eval(vec3<f32>(wo.xy, abs(wo.z)), vec3<f32>(wi.xy, wi.z * sign(wo.z)), p.roughness, p.base_color * p.base_weight);
        }
        case LOBE_SUBSURFACE: { return vec3<f32>(subsurface_entry_pdf(wo, wi, subsurface_entry_ior(p))); }
        case LOBE_TRANSLUCENT: { return diffuse_transmission_eval(wo, wi); }
        // The diffuse lobe carries its albedo itself: its energy compensation depends on
        // the albedo non-linearly.
        default: { return energy_preserving_diffuse_eval(wo, wi, p.base_color * clamp(p.base_weight, 0.0, 1.0), p.diffuse_roughness); }
    }
}

fn principled_lobe_pdf(p: Principled, lobe: u32, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if (!principled_lobe_compiled(lobe)) {
        return 0.0;
    }
    let alpha = ggx_alpha(p.roughness, p.anisotropy);
    switch (lobe) {
        case LOBE_COAT: { return dielectric_reflection_pdf(wo, wi, ggx_alpha(p.coat_roughness, 0.0)); }
        case LOBE_SHEEN: { return sheen_pdf(wo, wi); }
        case LOBE_METAL: { return conductor_pdf(vec3<f32>(wo.xy, abs(wo.z)), vec3<f32>(wi.xy, wi.z * sign(wo.z)), alpha); }
        case LOBE_GLASS: { return dielectric_pdf(wo, wi, alpha, p.ior, p.thin_walled); }
        case LOBE_SPECULAR: { return dielectric_reflection_pdf(wo, wi, alpha); }
        case LOBE_SUBSURFACE: { return subsurface_entry_pdf(wo, wi, subsurface_entry_ior(p)); }
        case LOBE_TRANSLUCENT: { return diffuse_transmission_pdf(wo, wi); }
        default: { return diffuse_pdf(wo, wi); }
    }
}

struct PrincipledEval {
    // f · |cos θi|
    value: vec3<f32>,
    pdf: f32,
};

// Only the diffuse lobe has weight: the common matte case skips the layering arithmetic
// (which is exact here too, only slower).
fn principled_is_diffuse(p: Principled) -> bool {
    if (!FEATURE_COAT && !FEATURE_SHEEN && !FEATURE_METAL && !FEATURE_GLASS && !FEATURE_SPECULAR
        && !FEATURE_SUBSURFACE && !FEATURE_TRANSLUCENT) {
        return true;
    }
    return p.metallic == 0.0 && p.specular_weight == 0.0 && p.coat_weight == 0.0
        && p.sheen_weight == 0.0 && p.transmission_weight == 0.0
        && (p.subsurface_weight == 0.0 || (!FEATURE_SUBSURFACE && !FEATURE_TRANSLUCENT));
}

// Sum over the non-delta lobes (delta lobes are 0 for every direction given). The
// subsurface lobe is left out: light reaches the surface through it only by a random
// walk, never straight from a light, and a direction it samples carries its own weight.
fn principled_eval(p: Principled, wo: vec3<f32>, wi: vec3<f32>) -> PrincipledEval {
    if (principled_is_diffuse(p)) {
        return PrincipledEval(
            energy_preserving_diffuse_eval(wo, wi, p.base_color * clamp(p.base_weight, 0.0, 1.0), p.diffuse_roughness),
            diffuse_pdf(wo, wi),
        );
    }
    let w = principled_weights(p, wo);
    var value = vec3<f32>(0.0);
    var pdf = 0.0;
    for (var i = 0u; i < LOBE_COUNT; i++) {
        if (w.probability[i] > 0.0 && i != LOBE_SUBSURFACE) {
            value += w.scale[i] * principled_lobe_eval(p, i, wo, wi);
            pdf += w.probability[i] * principled_lobe_pdf(p, i, wo, wi);
        }
    }
    return PrincipledEval(value, pdf);
}

fn principled_sample(p: Principled, wo: vec3<f32>, uc: f32, ul: f32, u: vec2<f32>) -> BsdfSample {
    principled_sampled_lobe = LOBE_DIFFUSE;
    if (principled_is_diffuse(p)) {
        let d = diffuse_sample(wo, vec3<f32>(1.0), u);
        if (d.pdf <= 0.0) {
            return no_sample();
        }
        let f = energy_preserving_diffuse_eval(wo, d.wi, p.base_color * clamp(p.base_weight, 0.0, 1.0), p.diffuse_roughness);
        return BsdfSample(d.wi, f / d.pdf, d.pdf, false, true);
    }
    let w = principled_weights(p, wo);
    // Pick a lobe by its probability.
    var lobe = LOBE_DIFFUSE;
    var acc = 0.0;
    var found = false;
    for (var i = 0u; i < LOBE_COUNT; i++) {
        acc += w.probability[i];
        if (!found && w.probability[i] > 0.0 && uc < acc) {
            lobe = i;
            found = true;
        }
    }
    if (!found) {
        // Rounding left uc above the last partial sum: take the last lobe in use.
        for (var i = 0u; i < LOBE_COUNT; i++) {
            if (w.probability[i] > 0.0) {
                lobe = i;
                found = true;
            }
        }
    }
    if (!found || !principled_lobe_compiled(lobe)) {
        return no_sample();
    }
    principled_sampled_lobe = lobe;
    let alpha = ggx_alpha(p.roughness, p.anisotropy);
    var s: BsdfSample;
    switch (lobe) {
        case LOBE_COAT: {
            s = dielectric_reflection_sample(wo, ggx_alpha(p.coat_roughness, 0.0), p.coat_ior, vec3<f32>(1.0), u);
        }
        case LOBE_SHEEN: { s = sheen_sample(wo, p.sheen_roughness, vec3<f32>(1.0), u); }
        case LOBE_METAL: {
            let side = select(-1.0, 1.0, wo.z >= 0.0);
            s = conductor_sample(vec3<f32>(wo.xy, abs(wo.z)), alpha, p.base_color * p.base_weight, p.specular_color, u);
            s.wi.z *= side;
        }
        case LOBE_GLASS: { s = dielectric_sample(wo, alpha, p.ior, principled_glass_tint(p), p.thin_walled, ul, u); }
        case LOBE_SPECULAR: { s = dielectric_reflection_sample(wo, alpha, p.ior, vec3<f32>(1.0), u); }
        case LOBE_SUBSURFACE: {
            let eta = subsurface_entry_ior(p);
            let wi = subsurface_entry_sample(wo, eta, ul, u);
            s = BsdfSample(wi, vec3<f32>(1.0), subsurface_entry_pdf(wo, wi, eta), false, wi.z != 0.0);
        }
        case LOBE_TRANSLUCENT: {
            let wi = diffuse_transmission_sample(wo, u);
            s = BsdfSample(wi, vec3<f32>(1.0), diffuse_transmission_pdf(wo, wi), false, wi.z != 0.0);
        }
        default: {
            let d = diffuse_sample(wo, vec3<f32>(1.0), u);
            s = BsdfSample(d.wi, d.weight, d.pdf, false, d.pdf > 0.0);
        }
    }
    if (!s.valid) {
        return s;
    }
    if (s.delta) {
        // Only this lobe can produce this direction: its weight over its choice odds.
        s.weight = w.scale[lobe] * s.weight / w.probability[lobe];
        s.pdf *= w.probability[lobe];
        return s;
    }
    if (w.probability[LOBE_SUBSURFACE] > 0.0 && s.wi.z * wo.z < 0.0) {
        // Into the object, by the subsurface lobe or by rough glass: the two go on
        // differently (a random walk, a straight path), so each keeps its own weight.
        let pdf = w.probability[lobe] * principled_lobe_pdf(p, lobe, wo, s.wi);
        if (!(pdf > 0.0)) {
            return no_sample();
        }
        return BsdfSample(s.wi, w.scale[lobe] * principled_lobe_eval(p, lobe, wo, s.wi) / pdf, pdf, false, true);
    }
    // A direction several lobes can produce: the mixture's value over its density.
    let e = principled_eval(p, wo, s.wi);
    if (e.pdf <= 0.0) {
        return no_sample();
    }
    return BsdfSample(s.wi, e.value / e.pdf, e.pdf, false, true);
}

// Beer–Lambert extinction coefficient inside a transmissive principled material.
fn principled_extinction(p: Principled) -> vec3<f32> {
    if (p.transmission_depth <= 0.0 || p.thin_walled) {
        return vec3<f32>(0.0);
    }
    return -log(clamp(p.transmission_color, vec3<f32>(1e-6), vec3<f32>(1.0))) / p.transmission_depth;
}
