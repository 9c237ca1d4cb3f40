//! Adaptive sampling (`--noise-threshold`): the noise estimate is calibrated against a
//! reference, pixels stop only at the fixed check counts, and the same seed and threshold
//! give the same bits however the render is cut into calls and passes.

mod common;

use std::sync::Arc;

use common::{gpu, settings};
use kiln::film::Film;
use kiln::render::{
    GpuContext, Pacing, RenderControl, RenderSettings, Renderer, is_adaptive_check,
    next_adaptive_check,
};
use kiln::scene::{Scene, default_scene};
use kiln::shader::sampling::Sampler;

const SIZE: u32 = 32;

/// Renders samples up to each of `ends` in turn (one call each) and returns the film, the noise estimate and the render's
/// last count of pixels not converged.
fn render_in(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: RenderSettings,
    pacing: Pacing,
    ends: &[u32],
) -> (Film, Vec<f32>, Option<u64>) {
    let mut r = Renderer::new(Arc::clone(ctx), scene, settings).expect("renderer");
    r.set_pacing(pacing);
    let mut active = None;
    let mut start = 0;
    for &end in ends {
        let stats = r
            .render(start..end, RenderControl::default())
            .expect("render");
        assert!(stats.completed);
        assert_eq!(stats.non_finite, 0);
        active = stats.active_pixels.or(active);
        start = end;
    }
    let noise = r
        .read_noise()
        .expect("noise")
        .expect("the noise is estimated");
    (r.read_film().expect("film"), noise, active)
}

fn adaptive(threshold: f32, spp: u32, sampler: Sampler) -> RenderSettings {
    let mut s = settings(SIZE, SIZE, spp);
    s.noise_threshold = threshold;
    s.sampling.sampler = sampler;
    s
}

/// A pixel's r + g + b.
fn total(film: &Film, x: u32, y: u32) -> f64 {
    let p = film.pixel(x, y);
    (p.x + p.y + p.z) as f64
}

#[test]
fn the_check_counts_follow_the_schedule() {
    let checks: Vec<u32> = std::iter::successors(Some(next_adaptive_check(0)), |&c| {
        Some(next_adaptive_check(c))
    })
    .take_while(|&c| c <= 512)
    .collect();
    assert_eq!(
        checks,
        [
            16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240, 256, 288, 320,
            352, 384, 432, 480
        ]
    );
    for n in 0..=512 {
        assert_eq!(is_adaptive_check(n), checks.contains(&n), "{n}");
    }
}

/// Of the pixels the estimate stops, at least 90 % are within the threshold of a
/// reference (2048 Sobol' samples): the estimate is a 90 % confidence bound, with the
/// neighbourhood rule making it safer. Checked with independent samples, which the
/// variance estimate assumes, and with the default Sobol' samples, whose error is lower
/// than the estimate says.
#[test]
fn pixels_marked_converged_are_within_the_threshold_of_a_reference() {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let reference = common::render(&ctx, &scene, settings(SIZE, SIZE, 2048));
    let threshold = 0.15;
    let cap = 512;
    for sampler in [Sampler::Independent, Sampler::Sobol] {
        let (film, noise, active) = render_in(
            &ctx,
            &scene,
            adaptive(threshold, cap, sampler),
            Pacing::Final,
            &[cap],
        );
        let mut converged = 0;
        let mut within = 0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                let n = film.sample_count(x, y) as u32;
                let i = (y * SIZE + x) as usize;
                assert!(noise[i].is_finite() && noise[i] >= 0.0, "{}", noise[i]);
                if n == cap {
                    continue;
                }
                assert!(
                    is_adaptive_check(n),
                    "pixel ({x}, {y}) stopped at {n} samples, not at a check"
                );
                assert!(noise[i] < threshold, "({x}, {y}): {}", noise[i]);
                converged += 1;
                let truth = total(&reference, x, y);
                let error = (total(&film, x, y) - truth).abs() / (1e-4 + truth.sqrt());
                within += (error <= threshold as f64) as u32;
            }
        }
        let pixels = SIZE * SIZE;
        assert_eq!(active, Some((pixels - converged) as u64), "{sampler:?}");
        // The test means something only if the threshold stops most pixels early.
        assert!(
            converged > pixels / 2,
            "{sampler:?}: only {converged} of {pixels} pixels converged"
        );
        let share = within as f64 / converged as f64;
        assert!(
            share >= 0.9,
            "{sampler:?}: {within} of {converged} converged pixels ({:.1} %) are within the threshold",
            share * 100.0
        );
    }
}

/// Samples go where the noise is: the converged pixels took fewer samples than the cap,
/// and a tighter threshold takes more samples everywhere it stops.
#[test]
fn a_tighter_threshold_takes_more_samples() {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let samples = |t: f32| {
        let (film, _, _) = render_in(
            &ctx,
            &scene,
            adaptive(t, 256, Sampler::Sobol),
            Pacing::Final,
            &[256],
        );
        film.total_samples()
    };
    let (loose, tight) = (samples(0.3), samples(0.1));
    let all = (SIZE * SIZE * 256) as u64;
    assert!(
        loose < tight && tight < all,
        "loose {loose}, tight {tight}, all {all}"
    );
}

#[test]
fn adaptive_sampling_gives_the_same_bits_however_the_render_is_cut() {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let s = adaptive(0.2, 160, Sampler::Sobol);
    let whole = render_in(&ctx, &scene, s, Pacing::Final, &[160]);
    let cut = render_in(
        &ctx,
        &scene,
        s,
        Pacing::Interactive { budget_us: 2000 },
        &[37, 100, 160],
    );
    assert!(whole.2.is_some_and(|a| a < (SIZE * SIZE) as u64));
    assert_eq!(whole.0.sums, cut.0.sums, "films differ");
    assert_eq!(whole.1, cut.1, "noise estimates differ");
    assert_eq!(whole.2, cut.2);
}

#[test]
fn without_a_threshold_every_pixel_takes_every_sample() {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    let s = RenderSettings {
        aovs: true,
        ..settings(SIZE, SIZE, 48)
    };
    let (film, noise, active) = render_in(&ctx, &scene, s, Pacing::Final, &[48]);
    assert_eq!(active, None);
    assert_eq!(film.total_samples(), (SIZE * SIZE * 48) as u64);
    // The estimate is still there (an AOV), and it says something: the light's edge and
    // the shadows are noisier than the lit walls.
    let finite: Vec<f32> = noise.iter().copied().filter(|e| e.is_finite()).collect();
    assert_eq!(finite.len(), noise.len());
    let max = finite.iter().copied().fold(0.0, f32::max);
    let min = finite.iter().copied().fold(f32::MAX, f32::min);
    assert!(max > 4.0 * min.max(1e-3), "noise from {min} to {max}");
}
