// Point (optionally spherical), spot and distant lights: sampled by next-event estimation
// only (BSDF rays do not hit them), so their samples carry MIS weight 1. Delta lights
// (zero radius or angular size) return pdf = the pick probability alone.

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

// The light picked by u in [0, 1) among the analytic lights (u counts from where the
// environment's and the triangles' pick probabilities end).
fn pick_analytic_light(u: f32) -> u32 {
    let count = u32(params.light_totals.z);
    for (var i = 0u; i < count; i++) {
        if (u < analytic_lights[i].shape.w) {
            return i;
        }
    }
    return count - 1u;
}

fn sample_analytic_light(index: u32, p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let l = analytic_lights[index];
    let kind = u32(l.position.w);
    let pick = l.intensity.w;
    let none = LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false);
    if (kind == 2u) {
        let to_light = -normalize(l.position.xyz);
        let one_minus_cos = l.axis.w;
        if (one_minus_cos <= 0.0) {
            return LightSample(to_light, 3.0e38, l.intensity.rgb, pick, false);
        }
        let wi = normalize(frame_to_world(frame_from_normal(to_light), sample_cone(u, one_minus_cos)));
        // Irradiance E = L ∫cos dω = L π sin²θ over the disk.
        let cos_max = 1.0 - one_minus_cos;
        let radiance = l.intensity.rgb / (PI * (1.0 - cos_max * cos_max));
        return LightSample(wi, 3.0e38, radiance, pick / (2.0 * PI * one_minus_cos), false);
    }
    let to = l.position.xyz - p;
    let d2 = dot(to, to);
    if (d2 == 0.0) {
        return none;
    }
    let d = sqrt(d2);
    var falloff = 1.0;
    if (kind == 1u) {
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
    return LightSample(wi, max(dist, 0.0), radiance, pick / (2.0 * PI * one_minus_cos), false);
}
