// Emissive triangles as lights: one is picked in proportion to its power (luminance of
// its radiance times its area), then a point is drawn uniformly on it. Emission is
// one-sided, from the side the triangle's winding faces.

struct LightSample {
    wi: vec3<f32>,
    dist: f32,
    radiance: vec3<f32>,
    // Solid-angle density at the shading point, including the pick probability (for delta
    // lights, the pick probability alone).
    pdf: f32,
    // Whether BSDF sampling can also reach this light, so MIS applies.
    mis: bool,
};

fn pick_light_triangle(u: f32) -> u32 {
    var lo = 0u;
    var hi = params.light_count - 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (light_cdf_at(mid) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A point on an emissive triangle picked by power. u.x picks the triangle and, rescaled
// to the triangle's share of the CDF, is reused with u.y for the point: a stratified 2D
// sample stays stratified over the whole light (a quad's two triangles, a mesh's many)
// rather than split between triangles at random.
fn sample_light_triangle(p: vec3<f32>, u: vec2<f32>) -> LightSample {
    let index = pick_light_triangle(u.x);
    let light = fetch_light_triangle(index);
    var lo = 0.0;
    if (index > 0u) {
        lo = light_cdf_at(index - 1u);
    }
    let hi = light_cdf_at(index);
    var x = 0.0;
    if (hi > lo) {
        x = clamp((u.x - lo) / (hi - lo), 0.0, 0.99999994);
    }
    let b = sample_uniform_triangle(vec2<f32>(x, u.y));
    let a = light.p0.xyz;
    let e1 = light.p1.xyz - a;
    let e2 = light.p2.xyz - a;
    let q = a + b.x * e1 + b.y * e2;
    let c = cross(e1, e2);
    let area2 = length(c);
    let to_light = q - p;
    let dist2 = dot(to_light, to_light);
    let none = LightSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, true);
    if (area2 == 0.0 || dist2 == 0.0) {
        return none;
    }
    let dist = sqrt(dist2);
    let wi = to_light / dist;
    let cos_light = -dot(c / area2, wi);
    if (cos_light <= 0.0) {
        return none;
    }
    let pdf_area = light.emission.w / (0.5 * area2);
    return LightSample(wi, dist, light.emission.rgb, pdf_area * dist2 / cos_light, true);
}

// Density with which `sample_light_triangle` would have produced a direction that reached
// an emitter of radiance `emission` at distance `dist` with cosine `cos_light` there.
// Because the pick probability is proportional to luminance times area, the area cancels.
fn light_triangle_pdf(emission: vec3<f32>, dist: f32, cos_light: f32) -> f32 {
    if (cos_light <= 0.0 || params.light_power <= 0.0) {
        return 0.0;
    }
    return luminance(emission) / params.light_power * dist * dist / cos_light;
}
