// Unidirectional path tracing with next-event estimation and multiple importance sampling
// (Veach 1997, ch. 9; the structure of Mitsuba 3's path.cpp and pbrt-v4's PathIntegrator).
// Each invocation owns one pixel of the current tile and renders `sample_count` samples
// into it, adding them to the film with Kahan summation so that sums over 10^5 samples do
// not drift.

const RR_START_DEPTH: u32 = 3u;

fn light_sampling_enabled() -> bool {
    return (params.flags & FLAG_LIGHT_SAMPLING) != 0u;
}

fn is_finite3(v: vec3<f32>) -> bool {
    // Bit test rather than comparisons, which a driver may fold under fast-math assumptions.
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

var<private> rays_traced: u32;

// Next-event estimation: one light sample, weighted against BSDF sampling.
fn sample_direct(s: Surface, n: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    let p_env = params.environment.w;
    let u_pick = rand();
    let u = rand2();
    var ls: LightSample;
    if (u_pick < p_env) {
        ls = sample_environment(u);
        ls.pdf *= p_env;
    } else {
        if (params.light_count == 0u) {
            return vec3<f32>(0.0);
        }
        ls = sample_light_triangle(s.pe.p, (u_pick - p_env) / (1.0 - p_env), u);
        ls.pdf *= 1.0 - p_env;
    }
    if (ls.pdf <= 0.0) {
        return vec3<f32>(0.0);
    }
    let f = lambert_eval(albedo, n, ls.wi);
    let cos_i = dot(n, ls.wi);
    // Light from below the geometric surface cannot arrive, whatever the shading normal says.
    if (cos_i <= 0.0 || dot(ls.wi, s.ng) * dot(n, s.ng) <= 0.0 || all(f == vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    let origin = offset_ray_origin(s.pe, s.ng, ls.wi);
    // Stop short of the light by its own rounding error: the light must not shadow itself.
    let t_max = ls.dist * (1.0 - 1e-4);
    rays_traced++;
    if (occluded(Ray(origin, ls.wi), t_max)) {
        return vec3<f32>(0.0);
    }
    let w = power_heuristic(ls.pdf, lambert_pdf(n, ls.wi));
    return f * cos_i * ls.radiance * (w / ls.pdf);
}

fn trace_path(primary: Ray) -> vec3<f32> {
    var ray = primary;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var prev_bsdf_pdf = 0.0;
    let nee = light_sampling_enabled();
    for (var depth = 0u; ; depth++) {
        rays_traced++;
        let hit = intersect_scene(ray);
        if (!hit.hit) {
            var w = 1.0;
            if (nee && depth > 0u && params.environment.w > 0.0) {
                w = power_heuristic(prev_bsdf_pdf, params.environment.w * environment_pdf(ray.dir));
            }
            radiance += throughput * environment_radiance(ray.dir) * w;
            break;
        }
        let s = surface_at(hit);
        let material = materials[s.material];
        let front = dot(ray.dir, s.ng) < 0.0;

        let emission = material.emission.rgb;
        if (front && any(emission > vec3<f32>(0.0))) {
            var w = 1.0;
            if (nee && depth > 0u) {
                let light_pdf = (1.0 - params.environment.w) * light_triangle_pdf(emission, hit.t, -dot(ray.dir, s.ng));
                w = power_heuristic(prev_bsdf_pdf, light_pdf);
            }
            radiance += throughput * emission * w;
        }
        if (depth >= params.max_bounces) {
            break;
        }

        // Two-sided surface: face the normals toward the incoming ray.
        let ng = select(-s.ng, s.ng, front);
        let ns = select(-s.ns, s.ns, front);
        let oriented = Surface(s.pe, ng, ns, s.uv, s.material);
        let albedo = material.base_color.rgb;

        if (nee) {
            radiance += throughput * sample_direct(oriented, ns, albedo);
        }

        let bs = lambert_sample(albedo, ns, rand2());
        // A direction under the geometric surface would pass through it: the path ends.
        if (bs.pdf <= 0.0 || dot(bs.wi, ng) <= 0.0) {
            break;
        }
        throughput *= bs.weight;
        prev_bsdf_pdf = bs.pdf;

        if (depth >= RR_START_DEPTH) {
            let q = max(0.05, 1.0 - max(throughput.r, max(throughput.g, throughput.b)));
            if (rand() < q) {
                break;
            }
            throughput /= 1.0 - q;
        }
        ray = Ray(offset_ray_origin(oriented.pe, ng, bs.wi), bs.wi);
    }
    return radiance;
}

@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.tile_size.x || gid.y >= params.tile_size.y) {
        return;
    }
    let px = params.tile_origin + gid.xy;
    if (px.x >= params.film_size.x || px.y >= params.film_size.y) {
        return;
    }
    let pixel = px.y * params.film_size.x + px.x;
    var sum = film_sum[pixel];
    var compensation = film_compensation[pixel];
    var non_finite = 0u;
    rays_traced = 0u;
    for (var i = 0u; i < params.sample_count; i++) {
        rng_seed(pixel, params.sample_start + i, params.seed);
        let film_pos = vec2<f32>(px) + vec2<f32>(0.5) + vec2<f32>(sample_tent(rand()), sample_tent(rand()));
        var l = trace_path(camera_ray(film_pos, rand2()));
        if (!is_finite3(l)) {
            non_finite++;
            l = vec3<f32>(0.0);
        }
        // Kahan summation; w counts samples.
        let y = vec4<f32>(l, 1.0) - compensation;
        let t = sum + y;
        compensation = (t * params.opaque_one - sum) - y;
        sum = t;
    }
    film_sum[pixel] = sum;
    film_compensation[pixel] = compensation;
    atomicAdd(&stats.rays, rays_traced);
    if (non_finite > 0u) {
        atomicAdd(&stats.non_finite, non_finite);
    }
}
