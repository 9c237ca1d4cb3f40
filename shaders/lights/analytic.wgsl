// Point (optionally spherical), spot and distant lights. Delta lights (zero radius or
// angular size) can only be reached by next-event estimation: their samples return pdf =
// the pick probability alone and MIS weight 1. Spheres (point and spot lights with a
// radius) and sun disks (distant lights with an angular diameter) are also hit by BSDF
// rays (`analytic_light_hit`), so both strategies are weighted by MIS. A sphere light is
// an opaque emitter to the rays that hit it but, as in Cycles, casts no shadow.

// Uniform direction in the cone around +z whose half-angle has 1 - cos = one_minus_cos
// (passed as such to keep tiny cones, like the sun's, accurate).
fn sample_cone(u: vec2<f32>, one_minus_cos: f32) -> vec3<f32> {
    let cos_t = 1.0 - u.x * one_minus_cos;
    let sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(cos(phi) * sin_t, sin(phi) * sin_t, cos_t);
}

fn spot_falloff(cos_axis: f32, cos_outer: f32, cos_inner: f32) -> f32 {
    if (cos_inner <= cos_outer) {
        return select(0.0, 1.0, cos_axis >= cos_outer);
    }
    return smoothstep(cos_outer, cos_inner, cos_axis);
}

// The light picked by u in [0, 1) among the analytic lights at infinity (distant lights)
// or the local ones; u counts from where the environment's or the triangles' pick
// probability ends. NO_LIGHT where that side has none.
fn pick_analytic_light(u: f32, at_infinity: bool) -> u32 {
    let count = params.analytic_light_count;
    var last = NO_LIGHT;
    for (var i = 0u; i < count; i++) {
        let l = analytic_lights[i];
        if ((l.kind == LIGHT_DISTANT) != at_infinity || l.intensity.w <= 0.0) {
            continue;
        }
        last = i;
        if (u < l.shape.w) {
            return i;
        }
    }
    return last;
}

const NO_LIGHT: u32 = 0xffffffffu;

// A sample of analytic light `index` (NO_LIGHT: none); its pdf has the light's pick
// probability among its side's lights in it.
fn sample_analytic_light(index: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let none = LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false);
    if (index == NO_LIGHT) {
        return none;
    }
    let l = analytic_lights[index];
    let pick = l.intensity.w;
    if (l.kind == LIGHT_DISTANT) {
        let to_light = -normalize(l.position);
        let one_minus_cos = l.axis.w;
        if (one_minus_cos <= 0.0) {
            return LightSample(to_light, 3.0e38, l.intensity.rgb, pick, false);
        }
        let wi = normalize(frame_to_world(frame_from_normal(to_light), sample_cone(u, one_minus_cos)));
        // Irradiance E = L ∫cos dω = L π sin²θ over the disk.
        let cos_max = 1.0 - one_minus_cos;
        let radiance = l.intensity.rgb / (PI * (1.0 - cos_max * cos_max));
        return LightSample(wi, 3.0e38, radiance, pick / (2.0 * PI * one_minus_cos), true);
    }
    let to = l.position - p;
    let d2 = dot(to, to);
    if (d2 == 0.0) {
        return none;
    }
    let d = sqrt(d2);
    var falloff = 1.0;
    if (l.kind == LIGHT_SPOT) {
        falloff = spot_falloff(dot(-to / d, l.axis.xyz), l.shape.x, l.shape.y);
        if (falloff <= 0.0) {
            return none;
        }
    }
    let r = l.axis.w;
    if (r <= 0.0 || d <= r) {
        return LightSample(to / d, d, l.intensity.rgb * falloff / d2, pick, false);
    }
    // A sphere: sample the cone it subtends; its radiance is I / (π r²).
    let sin2_max = r * r / d2;
    let cos_max = sqrt(max(0.0, 1.0 - sin2_max));
    let one_minus_cos = sin2_max / (1.0 + cos_max);
    let wi = normalize(frame_to_world(frame_from_normal(to / d), sample_cone(u, one_minus_cos)));
    let b = dot(to, wi);
    let dist = b - sqrt(max(0.0, r * r - (d2 - b * b)));
    let radiance = l.intensity.rgb * falloff / (PI * r * r);
    return LightSample(wi, max(dist, 0.0), radiance, pick / (2.0 * PI * one_minus_cos), true);
}

// What a ray from `o` along unit `d` sees of the analytic lights before `t_max`: the
// nearest sphere light, or where the ray escapes (t_max = 3e38), the sun disks it points
// into. `pdf` is next-event estimation's solid-angle density for that direction (pick
// probability included: `p_infinite` is infinite_light_pick's at the ray's vertex), for
// the MIS weight.
struct AnalyticHit {
    hit: bool,
    // Distance to the sphere hit; 3e38 for sun disks, which block nothing.
    t: f32,
    radiance: vec3<f32>,
    pdf: f32,
};

fn analytic_light_hit(o: vec3<f32>, d: vec3<f32>, t_max: f32, p_infinite: f32) -> AnalyticHit {
    var result = AnalyticHit(false, t_max, vec3<f32>(0.0), 0.0);
    let count = params.analytic_light_count;
    for (var i = 0u; i < count; i++) {
        let l = analytic_lights[i];
        let pick = l.intensity.w * select(1.0 - p_infinite, p_infinite, l.kind == LIGHT_DISTANT);
        if (l.kind == LIGHT_DISTANT) {
            let one_minus_cos = l.axis.w;
            if (one_minus_cos <= 0.0 || result.t < 3.0e38) {
                continue;
            }
            if (1.0 - dot(d, -normalize(l.position)) <= one_minus_cos) {
                let cos_max = 1.0 - one_minus_cos;
                result.hit = true;
                result.radiance += l.intensity.rgb / (PI * (1.0 - cos_max * cos_max));
                result.pdf += pick / (2.0 * PI * one_minus_cos);
            }
            continue;
        }
        let r = l.axis.w;
        if (r <= 0.0) {
            continue;
        }
        // Ray–sphere intersection in the form of Haines et al. 2019 ("Precision
        // Improvements for Ray/Sphere Intersection"): the discriminant from the distance
        // of the centre to the ray, not from b² - c, which cancels catastrophically.
        let f = o - l.position;
        let d2 = dot(f, f);
        if (d2 <= r * r) {
            // Inside the sphere: next-event estimation treats it as a point light too.
            continue;
        }
        let b = -dot(f, d);
        let perp = f + b * d;
        let disc = r * r - dot(perp, perp);
        if (b <= 0.0 || disc < 0.0) {
            continue;
        }
        let t = b - sqrt(disc);
        if (t <= 0.0 || t >= result.t) {
            continue;
        }
        var falloff = 1.0;
        if (l.kind == LIGHT_SPOT) {
            falloff = spot_falloff(dot(normalize(f), l.axis.xyz), l.shape.x, l.shape.y);
        }
        let sin2_max = r * r / d2;
        let cos_max = sqrt(max(0.0, 1.0 - sin2_max));
        let one_minus_cos = sin2_max / (1.0 + cos_max);
        // The nearest sphere replaces anything found so far (spheres are opaque), except
        // sun disks, which only a ray that hits no sphere can reach.
        result = AnalyticHit(true, t, l.intensity.rgb * falloff / (PI * r * r), pick / (2.0 * PI * one_minus_cos));
    }
    return result;
}
