// Counter-based random numbers: every value is a pure function of
// (pixel, sample index, seed, dimension), so a render repeats bit for bit and a sample
// range can be rendered on its own and merged.
//
// Two samplers (Params.sampler, SAMPLER_* in scene.wgsl):
// - independent: a PCG-RXS-M-XS hash chain (Jarzynski & Olano, "Hash Functions for GPU
//   Rendering", JCGT 2020);
// - sobol: Owen-scrambled Sobol' points with hash-based scrambling and shuffling (Burley,
//   "Practical Hash-based Owen Scrambling", JCGT 2020), padded as pbrt-v4's
//   PaddedSobolSampler: every draw (a rand() or a rand2()) is its own dimension, with its
//   own shuffle of the sample indices and its own scrambles, so that draws are independent
//   of each other while each one is stratified over a pixel's samples (the first 2^k
//   samples of a pixel are a (0, k, 2)-net in every rand2(), and fall one in each of 2^k
//   equal intervals in every rand()). Paths align their dimensions by bounce
//   (`rng_align`), so the same draw of the same bounce meets the same sequence.

// Dimensions the camera's draws take (film position, lens) before the first bounce's.
const RNG_CAMERA_DIMENSIONS: u32 = 4u;
// Dimensions reserved per bounce; a bounce that draws more runs into the next one's, and
// the next one starts after it (dimensions never repeat within a path).
const RNG_BOUNCE_DIMENSIONS: u32 = 16u;

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

var<private> rng_state: u32;
var<private> rng_sampler: u32;
// sobol: the pixel's (and seed's) hash, the sample index and the next dimension.
var<private> rng_pixel: u32;
var<private> rng_index: u32;
var<private> rng_dimension: u32;

// Independent numbers for (pixel, sample index, seed).
fn rng_seed(pixel: u32, sample_index: u32, seed: u32) {
    rng_begin(pixel, sample_index, seed, SAMPLER_INDEPENDENT);
}

fn rng_begin(pixel: u32, sample_index: u32, seed: u32, sampler: u32) {
    rng_state = pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(seed)));
    rng_sampler = sampler;
    rng_pixel = pcg_hash(pixel ^ pcg_hash(seed ^ 0x9e3779b9u));
    rng_index = sample_index;
    rng_dimension = 0u;
}

// Moves the next draw to the first dimension of bounce `depth`, unless this path's draws
// are already past it.
fn rng_align(depth: u32) {
    rng_dimension = max(rng_dimension, RNG_CAMERA_DIMENSIONS + depth * RNG_BOUNCE_DIMENSIONS);
}

// Burley's hash-based Owen scrambling of a value whose most significant bit is its first
// binary digit (a Laine–Karras permutation of the reversed bits: each digit is flipped by
// a hash of the digits before it). Applied to a sample index it shuffles the sequence so
// that the first 2^k indices map onto an aligned block of 2^k.
fn owen_scramble(x: u32, seed: u32) -> u32 {
    var v = reverseBits(x);
    v += seed;
    v ^= v * 0x6c50b47cu;
    v ^= v * 0xb82f1e52u;
    v ^= v * 0xc7afe638u;
    v ^= v * 0x8d22f6e6u;
    return reverseBits(v);
}

// The second dimension of Sobol' (generator matrix: Pascal's triangle mod 2), without a
// loop over the index's bits. Index bit j contributes the column with bit 31 - k set for
// every k whose binary digits are a subset of j's (C(j, k) is odd: Lucas), so bit 31 - k
// of the result is the parity of the index's set bits j that contain k: a superset sum
// over the 5-bit positions, one step per position bit, then reversed.
fn sobol_second(index: u32) -> u32 {
    var x = index;
    x ^= (x >> 1u) & 0x55555555u;
    x ^= (x >> 2u) & 0x33333333u;
    x ^= (x >> 4u) & 0x0f0f0f0fu;
    x ^= (x >> 8u) & 0x00ff00ffu;
    x ^= (x >> 16u) & 0x0000ffffu;
    return reverseBits(x);
}

// A 32-bit fraction to [0, 1): its top 24 bits, so 1.0 is never returned.
fn unit_float(bits: u32) -> f32 {
    return f32(bits >> 8u) * (1.0 / 16777216.0);
}

// The next dimension's hash for this pixel, and the sample index shuffled by it.
fn sobol_dimension() -> vec2<u32> {
    let hash = pcg_hash(rng_pixel ^ pcg_hash(rng_dimension));
    rng_dimension++;
    return vec2<u32>(hash, owen_scramble(rng_index, hash));
}

// Whether the draws are Sobol' points: the sampler compiled into the kernel where it has
// one (FEATURE_FIXED_SAMPLER, src/shader/features.rs), else the one rng_begin was given.
// Lavapipe runs both sides of a branch for the whole SIMD batch; a sampler known when the
// kernel is compiled costs only its own draws.
fn draws_sobol() -> bool {
    if (FEATURE_FIXED_SAMPLER) {
        return FIXED_SAMPLER == SAMPLER_SOBOL;
    }
    return rng_sampler == SAMPLER_SOBOL;
}

// Uniform in [0, 1).
fn rand() -> f32 {
    if (draws_sobol()) {
        let d = sobol_dimension();
        return unit_float(owen_scramble(reverseBits(d.y), pcg_hash(d.x)));
    }
    rng_state = pcg_hash(rng_state);
    return unit_float(rng_state);
}

// Uniform in [0, 1)^2.
fn rand2() -> vec2<f32> {
    if (draws_sobol()) {
        let d = sobol_dimension();
        let x = owen_scramble(reverseBits(d.y), pcg_hash(d.x));
        let y = owen_scramble(sobol_second(d.y), pcg_hash(d.x ^ 0x5bd1e995u));
        return vec2<f32>(unit_float(x), unit_float(y));
    }
    let a = rand();
    return vec2<f32>(a, rand());
}
