// Glass and other dielectric interfaces: exact Fresnel, smooth or GGX-rough reflection and
// refraction (Walter et al. 2007, "Microfacet Models for Refraction through Rough
// Surfaces", in the form of pbrt-v4's DielectricBxDF). Which side the light is on comes
// from the sign of cos θ, never from a flag: wo.z > 0 is outside, wo.z < 0 inside, and
// `eta` is the IOR inside over outside. Total internal reflection falls out of Fresnel.
//
// Thin-walled (a soap film, a window pane modelled as one surface): light passes through
// without bending, the two interfaces' reflections summed incoherently; a rough thin wall
// transmits the reflection lobe mirrored through the surface.
//
// Transmitted radiance is divided by etap² (radiance, not importance, is transported).

// Within 1e-3 of 1 the rough refraction lobe becomes a spike no f32 sampling resolves (its
// Jacobian grows as 1/(eta - 1)^2) around a direction bent by at most a few milliradians:
// such an interface is treated as smooth, with exact Fresnel and Snell refraction.
fn dielectric_index_matched(eta: f32) -> bool {
    return abs(eta - 1.0) < 1e-3;
}

fn same_hemisphere(a: vec3<f32>, b: vec3<f32>) -> bool {
    return a.z * b.z > 0.0;
}

// Reflectance and transmittance of a thin slab with two identical interfaces.
fn thin_slab_reflectance(r: f32) -> f32 {
    if (r >= 1.0) {
        return 1.0;
    }
    let t = 1.0 - r;
    return r + t * t * r / (1.0 - r * r);
}

// The generalized half vector of a reflection or refraction from wo to wi (Walter et al.
// 2007, eq. 16), turned up; not ok where no microfacet seen from the front of both
// directions connects them.
struct HalfVector {
    ok: bool,
    m: vec3<f32>,
    etap: f32,
    reflect: bool,
};

fn dielectric_half_vector(wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> HalfVector {
    let fail = HalfVector(false, vec3<f32>(0.0, 0.0, 1.0), 1.0, true);
    let reflect = wo.z * wi.z > 0.0;
    var etap = 1.0;
    if (!reflect) {
        etap = select(1.0 / eta, eta, wo.z > 0.0);
    }
    var m = wi * etap + wo;
    if (dot(m, m) == 0.0) {
        return fail;
    }
    m = normalize(m);
    if (m.z < 0.0) {
        m = -m;
    }
    // Microfacets seen from behind contribute nothing.
    if (dot(m, wi) * wi.z < 0.0 || dot(m, wo) * wo.z < 0.0) {
        return fail;
    }
    return HalfVector(true, m, etap, reflect);
}

fn dielectric_eval(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>, eta: f32, tint: vec3<f32>, thin: bool) -> vec3<f32> {
    if (dielectric_index_matched(eta) || ggx_is_smooth(alpha) || wo.z == 0.0 || wi.z == 0.0) {
        return vec3<f32>(0.0);
    }
    if (thin) {
        // Both lobes are the reflection lobe, the transmitted one mirrored below.
        let wr = vec3<f32>(wi.xy, abs(wi.z));
        let wou = vec3<f32>(wo.xy, abs(wo.z));
        let m = normalize(wou + wr);
        let r = thin_slab_reflectance(fresnel_dielectric(dot(wou, m), eta));
        let f = ggx_d(m, alpha) * ggx_g2(wou, wr, alpha) / (4.0 * wou.z);
        if (same_hemisphere(wo, wi)) {
            return vec3<f32>(f * r);
        }
        return tint * (f * (1.0 - r));
    }
    let cos_o = wo.z;
    let h = dielectric_half_vector(wo, wi, eta);
    if (!h.ok) {
        return vec3<f32>(0.0);
    }
    let m = h.m;
    let etap = h.etap;
    let reflect = h.reflect;
    let f = fresnel_dielectric(dot(wo, m), eta);
    let d = ggx_d(m, alpha);
    let g = ggx_g2(wo, wi, alpha);
    if (reflect) {
        return vec3<f32>(d * g * f / (4.0 * abs(cos_o)));
    }
    let denom = dot(wi, m) + dot(wo, m) / etap;
    let ft = d * (1.0 - f) * g * abs(dot(wi, m) * dot(wo, m) / (denom * denom * cos_o));
    return tint * (ft / (etap * etap));
}

fn dielectric_pdf(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>, eta: f32, thin: bool) -> f32 {
    if (dielectric_index_matched(eta) || ggx_is_smooth(alpha) || wo.z == 0.0 || wi.z == 0.0) {
        return 0.0;
    }
    if (thin) {
        let wr = vec3<f32>(wi.xy, abs(wi.z));
        let wou = vec3<f32>(wo.xy, abs(wo.z));
        let m = normalize(wou + wr);
        let r = thin_slab_reflectance(fresnel_dielectric(dot(wou, m), eta));
        let pdf = ggx_vndf_pdf(wou, m, alpha) / (4.0 * dot(wou, m));
        return pdf * select(1.0 - r, r, same_hemisphere(wo, wi));
    }
    let h = dielectric_half_vector(wo, wi, eta);
    if (!h.ok) {
        return 0.0;
    }
    let m = h.m;
    let etap = h.etap;
    let reflect = h.reflect;
    let r = fresnel_dielectric(dot(wo, m), eta);
    let vndf = ggx_vndf_pdf(wo, m, alpha);
    if (reflect) {
        return vndf / (4.0 * abs(dot(wo, m))) * r;
    }
    let denom = dot(wi, m) + dot(wo, m) / etap;
    return vndf * abs(dot(wi, m)) / (denom * denom) * (1.0 - r);
}

// `uc` picks reflection or transmission; `u` samples the microfacet normal.
fn dielectric_sample(wo: vec3<f32>, alpha: vec2<f32>, eta: f32, tint: vec3<f32>, thin: bool, uc: f32, u: vec2<f32>) -> BsdfSample {
    if (wo.z == 0.0) {
        return no_sample();
    }
    let n = vec3<f32>(0.0, 0.0, 1.0);
    if (dielectric_index_matched(eta) || ggx_is_smooth(alpha)) {
        var r = fresnel_dielectric(wo.z, eta);
        if (thin) {
            // A thin wall has no inside: both faces see air on the far side.
            r = thin_slab_reflectance(fresnel_dielectric(abs(wo.z), eta));
        }
        if (uc < r) {
            return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), vec3<f32>(1.0), r, true, true);
        }
        if (thin || eta == 1.0) {
            return BsdfSample(-wo, tint, 1.0 - r, true, true);
        }
        let rf = refract_dir(wo, n, eta);
        if (!rf.ok) {
            return no_sample();
        }
        return BsdfSample(rf.wt, tint / (rf.etap * rf.etap), 1.0 - r, true, true);
    }
    if (thin) {
        let wou = vec3<f32>(wo.xy, abs(wo.z));
        let m = ggx_sample_vndf(wou, alpha, u);
        var wr = reflect(-wou, m);
        if (wr.z <= 0.0) {
            return no_sample();
        }
        let r = thin_slab_reflectance(fresnel_dielectric(dot(wou, m), eta));
        let pdf_m = ggx_vndf_pdf(wou, m, alpha) / (4.0 * dot(wou, m));
        let g = ggx_g2(wou, wr, alpha) / ggx_g1(wou, alpha);
        let side = select(-1.0, 1.0, wo.z > 0.0);
        if (uc < r) {
            return BsdfSample(vec3<f32>(wr.xy, side * wr.z), vec3<f32>(g), pdf_m * r, false, true);
        }
        return BsdfSample(vec3<f32>(wr.xy, -side * wr.z), tint * g, pdf_m * (1.0 - r), false, true);
    }
    let m = ggx_sample_vndf(wo, alpha, u);
    let r = fresnel_dielectric(dot(wo, m), eta);
    let vndf = ggx_vndf_pdf(wo, m, alpha);
    if (uc < r) {
        let wi = reflect(-wo, m);
        if (!same_hemisphere(wo, wi)) {
            return no_sample();
        }
        let pdf = vndf / (4.0 * abs(dot(wo, m))) * r;
        let f = ggx_d(m, alpha) * ggx_g2(wo, wi, alpha) * r / (4.0 * abs(wo.z));
        return BsdfSample(wi, vec3<f32>(f / pdf), pdf, false, pdf > 0.0);
    }
    let rf = refract_dir(wo, m, eta);
    if (!rf.ok || same_hemisphere(wo, rf.wt) || rf.wt.z == 0.0) {
        return no_sample();
    }
    let wi = rf.wt;
    let denom = dot(wi, m) + dot(wo, m) / rf.etap;
    let pdf = vndf * abs(dot(wi, m)) / (denom * denom) * (1.0 - r);
    let ft = ggx_d(m, alpha) * (1.0 - r) * ggx_g2(wo, wi, alpha)
        * abs(dot(wi, m) * dot(wo, m) / (denom * denom * wo.z)) / (rf.etap * rf.etap);
    return BsdfSample(wi, tint * (ft / pdf), pdf, false, pdf > 0.0);
}

// Reflection off a dielectric interface alone (the specular layer over an opaque base,
// and coats): the reflection part of the rough dielectric, always sampled, scaled by
// `scale` (specular weight × colour). Seen from below, the frame is mirrored up: an opaque
// base is two-sided.
fn dielectric_reflection_eval(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>, eta: f32, scale: vec3<f32>) -> vec3<f32> {
    if (wo.z * wi.z <= 0.0 || ggx_is_smooth(alpha)) {
        return vec3<f32>(0.0);
    }
    let s = select(-1.0, 1.0, wo.z > 0.0);
    let o = vec3<f32>(wo.xy, wo.z * s);
    let i = vec3<f32>(wi.xy, wi.z * s);
    let m = normalize(o + i);
    let f = fresnel_dielectric(dot(o, m), eta);
    return scale * (f * ggx_d(m, alpha) * ggx_g2(o, i, alpha) / (4.0 * o.z));
}

fn dielectric_reflection_pdf(wo: vec3<f32>, wi: vec3<f32>, alpha: vec2<f32>) -> f32 {
    if (wo.z * wi.z <= 0.0 || ggx_is_smooth(alpha)) {
        return 0.0;
    }
    let s = select(-1.0, 1.0, wo.z > 0.0);
    let o = vec3<f32>(wo.xy, wo.z * s);
    let i = vec3<f32>(wi.xy, wi.z * s);
    let m = normalize(o + i);
    return ggx_vndf_pdf(o, m, alpha) / (4.0 * dot(o, m));
}

fn dielectric_reflection_sample(wo: vec3<f32>, alpha: vec2<f32>, eta: f32, scale: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (wo.z == 0.0) {
        return no_sample();
    }
    let s = select(-1.0, 1.0, wo.z > 0.0);
    let o = vec3<f32>(wo.xy, wo.z * s);
    if (ggx_is_smooth(alpha)) {
        let f = fresnel_dielectric(o.z, eta);
        return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), scale * f, 1.0, true, true);
    }
    let m = ggx_sample_vndf(o, alpha, u);
    let i = reflect(-o, m);
    if (i.z <= 0.0) {
        return no_sample();
    }
    let pdf = ggx_vndf_pdf(o, m, alpha) / (4.0 * dot(o, m));
    let weight = scale * (fresnel_dielectric(dot(o, m), eta) * ggx_g2(o, i, alpha) / ggx_g1(o, alpha));
    return BsdfSample(vec3<f32>(i.xy, i.z * s), weight, pdf, false, pdf > 0.0);
}
