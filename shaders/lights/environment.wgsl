// A uniform environment: constant radiance from every direction, sampled uniformly over
// the sphere for next-event estimation.

fn environment_radiance(dir: vec3<f32>) -> vec3<f32> {
    return params.environment.rgb;
}

fn sample_environment(u: vec2<f32>) -> LightSample {
    let wi = sample_uniform_sphere(u);
    return LightSample(wi, 3.0e38, environment_radiance(wi), INV_4PI, true);
}

fn environment_pdf(dir: vec3<f32>) -> f32 {
    return INV_4PI;
}
