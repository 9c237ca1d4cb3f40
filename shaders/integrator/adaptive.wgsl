// Adaptive sampling (Cycles' noise threshold): the renderer runs these two entry points
// over the film at fixed sample counts (`Renderer::render`), so that which pixels stop, and
// when, depends on the samples alone and not on how the work was timed.
//
// A pixel's noise is the half-width of the 90 % confidence interval of its mean's
// r + g + b, relative to the square root of that mean (the compromise between absolute
// and relative error that Cycles' threshold uses):
//
//     e = 1.645 · sqrt(s² / n) / (10⁻⁴ + sqrt(mean)),
//
// with s² the sample variance of the samples' r + g + b over the pixel's n samples. So a
// pixel whose estimate is below a threshold T has its mean within T · sqrt(mean) of the
// converged value with 90 % confidence, where its samples' variance is estimated right
// (`tests/adaptive.rs` checks that on a scene with a reference).
//
// Dispatched over one film piece at a time: `tile_origin` is the piece's first row (x 0),
// `tile_size` its width and rows.

const NOISE_CONFIDENCE: f32 = 1.645;
/// The estimate of a pixel with fewer than two samples: unknown, so never converged.
const NOISE_UNKNOWN: f32 = 3.0e38;

fn noise_estimate(index: u32) -> f32 {
    let sum = film_value(film_sum[index], film_high[index]);
    let n = sum.w;
    if (n < 2.0) {
        return NOISE_UNKNOWN;
    }
    let mean = max((sum.x + sum.y + sum.z) / n, 0.0);
    let m = film_noise[index];
    let second = (m.x - m.y) / n;
    let variance = max(second - mean * mean, 0.0) * n / (n - 1.0);
    return NOISE_CONFIDENCE * sqrt(variance / n) / (1.0e-4 + sqrt(mean));
}

/// The index in the bound piece of film pixel `px`.
fn noise_index(px: vec2<u32>) -> u32 {
    return px.y * params.film_size.x + px.x - params.film_piece_start;
}

/// Writes each pixel's noise estimate (z of `film_noise`); a converged pixel keeps the
/// estimate it stopped with, which its samples still have.
@compute @workgroup_size(8, 8)
fn adaptive_error(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.tile_size.x || gid.y >= params.tile_size.y) {
        return;
    }
    let index = noise_index(params.tile_origin + gid.xy);
    var m = film_noise[index];
    if (m.w != 0.0) {
        return;
    }
    m.z = noise_estimate(index);
    film_noise[index] = m;
}

/// Marks converged (w = 1) the pixels whose estimate, and those of their eight neighbours
/// in the piece, are below the threshold: a pixel next to a noisy one keeps sampling, so
/// that a noisy area is not cut short at its edges by pixels that look converged by
/// chance. Counts the pixels left in `stats.active_pixels`.
@compute @workgroup_size(8, 8)
fn adaptive_converge(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.tile_size.x || gid.y >= params.tile_size.y) {
        return;
    }
    let px = params.tile_origin + gid.xy;
    let index = noise_index(px);
    let m = film_noise[index];
    if (m.w != 0.0) {
        return;
    }
    var worst = m.z;
    let lo = vec2<i32>(0, i32(params.tile_origin.y));
    let hi = vec2<i32>(i32(params.film_size.x), i32(params.tile_origin.y + params.tile_size.y)) - 1;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = clamp(vec2<i32>(px) + vec2<i32>(dx, dy), lo, hi);
            worst = max(worst, film_noise[noise_index(vec2<u32>(q))].z);
        }
    }
    if (worst < params.noise_threshold) {
        // Only w: neighbours read z meanwhile.
        film_noise[index].w = 1.0;
    } else {
        atomicAdd(&stats.active_pixels, 1u);
    }
}
