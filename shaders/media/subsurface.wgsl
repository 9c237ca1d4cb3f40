// Random-walk subsurface scattering, as Cycles' Random Walk does it: light that the
// principled surface's subsurface lobe lets in walks through a homogeneous medium inside
// the object (free flights, Henyey–Greenstein scattering) until it reaches the surface
// again, where it leaves by a Lambertian exit. The medium comes from the base colour
// (the albedo the walk should have) and the radius (mean free path per channel) by the
// inversion of Chiang, Kutz & Burley, "Practical and Controllable Subsurface Scattering
// for Production Path Tracing" (SIGGRAPH 2016 talk):
//
//   single-scattering albedo  α = 1 - exp(A (-5.09406 + A (2.61188 - 4.31805 A)))
//   extinction                σt = 1 / (d (1.9 - A + 3.5 (A - 0.8)²))
//
// for multiple-scattering albedo A and mean free path d = radius × scale. Kiln normalises
// α so that A = 1 gives α = 1 exactly (the fit gives 0.99889): a white material then loses
// no energy (the furnace test). With anisotropy g the scattering coefficient grows by
// 1 / (1 - g) (similarity theory), so the reduced coefficient (1 - g) σs, which sets the
// diffuse look, stays what the radius asks for.
//
// Chromatic media (a different σt per channel) are sampled with one-sample MIS over the
// channels (the balance heuristic; pbrt-v4 §14.2.2, Cycles' volume_sample_channel): the
// channel whose free flight is drawn is picked in proportion to throughput × albedo, and
// the weight divides by the mixture of the channels' densities, so no channel's weight
// can grow without bound.

// A walk that has not left the object after this many scattering events ends (its
// energy is lost, as in Cycles, which uses the same bound).
const SUBSURFACE_MAX_STEPS: u32 = 256u;

// A homogeneous medium: extinction per scene unit and single-scattering albedo per
// channel, and the phase function's g.
struct Medium {
    sigma_t: vec3<f32>,
    albedo: vec3<f32>,
    g: f32,
};

// Single-scattering albedo α whose random walk has the multiple-scattering albedo `a`.
fn subsurface_single_albedo(a: vec3<f32>) -> vec3<f32> {
    let fit = 1.0 - exp(a * (-5.09406 + a * (2.61188 - 4.31805 * a)));
    let at_one = 1.0 - exp(-5.09406 + 2.61188 - 4.31805);
    return select(min(fit / at_one, vec3<f32>(1.0)), vec3<f32>(1.0), a >= vec3<f32>(1.0));
}

// The medium under a principled surface with subsurface weight.
fn subsurface_medium(p: Principled) -> Medium {
    let a = clamp(p.base_color, vec3<f32>(0.0), vec3<f32>(1.0));
    let g = clamp(p.subsurface_anisotropy, 0.0, HG_MAX_G);
    // Radii are non-negative; a zero radius turns the lobe off (principled_weights), so
    // this bound only keeps a tiny one finite.
    let d = max(p.subsurface_radius * p.subsurface_scale, vec3<f32>(1e-12));
    let alpha = subsurface_single_albedo(a);
    let s = 1.9 - a + 3.5 * (a - 0.8) * (a - 0.8);
    let sigma_t = 1.0 / (d * s);
    let sigma_s = alpha * sigma_t / (1.0 - g);
    let sigma_a = (1.0 - alpha) * sigma_t;
    let total = sigma_s + sigma_a;
    return Medium(total, sigma_s / total, g);
}

// The direction a walk enters the object by, as Cycles' Random Walk enters: half the time
// a cosine-weighted direction into the surface, half the time the view direction refracted
// through a rough interface (GGX α = 1) of the subsurface IOR. A refraction through a
// steep microfacet can point back out of the surface; it is mirrored into the object, and
// the density counts both directions that land on the same one. The entry carries no
// Fresnel weight (the specular layer above took its reflection already) and no microfacet
// shadowing (as in Cycles): its value is its density, so every sample has weight 1 and
// the entry only shapes where the walk starts heading. wo and wi on opposite sides; a wo
// below the surface enters upward, mirrored.
const SUBSURFACE_ENTRY_ALPHA: vec2<f32> = vec2<f32>(1.0, 1.0);

fn subsurface_entry_ior(p: Principled) -> f32 {
    return clamp(p.subsurface_ior, 1.01, 3.8);
}

// Density of refracting wo (above) into wi through a microfacet of the entry interface,
// wi on either side (Walter et al. 2007, eq. 17).
fn subsurface_refraction_pdf(wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> f32 {
    let h = -(wo + eta * wi);
    if (!(dot(h, h) > 0.0)) {
        return 0.0;
    }
    let m = normalize(h);
    let cos_om = dot(wo, m);
    let cos_im = dot(wi, m);
    if (m.z <= 0.0 || cos_om <= 0.0 || cos_im >= 0.0) {
        return 0.0;
    }
    let denom = cos_im + cos_om / eta;
    return ggx_vndf_pdf(wo, m, SUBSURFACE_ENTRY_ALPHA) * abs(cos_im) / (denom * denom);
}

fn subsurface_entry_pdf(wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> f32 {
    if (wo.z * wi.z >= 0.0) {
        return 0.0;
    }
    // Mirrored so that wo is above and wi below.
    let s = select(-1.0, 1.0, wo.z > 0.0);
    let o = vec3<f32>(wo.xy, s * wo.z);
    let i = vec3<f32>(wi.xy, s * wi.z);
    let folded = vec3<f32>(i.xy, -i.z);
    let refraction = subsurface_refraction_pdf(o, i, eta) + subsurface_refraction_pdf(o, folded, eta);
    return 0.5 * abs(wi.z) * INV_PI + 0.5 * refraction;
}

fn subsurface_entry_sample(wo: vec3<f32>, eta: f32, uc: f32, u: vec2<f32>) -> vec3<f32> {
    let s = select(-1.0, 1.0, wo.z > 0.0);
    var wi: vec3<f32>;
    if (uc < 0.5) {
        wi = sample_cosine_hemisphere(u);
    } else {
        let o = vec3<f32>(wo.xy, s * wo.z);
        let m = ggx_sample_vndf(o, SUBSURFACE_ENTRY_ALPHA, u);
        // From outside into a denser medium (eta > 1): never total internal reflection.
        let rf = refract_dir(o, m, eta);
        wi = select(vec3<f32>(0.0, 0.0, 1.0), rf.wt, rf.ok);
    }
    // Below the surface, in the mirrored frame, then back.
    return vec3<f32>(wi.xy, -s * abs(wi.z));
}

// Whether the subsurface lobe has any weight: a walk needs a radius.
fn subsurface_enabled(p: Principled) -> bool {
    let d = p.subsurface_radius * p.subsurface_scale;
    return FEATURE_SUBSURFACE && p.subsurface_weight > 0.0 && !p.thin_walled
        && max(d.x, max(d.y, d.z)) > 0.0;
}

struct FreeFlight {
    // Scattered inside the medium (else it reached t_max, the boundary).
    scattered: bool,
    t: f32,
    // What the throughput is multiplied by.
    weight: vec3<f32>,
    // False when no channel can reach t_max (an unbounded medium): the path ends.
    valid: bool,
};

// One free flight through `m` toward a boundary `t_max` away, for a path carrying
// `throughput`: scattering at distance t with density Σ p_c σt_c e^(-σt_c t), or the
// boundary with probability Σ p_c e^(-σt_c t_max), p_c the channel probabilities.
fn medium_free_flight(m: Medium, throughput: vec3<f32>, t_max: f32, u_channel: f32, u_distance: f32) -> FreeFlight {
    var w = throughput * m.albedo;
    if (!(w.x + w.y + w.z > 0.0)) {
        w = max(throughput, vec3<f32>(0.0));
    }
    if (!(w.x + w.y + w.z > 0.0)) {
        w = vec3<f32>(1.0);
    }
    let probs = w / (w.x + w.y + w.z);
    var sigma = m.sigma_t.z;
    if (u_channel < probs.x) {
        sigma = m.sigma_t.x;
    } else if (u_channel < probs.x + probs.y) {
        sigma = m.sigma_t.y;
    }
    let t = select(3.0e38, -log(1.0 - u_distance) / sigma, sigma > 0.0);
    if (t < t_max) {
        let tr = exp(-m.sigma_t * t);
        let pdf = dot(probs, m.sigma_t * tr);
        if (!(pdf > 0.0)) {
            return FreeFlight(true, t, vec3<f32>(0.0), false);
        }
        return FreeFlight(true, t, m.sigma_t * m.albedo * tr / pdf, true);
    }
    let tr = exp(-m.sigma_t * t_max);
    let p = dot(probs, tr);
    if (!(p > 0.0)) {
        return FreeFlight(false, t_max, vec3<f32>(0.0), false);
    }
    return FreeFlight(false, t_max, tr / p, true);
}
