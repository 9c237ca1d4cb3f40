// Test kernel: the random numbers of shaders/rng.wgsl as a path draws them.
// probe_in[0] = (pixels, samples per pixel, sampler, seed); pixel p's sample s is
// invocation p * samples + s. probe_out per invocation, two vectors:
// (the camera's first rand2(), the next rand(), 0) and (the first rand2() of bounce 3,
// the integrand of tests/sampler.rs at the camera's rand2(), 0).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sampler_probe(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    if (index >= header.x * header.y) {
        return;
    }
    rng_begin(index / header.y, index % header.y, header.w, header.z);
    let film = rand2();
    let pick = rand();
    rng_align(3u);
    let bounce = rand2();
    // A smooth integrand over the unit square (its integral is in tests/sampler.rs).
    let f = exp(film.x) * cos(film.y);
    probe_out[2u * index] = vec4<f32>(film, pick, 0.0);
    probe_out[2u * index + 1u] = vec4<f32>(bounce, f, 0.0);
}
