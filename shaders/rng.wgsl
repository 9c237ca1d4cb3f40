// Counter-based random numbers: every value is a pure function of
// (pixel, sample index, seed, dimension), so a render repeats bit for bit and a sample
// range can be rendered on its own and merged. PCG-RXS-M-XS as a hash
// (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020).

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

var<private> rng_state: u32;

fn rng_seed(pixel: u32, sample_index: u32, seed: u32) {
    rng_state = pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(seed)));
}

// Uniform in [0, 1): 24 random bits, so 1.0 is never returned.
fn rand() -> f32 {
    rng_state = pcg_hash(rng_state);
    return f32(rng_state >> 8u) * (1.0 / 16777216.0);
}

fn rand2() -> vec2<f32> {
    let a = rand();
    return vec2<f32>(a, rand());
}
