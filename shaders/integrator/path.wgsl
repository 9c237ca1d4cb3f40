// Unidirectional path tracing with next-event estimation and multiple importance sampling
// (Veach 1997, ch. 9; the structure of Mitsuba 3's path.cpp and pbrt-v4's PathIntegrator)
// over the principled surface (shaders/bsdf/principled.wgsl), with alpha cut-outs,
// random-walk subsurface scattering (shaders/media/subsurface.wgsl) and participating
// media: the volumes of materials and the Beer–Lambert absorption of transmissive
// objects, nested as shaders/integrator/media.wgsl says, sampled by free flights with
// one-sample MIS over the channels, with next-event estimation through media and volume
// boundaries (transmittance) weighted against phase-function sampling.
// Each invocation owns one pixel of the current tile and renders sample number
// `sample_index` into it, adding it to the film as 64-bit fixed point (`film_add`), so
// that sums over 10^5 samples do not drift and split renders merge exactly. A batch of
// samples is one dispatch per sample, each with its own `Params` (a dynamic offset,
// `Renderer::dispatch`): a loop over samples here would wrap the whole path, and
// lavapipe runs such a loop ~10 % slower even for one sample (docs/BENCHMARKS.md).

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

// The AOVs of the current sample: what the camera ray's first surface looks like.
var<private> aov_albedo: vec3<f32>;
var<private> aov_normal: vec3<f32>;
var<private> aov_depth: f32;
// Light emitted by what the camera sees (surfaces, the sky), which the denoiser keeps
// out of the light it filters.
var<private> aov_emission: vec3<f32>;
// Coverage: 1 where the camera ray meets a surface, 0 where it leaves the scene, and on a
// shadow catcher whether the light sampled from it was blocked (`catcher_shadow`).
var<private> aov_alpha: f32;

// Surfaces a path may pass through (alpha cut-outs) before it counts as lost.
const MAX_PASS_THROUGH: u32 = 64u;

// The fixed-parameter material of the material buffer (materials without a graph).
fn material_from_buffer(id: u32, sp: ShadingPoint) -> MaterialEval {
    return material_eval(principled_unpack(fetch_material(id).principled), sp.n);
}

// A contribution `c` of light that scattered `scatterings` times on its way to the
// camera, limited by the firefly clamp (Params.clamp_*; 0: no limit): its largest channel
// at most the limit, its colour kept. Light that scattered at most once is direct (Cycles'
// Light Paths ▸ Clamping).
fn clamped(c: vec3<f32>, scatterings: u32) -> vec3<f32> {
    let limit = select(params.clamp_indirect, params.clamp_direct, scatterings <= 1u);
    let peak = max(c.x, max(c.y, c.z));
    if (limit > 0.0 && peak > limit) {
        return c * (limit / peak);
    }
    return c;
}

// A small hash of the instance index in [0, 1), for the Object Info node.
fn instance_random(i: u32) -> f32 {
    var x = i * 747796405u + 2891336453u;
    x = ((x >> ((x >> 28u) + 4u)) ^ x) * 277803737u;
    x = (x >> 22u) ^ x;
    return f32(x >> 8u) / 16777216.0;
}

// Where a world-space point lies in an instance's object: its object-space position and
// its generated coordinates (the position within the object's bounds, [0, 1]³ inside).
fn generated_coordinates(inst: Instance, p_object: vec3<f32>) -> vec3<f32> {
    let lo = inst.mesh_min.xyz;
    let extent = inst.mesh_max.xyz - lo;
    return (p_object - lo) / select(extent, vec3<f32>(1.0), extent <= vec3<f32>(0.0));
}

fn instance_location(inst: Instance) -> vec3<f32> {
    return vec3<f32>(inst.to_world[0].w, inst.to_world[1].w, inst.to_world[2].w);
}

// What material graphs see of a hit (shaders/nodes/inputs.wgsl).
fn shading_point(s: Surface, hit: SceneHit, wo: vec3<f32>, front: bool) -> ShadingPoint {
    let inst = fetch_instance(hit.instance);
    let p_object = transform_point(inst.to_object, s.pe.p);
    let n_object = normalize(transform_vector(transpose_rows(inst.to_world), s.ns));
    return ShadingPoint(
        s.pe.p, s.ns, s.ng, s.uv, s.uv1, s.dpdu, s.dpdv, wo, p_object, n_object,
        generated_coordinates(inst, p_object), s.color, instance_random(hit.instance),
        instance_location(inst), !front,
    );
}

// What a volume's graph sees at a point `p` inside instance `instance`, for a path
// travelling along `dir`: as in Cycles, the normal faces back along the path; there are
// no texture coordinates or vertex colours inside.
fn volume_point(instance: u32, p: vec3<f32>, dir: vec3<f32>) -> ShadingPoint {
    let inst = fetch_instance(instance);
    let p_object = transform_point(inst.to_object, p);
    let n = -dir;
    let n_object = normalize(transform_vector(transpose_rows(inst.to_world), n));
    return ShadingPoint(
        p, n, n, vec2<f32>(0.0), vec2<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), n, p_object,
        n_object, generated_coordinates(inst, p_object), vec4<f32>(1.0),
        instance_random(instance), instance_location(inst), false,
    );
}

// The rows of the transpose of a 3x4 matrix's linear part (normals go to object space
// by the transpose of the object-to-world matrix, up to scale).
fn transpose_rows(m: array<vec4<f32>, 3>) -> array<vec4<f32>, 3> {
    return array<vec4<f32>, 3>(
        vec4<f32>(m[0].x, m[1].x, m[2].x, 0.0),
        vec4<f32>(m[0].y, m[1].y, m[2].y, 0.0),
        vec4<f32>(m[0].z, m[1].z, m[2].z, 0.0),
    );
}

fn to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n));
}

// The media the path is in now (shaders/integrator/media.wgsl).
var<private> media: Media;

// The fraction of light that crosses the segment from `origin` along `dir` to `t_max`:
// through the media `start` (the media at the origin), across the bare boundaries of
// volumes (entering and leaving their media on the way) and through cut-outs by their
// transparency; 0 where any other surface blocks it. Without volumes or cut-outs in the
// kernel, only whether it is blocked.
fn transmittance(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, start: Media) -> vec3<f32> {
    if (!FEATURE_VOLUME && !FEATURE_CUTOUT) {
        rays_traced++;
        return select(vec3<f32>(1.0), vec3<f32>(0.0), occluded(Ray(origin, dir), t_max));
    }
    var inside = start;
    var o = origin;
    var tr = vec3<f32>(1.0);
    // Media attenuate in order, so volumes need the nearest hit each time. Without them
    // any hit settles the common cases (nothing in the way, or an opaque surface); the
    // first cut-out met restarts the segment nearest-first. One traversal in the kernel.
    var nearest = FEATURE_VOLUME;
    for (var i = 0u; i <= MAX_PASS_THROUGH + 1u; i++) {
        let remaining = t_max - dot(o - origin, dir);
        if (!(remaining > 0.0)) {
            return tr;
        }
        rays_traced++;
        let hit = traverse_scene(Ray(o, dir), remaining, !nearest);
        let t = select(remaining, hit.t, hit.hit);
        if (FEATURE_VOLUME && inside.count > 0u) {
            if (FEATURE_HETEROGENEOUS && inside.majorant[inside.count - 1u] > 0.0) {
                tr *= ratio_tracking(inside, o, dir, t);
            } else {
                tr *= exp(-inside.medium[inside.count - 1u].sigma_t * t);
            }
        }
        if (!hit.hit) {
            return tr;
        }
        let material = fetch_material(fetch_instance(hit.instance).material);
        if (FEATURE_CUTOUT && !nearest && material.cutout != 0u) {
            nearest = true;
            continue;
        }
        let s = surface_at(hit);
        if (FEATURE_VOLUME && material.boundary_only != 0u) {
            if (dot(dir, s.ng) < 0.0) {
                inside = media_entered(inside, s.material, hit.instance, vec3<f32>(0.0));
            } else {
                inside = media_left(inside, s.material);
            }
        } else if (FEATURE_CUTOUT && material.cutout != 0u) {
            // Cycles' transparent shadows: the expected value of the camera path's
            // stochastic pass through a cut-out.
            let front = dot(dir, s.ng) < 0.0;
            let opacity = evaluate_material(s.material, shading_point(s, hit, -dir, front)).opacity;
            tr *= 1.0 - saturate(opacity);
        } else {
            return vec3<f32>(0.0);
        }
        if (!any(tr > vec3<f32>(0.0))) {
            return vec3<f32>(0.0);
        }
        o = offset_ray_origin(s.pe, s.ng, dir);
    }
    return vec3<f32>(0.0);
}

// Where next-event estimation samples a light from: a surface seen through its shading
// frame, or a point in a medium.
struct ScatterVertex {
    pe: PointError,
    in_medium: bool,
    // On a surface: the geometric normal on the frame's side, the shading frame, and the
    // direction back along the path in that frame.
    ng: vec3<f32>,
    frame: Frame,
    wo: vec3<f32>,
    // In a medium: the direction the path arrived in, and the phase function's g.
    dir: vec3<f32>,
    g: f32,
};

fn surface_vertex(pe: PointError, ng: vec3<f32>, frame: Frame, wo: vec3<f32>) -> ScatterVertex {
    var v: ScatterVertex;
    v.pe = pe;
    v.ng = ng;
    v.frame = frame;
    v.wo = wo;
    return v;
}

fn medium_vertex(p: vec3<f32>, dir: vec3<f32>, g: f32) -> ScatterVertex {
    var v: ScatterVertex;
    v.pe = PointError(p, vec3<f32>(0.0));
    v.in_medium = true;
    v.dir = dir;
    v.g = g;
    return v;
}

// Next-event estimation: one light sample, weighted against BSDF or phase-function
// sampling. A surface scatters by `p`; `beyond` is the media on the far side of it from
// `wo`, where a light sampled through it is seen from. The path's only call site: the
// light sampling and the transmittance ray (a traversal) are compiled once.
fn sample_direct(v: ScatterVertex, p: Principled, beyond: Media) -> vec3<f32> {
    let ls = sample_light(v.pe.p);
    if (ls.pdf <= 0.0) {
        return vec3<f32>(0.0);
    }
    var f: vec3<f32>;
    var scatter_pdf: f32;
    var origin = v.pe.p;
    var start = media;
    if (v.in_medium) {
        scatter_pdf = hg_phase(dot(v.dir, ls.wi), v.g);
        f = vec3<f32>(scatter_pdf);
    } else {
        let wi = to_local(v.frame, ls.wi);
        // The shading and geometric normals must agree on which side the light is, or
        // light would leak through the surface.
        if (dot(ls.wi, v.ng) * wi.z <= 0.0) {
            return vec3<f32>(0.0);
        }
        let e = principled_eval(p, v.wo, wi);
        if (all(e.value == vec3<f32>(0.0))) {
            return vec3<f32>(0.0);
        }
        f = e.value;
        scatter_pdf = e.pdf;
        origin = offset_ray_origin(v.pe, v.ng, ls.wi);
        if (v.wo.z * wi.z < 0.0) {
            start = beyond;
        }
    }
    // Stop short of the light by its own rounding error: the light must not shadow itself.
    let tr = transmittance(origin, ls.wi, ls.dist * (1.0 - 1e-4), start);
    if (!any(tr > vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    let w = select(1.0, power_heuristic(ls.pdf, scatter_pdf), ls.mis);
    return f * tr * ls.radiance * (w / ls.pdf);
}

// A shadow catcher met by the camera ray (Cycles' shadow catcher, as the opacity of the
// shadow alone): the share of the light sampled from its point `pe`, on the side `n`
// faces, that objects block (cut-outs and volumes block part of it), 0 when the light
// gives the point nothing. Averaged over a pixel's samples, the share of light blocked,
// lights picked by power as next-event estimation picks them.
fn catcher_shadow(pe: PointError, n: vec3<f32>) -> f32 {
    let ls = sample_light(pe.p);
    if (ls.pdf <= 0.0 || dot(ls.wi, n) <= 0.0 || all(ls.radiance == vec3<f32>(0.0))) {
        return 0.0;
    }
    let tr = transmittance(offset_ray_origin(pe, n, ls.wi), ls.wi, ls.dist * (1.0 - 1e-4), media);
    return 1.0 - (tr.x + tr.y + tr.z) / 3.0;
}

// What a random walk leaves by: a white Lambertian surface.
fn walk_exit_surface() -> Principled {
    var p = principled_default();
    p.base_color = vec3<f32>(1.0);
    p.base_weight = 1.0;
    p.diffuse_roughness = 0.0;
    p.specular_weight = 0.0;
    p.subsurface_weight = 0.0;
    return p;
}

// Russian roulette past RR_START_DEPTH: false when the path ends; else the survivors'
// throughput is divided by their probability. The odds follow the throughput times
// `eta_scale`, the product of etap² over the refractions so far: radiance entering glass
// is divided by etap² and multiplied back on leaving, which says nothing about what the
// path will carry (pbrt-v4's etaScale, Mitsuba 3's eta²). Without it a path inside
// glass of IOR 1.5 survived at 0.44 times the odds and came out 2.25 times as heavy.
fn survives_roulette(depth: u32, throughput: ptr<function, vec3<f32>>, eta_scale: f32) -> bool {
    if (depth < RR_START_DEPTH) {
        return true;
    }
    let t = *throughput;
    let q = max(0.05, 1.0 - max(t.r, max(t.g, t.b)) * eta_scale);
    if (rand() < q) {
        return false;
    }
    *throughput = t / (1.0 - q);
    return true;
}

// What a path's vertex is, for the code after next-event estimation.
const EVENT_SURFACE: u32 = 0u;
const EVENT_MEDIUM: u32 = 1u;
const EVENT_WALK_EXIT: u32 = 2u;

fn trace_path(primary: Ray) -> vec3<f32> {
    var ray = primary;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var prev_bsdf_pdf = 0.0;
    // The product of etap² over the refractions so far (survives_roulette).
    var eta_scale = 1.0;
    // The camera, like a delta lobe, could not have been sampled by light sampling.
    var prev_delta = true;
    // Where the last scattering event was: what light sampling saw a light from.
    var vertex = primary.origin;
    media = media_empty();
    if (FEATURE_MEDIA) {
        media = camera_media();
    }
    let nee = light_sampling_enabled();
    var depth = 0u;
    // Scattering events in media, against params.max_volume_bounces.
    var volume_depth = 0u;
    var passes = 0u;
    // Inside an object, in a random walk its subsurface lobe started.
    var walking = false;
    var walk_medium: Medium;
    var walk_steps = 0u;
    loop {
        rng_align(depth);
        rays_traced++;
        let hit = intersect_scene(ray);
        // Each pass of the loop finds one vertex to scatter at (a surface, where a walk
        // leaves, or a point in a medium), samples a light from it at the one call site
        // below, then samples the next direction.
        var event = EVENT_SURFACE;
        var v: ScatterVertex;
        var p: Principled;
        var beyond = media;
        var s: Surface;
        var transmissive = false;
        if (FEATURE_SUBSURFACE && walking) {
            // Whatever surface the walk meets is where it leaves: the object's own
            // boundary (or, in an open or overlapping mesh, the first surface ahead).
            let flight = medium_free_flight(walk_medium, throughput, select(3.0e38, hit.t, hit.hit), rand(), rand());
            if (!flight.valid) {
                break;
            }
            throughput *= flight.weight;
            if (flight.scattered) {
                walk_steps++;
                if (walk_steps > SUBSURFACE_MAX_STEPS) {
                    break;
                }
                vertex = ray.origin + ray.dir * flight.t;
                ray = Ray(vertex, hg_sample(ray.dir, walk_medium.g, rand2()));
                continue;
            }
            // The exit: a white Lambertian facing out, lit by next-event estimation as
            // part of the bounce that entered (so one bounce sees subsurface light).
            walking = false;
            event = EVENT_WALK_EXIT;
            s = surface_at(hit);
            let ng_out = select(-s.ng, s.ng, dot(ray.dir, s.ng) > 0.0);
            let ns_out = select(s.ns, -s.ns, dot(s.ns, ng_out) < 0.0);
            v = surface_vertex(s.pe, ng_out, frame_from_normal(ns_out), vec3<f32>(0.0, 0.0, 1.0));
            p = walk_exit_surface();
        } else {
            let t_scene = select(3.0e38, hit.t, hit.hit);
            // Sphere lights and sun disks in front of the surface (or the sky).
            var light_hit = AnalyticHit(false, t_scene, vec3<f32>(0.0), 0.0);
            if (FEATURE_ANALYTIC_LIGHTS && params.analytic_light_count > 0u) {
                light_hit = analytic_light_hit(ray.origin, ray.dir, t_scene, infinite_light_pick(vertex));
            }
            if (FEATURE_MEDIA && media.count > 0u) {
                // The segment runs through the innermost medium; a medium without an exit
                // absorbs everything.
                let top = media.count - 1u;
                let m = media.medium[top];
                let t_segment = min(t_scene, light_hit.t);
                // Past its volume bounces a path sees media as absorbers of their whole
                // extinction (Cycles' absorption-only volumes).
                let scatters = volume_depth < params.max_volume_bounces;
                if (FEATURE_HETEROGENEOUS && media.majorant[top] > 0.0) {
                    let tracked = heterogeneous_flight(media, ray.origin, ray.dir, t_segment, throughput, scatters);
                    radiance += clamped(tracked.emitted, depth);
                    throughput = tracked.throughput;
                    if (!tracked.valid) {
                        break;
                    }
                    if (tracked.scattered) {
                        vertex = ray.origin + ray.dir * tracked.t;
                        if (depth >= params.max_bounces) {
                            break;
                        }
                        event = EVENT_MEDIUM;
                        v = medium_vertex(vertex, ray.dir, tracked.g);
                    }
                } else {
                    if (FEATURE_VOLUME && any(media.emission[top] > vec3<f32>(0.0))) {
                        radiance += clamped(throughput * medium_emission(m, media.emission[top], t_segment), depth);
                    }
                    if (FEATURE_VOLUME && scatters && any(m.albedo > vec3<f32>(0.0))) {
                        let flight = medium_free_flight(m, throughput, t_segment, rand(), rand());
                        if (!flight.valid) {
                            break;
                        }
                        throughput *= flight.weight;
                        if (flight.scattered) {
                            vertex = ray.origin + ray.dir * flight.t;
                            if (depth >= params.max_bounces) {
                                break;
                            }
                            event = EVENT_MEDIUM;
                            v = medium_vertex(vertex, ray.dir, m.g);
                        }
                    } else {
                        // Beer–Lambert: the medium only absorbs.
                        throughput *= exp(-m.sigma_t * t_segment);
                    }
                }
            }
            if (event == EVENT_SURFACE) {
                if (light_hit.hit) {
                    var w = 1.0;
                    if (nee && !prev_delta) {
                        w = power_heuristic(prev_bsdf_pdf, light_hit.pdf);
                    }
                    radiance += clamped(throughput * light_hit.radiance * w, depth);
                    if (light_hit.t < t_scene) {
                        // The sphere light is opaque: the path ends on it.
                        break;
                    }
                }
                if (!hit.hit) {
                    if (FEATURE_SHADOW_CATCHER && depth == 0u && (params.flags & FLAG_SHADOW_CATCHER) != 0u) {
                        // Beside a shadow catcher the background is transparent: the
                        // camera sees nothing here (alpha 0).
                        break;
                    }
                    var w = 1.0;
                    if (nee && !prev_delta && params.environment.w > 0.0) {
                        w = power_heuristic(prev_bsdf_pdf, environment_light_pdf(vertex, ray.dir));
                    }
                    let sky = clamped(throughput * environment_radiance(ray.dir) * w, depth);
                    radiance += sky;
                    if (FEATURE_AOVS && depth == 0u) {
                        aov_emission += sky;
                    }
                    break;
                }
                s = surface_at(hit);
                let material = fetch_material(s.material);
                let front = dot(ray.dir, s.ng) < 0.0;
                if (FEATURE_SHADOW_CATCHER && depth == 0u && (fetch_instance(hit.instance).flags & INSTANCE_SHADOW_CATCHER) != 0u) {
                    // The camera sees a shadow catcher: only its shadow, as alpha.
                    aov_alpha = catcher_shadow(s.pe, select(-s.ng, s.ng, front));
                    break;
                }
                if (FEATURE_VOLUME && material.boundary_only != 0u) {
                    // A volume's bare boundary: the path enters or leaves its medium unchanged.
                    if (front) {
                        media = media_entered(media, s.material, hit.instance, vec3<f32>(0.0));
                    } else {
                        media = media_left(media, s.material);
                    }
                    passes++;
                    if (passes > MAX_PASS_THROUGH) {
                        break;
                    }
                    ray = Ray(offset_ray_origin(s.pe, s.ng, ray.dir), ray.dir);
                    continue;
                }
                let me = evaluate_material(s.material, shading_point(s, hit, -ray.dir, front));
                // A normal from a normal map or bump on the other side of the surface than its
                // geometry would let light leak: keep the interpolated one then.
                if (dot(me.normal, s.ng) > 0.0) {
                    s.ns = me.normal;
                }

                // Alpha cut-out: the path continues through the surface without scattering.
                let opacity = me.opacity;
                if (FEATURE_CUTOUT && opacity < 1.0 && rand() >= opacity) {
                    passes++;
                    if (passes > MAX_PASS_THROUGH) {
                        break;
                    }
                    ray = Ray(offset_ray_origin(s.pe, s.ng, ray.dir), ray.dir);
                    continue;
                }

                if (depth == 0u) {
                    aov_alpha = 1.0;
                }
                let emission = me.emission;
                if (front && any(emission > vec3<f32>(0.0))) {
                    var w = 1.0;
                    if (nee && !prev_delta) {
                        // Light sampling knows the surface by its buffer emission (0 for emission
                        // that varies over it, which only BSDF sampling finds).
                        let light_pdf = triangle_light_pdf(vertex, material.emission.rgb, distance(vertex, s.pe.p), -dot(ray.dir, s.ng));
                        w = power_heuristic(prev_bsdf_pdf, light_pdf);
                    }
                    let emitted = clamped(throughput * emission * w, depth);
                    radiance += emitted;
                    if (FEATURE_AOVS && depth == 0u) {
                        aov_emission += emitted;
                    }
                }
                // Opaque surfaces are two-sided: their frame turns toward the incoming ray.
                // Surfaces light passes through keep their front, so inside and outside differ.
                transmissive = material.transmissive != 0u;
                let flip = !transmissive && !front;
                let ng = select(s.ng, -s.ng, flip);
                let ns = select(s.ns, -s.ns, flip);
                p = me.principled;
                // Anisotropic highlights follow the texture's u direction, turned by the material.
                var frame = frame_from_normal(ns);
                if (p.anisotropy > 0.0) {
                    frame = frame_from_normal_tangent(ns, s.dpdu, me.anisotropy_rotation);
                }
                let wo = to_local(frame, -ray.dir);
                if (FEATURE_AOVS && depth == 0u) {
                    let dielectric = 1.0 - p.metallic;
                    aov_albedo = mix(p.base_color * mix(p.base_weight, 1.0, p.metallic), p.transmission_color, p.transmission_weight * dielectric);
                    aov_normal = ns;
                    aov_depth = hit.t;
                }
                // Past the AOVs, so that a render without bounces still has its first hit's.
                if (depth >= params.max_bounces) {
                    break;
                }
                v = surface_vertex(s.pe, ng, frame, wo);
                // Light through a transmissive surface is seen from the media on its far side.
                if (FEATURE_VOLUME && transmissive && !p.thin_walled) {
                    if (front) {
                        beyond = media_entered(media, s.material, hit.instance, principled_extinction(p));
                    } else {
                        beyond = media_left(media, s.material);
                    }
                }
            }
        }

        if (nee) {
            // Light sampled here has scattered once more than the path.
            radiance += clamped(throughput * sample_direct(v, p, beyond), depth + 1u);
        }

        if (event == EVENT_MEDIUM) {
            let wi = hg_sample(ray.dir, v.g, rand2());
            prev_bsdf_pdf = hg_phase(dot(ray.dir, wi), v.g);
            prev_delta = false;
            if (!survives_roulette(depth, &throughput, eta_scale)) {
                break;
            }
            ray = Ray(vertex, wi);
            depth++;
            volume_depth++;
            continue;
        }
        if (event == EVENT_WALK_EXIT) {
            if (depth >= params.max_bounces) {
                break;
            }
            let local = sample_cosine_hemisphere(rand2());
            let wi = normalize(frame_to_world(v.frame, local));
            if (dot(wi, v.ng) <= 0.0 || local.z <= 0.0) {
                break;
            }
            prev_bsdf_pdf = local.z / PI;
            prev_delta = false;
            vertex = v.pe.p;
            ray = Ray(offset_ray_origin(v.pe, v.ng, wi), wi);
            depth++;
            continue;
        }

        let bs = principled_sample(p, v.wo, rand(), rand(), rand2());
        if (!bs.valid) {
            break;
        }
        let wi = normalize(frame_to_world(v.frame, bs.wi));
        // A direction the shading frame calls reflection but the geometry calls
        // transmission (or the reverse) would pass through the surface: the path ends.
        if (dot(wi, v.ng) * bs.wi.z <= 0.0) {
            break;
        }
        throughput *= bs.weight;
        prev_bsdf_pdf = bs.pdf;
        prev_delta = bs.delta;
        vertex = s.pe.p;
        if (FEATURE_SUBSURFACE && principled_sampled_lobe == LOBE_SUBSURFACE) {
            walking = true;
            walk_medium = subsurface_medium(p);
            walk_steps = 0u;
        } else if (FEATURE_MEDIA && transmissive && !p.thin_walled && dot(wi, s.ng) * dot(ray.dir, s.ng) > 0.0) {
            // Crossed the surface: entering through the front, or leaving through it.
            if (principled_sampled_lobe == LOBE_GLASS) {
                let ior = max(p.ior, 1e-4);
                let etap = select(1.0 / ior, ior, v.wo.z > 0.0);
                eta_scale *= etap * etap;
            }
            if (dot(wi, s.ng) < 0.0) {
                media = media_entered(media, s.material, hit.instance, principled_extinction(p));
            } else {
                media = media_left(media, s.material);
            }
        }

        if (!survives_roulette(depth, &throughput, eta_scale)) {
            break;
        }
        ray = Ray(offset_ray_origin(s.pe, v.ng, wi), wi);
        depth++;
    }
    return radiance;
}

// The film's sums are 64-bit two's-complement fixed point (`crate::film::ExactFilm`):
// low words in `film_sum.xyz` with the sample count in w, high words in `film_high.xyz`.
// Integer addition is associative, so a pixel's sum is the same bits however its samples
// are split into dispatches, passes, or the parts of a render merged later (`kiln merge`).
const FILM_FRACTION_BITS: f32 = 268435456.0; // 2^28
const FILM_WORD: f32 = 4294967296.0; // 2^32
/// Samples are clamped to this magnitude (2^24 ≈ 1.7·10^7), so that one adds at most 2^20
/// to a sum's high word.
const FILM_SAMPLE_LIMIT: f32 = 16777216.0;
/// Sums saturate at this high word (2^31 − 2^21, about ±3.4·10^10): below it, adding a
/// sample cannot wrap, and clamping the high word to it after each add saturates the sum.
const FILM_HIGH_LIMIT: i32 = 2145386496;

struct FilmSum {
    low: vec3<u32>,
    high: vec3<u32>,
}

/// `sum` + `l` rounded to the film's step; saturates at the range's ends.
fn film_add(sum: FilmSum, l: vec3<f32>) -> FilmSum {
    let v = round(clamp(l, vec3<f32>(-FILM_SAMPLE_LIMIT), vec3<f32>(FILM_SAMPLE_LIMIT)) * FILM_FRACTION_BITS);
    // v = high·2^32 + low exactly: both parts are f32 integers below 2^32.
    let vh = floor(v * (1.0 / FILM_WORD));
    let add_low = vec3<u32>(v - vh * FILM_WORD);
    let low = sum.low + add_low;
    let carry = select(vec3<i32>(0), vec3<i32>(1), low < add_low);
    let high = bitcast<vec3<i32>>(sum.high) + vec3<i32>(vh) + carry;
    let limit = vec3<i32>(FILM_HIGH_LIMIT);
    return FilmSum(low, bitcast<vec3<u32>>(clamp(high, -limit, limit)));
}

/// A pixel's sums as floating point, and its count in w.
fn film_value(low: vec4<u32>, high: vec4<u32>) -> vec4<f32> {
    let sum = (vec3<f32>(bitcast<vec3<i32>>(high.xyz)) * FILM_WORD + vec3<f32>(low.xyz)) / FILM_FRACTION_BITS;
    return vec4<f32>(sum, f32(low.w));
}

// `kiln bench --ablation`: the kernel cut down to a part of its work, to measure where
// the time goes. Each mode returns a value that depends on all the work it did, so the
// driver cannot drop any of it. ABLATION_FULL is the path tracer above.
//   camera     the camera ray alone: dispatch, sampler, filter and film
//   primary    + the closest hit of the camera ray (coherent rays)
//   traversal  + closest-hit and shadow rays along a cosine-weighted walk about the
//              geometric normal, `params.max_bounces` deep at most (at most 8): traversal of
//              incoherent rays, and the hit points' geometry, with no material, light or
//              BSDF code.
fn ablated_path(primary: Ray) -> vec3<f32> {
    if (ABLATION == ABLATION_CAMERA) {
        return primary.dir * 0.5 + vec3<f32>(0.5);
    }
    var ray = primary;
    var value = vec3<f32>(0.0);
    let depth = select(min(params.max_bounces, 8u), 1u, ABLATION == ABLATION_PRIMARY);
    for (var bounce = 0u; bounce < depth; bounce++) {
        rng_align(bounce);
        rays_traced++;
        let hit = intersect_scene(ray);
        if (!hit.hit) {
            value += vec3<f32>(1.0);
            break;
        }
        if (ABLATION == ABLATION_PRIMARY) {
            value += vec3<f32>(hit.t, f32(hit.instance), hit.b1);
            break;
        }
        let s = surface_at(hit);
        value += s.ng * 0.5 + vec3<f32>(0.5 / hit.t);
        // Facing the ray, a cosine-weighted direction, and a shadow ray along another.
        let n = select(-s.ng, s.ng, dot(ray.dir, s.ng) < 0.0);
        let frame = frame_from_normal(n);
        let to_light = frame_to_world(frame, sample_cosine_hemisphere(rand2()));
        rays_traced++;
        if (!occluded(Ray(offset_ray_origin(s.pe, n, to_light), to_light), 3.0e38)) {
            value += vec3<f32>(0.25);
        }
        let wi = frame_to_world(frame, sample_cosine_hemisphere(rand2()));
        ray = Ray(offset_ray_origin(s.pe, n, wi), wi);
    }
    return value;
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
    // Samples are seeded by the pixel's index in the whole film; the buffers bound hold
    // one piece of it, so that how the film is split never changes a sample.
    let pixel = px.y * params.film_size.x + px.x;
    let index = pixel - params.film_piece_start;
    var noise = vec4<f32>(0.0);
    if (FEATURE_NOISE) {
        noise = film_noise[index];
        // Adaptive sampling found the pixel converged (shaders/integrator/adaptive.wgsl).
        if (noise.w != 0.0) {
            atomicAdd(&stats.skipped_samples, 1u);
            return;
        }
    }
    rays_traced = 0u;
    rng_begin(pixel, params.sample_index, params.seed, params.sampler);
    aov_albedo = vec3<f32>(0.0);
    aov_normal = vec3<f32>(0.0);
    aov_depth = 0.0;
    aov_emission = vec3<f32>(0.0);
    aov_alpha = 0.0;
    let film_pos = vec2<f32>(px) + vec2<f32>(0.5) + filter_offset(rand2());
    let primary = camera_ray(film_pos, rand2());
    var l: vec3<f32>;
    if (ABLATION == ABLATION_FULL) {
        l = trace_path(primary);
    } else {
        l = ablated_path(primary);
    }
    atomicAdd(&stats.rays, rays_traced);
    if (!is_finite3(l)) {
        atomicAdd(&stats.non_finite, 1u);
        l = vec3<f32>(0.0);
    }
    let low = film_sum[index];
    let added = film_add(FilmSum(low.xyz, film_high[index].xyz), l);
    film_sum[index] = vec4<u32>(added.low, low.w + 1u);
    film_high[index] = vec4<u32>(added.high, 0u);
    // The AOV sums are added to sample by sample, as the film is, so that they do not
    // depend on how a render splits into dispatches.
    if (FEATURE_AOVS) {
        film_aov[3u * index] += vec4<f32>(aov_albedo, aov_depth);
        film_aov[3u * index + 1u] += vec4<f32>(aov_normal, 1.0);
        film_aov[3u * index + 2u] += vec4<f32>(aov_emission, aov_alpha);
    }
    if (FEATURE_NOISE) {
        // The second moment of the sample's r + g + b, for the noise estimate; Kahan
        // summation, its compensation in y.
        let s = l.r + l.g + l.b;
        let y2 = s * s - noise.y;
        let t2 = noise.x + y2;
        noise.y = (t2 * params.opaque_one - noise.x) - y2;
        noise.x = t2;
        film_noise[index] = noise;
    }
}
