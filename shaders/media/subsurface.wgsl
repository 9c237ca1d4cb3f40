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
