// Which light next-event estimation samples, and with what density: the split between
// the lights at infinity and the local ones at each shading point, then the light on that
// side by the host's power estimates (src/render/light_distribution.rs). The integrator
// weighs a BSDF ray that reaches a light by the same densities (environment_light_pdf,
// triangle_light_pdf, analytic_light_hit's pdf); tests/lights.rs checks that they agree
// with sample_light's.

// The probability that a light sample from `p` is of the lights at infinity (the
// environment, distant lights) rather than the local ones (emissive triangles, point and
// spot lights), as the root of a light tree splits it: the irradiance the lights at
// infinity give a surface facing them against the local lights' summed intensity over
// the squared distance to their bounds (src/render/light_distribution.rs). Each side keeps
// a tenth at least, so that neither is starved where the estimate is wrong (a sky behind
// walls, a lamp facing away).
fn infinite_light_pick(p: vec3<f32>) -> f32 {
    // A kernel without lights at infinity: the host gives them no share either
    // (light_split.x is 0).
    if (!FEATURE_INFINITE_LIGHTS) {
        return 0.0;
    }
    let at_infinity = params.light_split.x;
    let local = params.light_split.y;
    if (local <= 0.0) {
        return select(0.0, 1.0, at_infinity > 0.0);
    }
    if (at_infinity <= 0.0) {
        return 0.0;
    }
    let to = p - params.local_lights.xyz;
    let near = local / (dot(to, to) + params.local_lights.w);
    return clamp(at_infinity / (at_infinity + near), 0.1, 0.9);
}

// Next-event estimation's density for the environment in direction `dir` seen from
// `vertex` (pick probabilities included), for the MIS weight of a BSDF ray that escapes.
fn environment_light_pdf(vertex: vec3<f32>, dir: vec3<f32>) -> f32 {
    return infinite_light_pick(vertex) * params.environment.w * environment_pdf(dir);
}

// Next-event estimation's density for a point of an emissive triangle of buffer emission
// `emission` at distance `dist` from `vertex`, seen at `cos_light` to its normal.
fn triangle_light_pdf(vertex: vec3<f32>, emission: vec3<f32>, dist: f32, cos_light: f32) -> f32 {
    let pick = (1.0 - infinite_light_pick(vertex)) * params.triangle_pick;
    return pick * light_triangle_pdf(emission, dist, cos_light);
}

// What the last sample_light picked (for tests: shaders/tests/light_probe.wgsl).
const LIGHT_SAMPLED_ENVIRONMENT: u32 = 0u;
const LIGHT_SAMPLED_TRIANGLE: u32 = 1u;
const LIGHT_SAMPLED_ANALYTIC: u32 = 2u;
var<private> light_sampled: u32;

// The largest f32 below 1: where a rescaled uniform number must stay.
const ONE_MINUS_EPSILON: f32 = 0.99999994;

// One light sample seen from `p`: first the lights at infinity or the local ones
// (infinite_light_pick), then on that side the environment, an emissive triangle or an
// analytic light, each picked with the probability the host estimated from its power. A
// pdf of 0 means no light.
fn sample_light(p: vec3<f32>) -> LightSample {
    let p_infinite = infinite_light_pick(p);
    let u_pick = rand();
    let u = rand2();
    var ls: LightSample;
    ls.pdf = 0.0;
    if (FEATURE_INFINITE_LIGHTS && u_pick < p_infinite) {
        let u_side = min(u_pick / p_infinite, ONE_MINUS_EPSILON);
        let p_env = params.environment.w;
        if (u_side < p_env) {
            light_sampled = LIGHT_SAMPLED_ENVIRONMENT;
            ls = sample_environment(u);
            ls.pdf *= p_env;
        } else if (FEATURE_ANALYTIC_LIGHTS) {
            light_sampled = LIGHT_SAMPLED_ANALYTIC;
            ls = sample_analytic_light(pick_analytic_light(u_side, true), p, u);
        }
        ls.pdf *= p_infinite;
    } else {
        let u_side = min((u_pick - p_infinite) / (1.0 - p_infinite), ONE_MINUS_EPSILON);
        let p_tri = params.triangle_pick;
        if (FEATURE_EMISSIVE_TRIANGLES && u_side < p_tri) {
            light_sampled = LIGHT_SAMPLED_TRIANGLE;
            ls = sample_light_triangle(p, u);
            ls.pdf *= p_tri;
        } else if (FEATURE_ANALYTIC_LIGHTS) {
            light_sampled = LIGHT_SAMPLED_ANALYTIC;
            ls = sample_analytic_light(pick_analytic_light(u_side, false), p, u);
        }
        ls.pdf *= 1.0 - p_infinite;
    }
    return ls;
}
