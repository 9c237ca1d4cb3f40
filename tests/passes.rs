//! Renders go in whole-image passes, and whatever stops them (a deadline, a cancel) waits
//! for the first: a stopped film has a sample in every pixel, its pixels' counts differ by
//! at most one pass's batch, and its mean is that of a complete render within the noise.

mod common;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use common::{gpu, settings};
use kiln::film::Film;
use kiln::render::{RenderControl, Renderer};
use kiln::scene;

/// Mean luminance of the film's pixels and the standard error of that mean (from the
/// spread of the pixels: image content and noise together, so an upper bound of the noise).
fn mean_and_error(film: &Film) -> (f64, f64) {
    let values: Vec<f64> = film
        .radiance()
        .iter()
        .map(|c| ((c.x + c.y + c.z) / 3.0) as f64)
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// The smallest and largest sample count over the film's pixels.
fn count_range(film: &Film) -> (u64, u64) {
    film.sums
        .iter()
        .map(|s| s[3] as u64)
        .fold((u64::MAX, 0), |(lo, hi), c| (lo.min(c), hi.max(c)))
}

#[test]
fn a_deadline_before_the_first_pass_ends_still_leaves_every_pixel_sampled() {
    let ctx = gpu();
    let scene = scene::default_scene().expect("bundled scene");
    let mut s = settings(64, 64, 64);
    s.max_bounces = 4;
    let mut stopped = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    let stats = stopped
        .render(
            0..64,
            RenderControl {
                deadline: Some(Instant::now()),
                ..RenderControl::default()
            },
        )
        .unwrap();
    assert!(!stats.completed, "the deadline had passed");
    assert_eq!(
        stats.passes, 1,
        "only the first pass, which a stop waits for"
    );
    assert!(stats.first_pass.is_some());
    let film = stopped.read_film().unwrap();
    let (lo, hi) = count_range(&film);
    assert!(lo >= 1, "a pixel without samples");
    assert_eq!(lo, hi, "one whole pass: every pixel the same count");

    let complete = common::render(&ctx, &scene, s);
    let (mean, error) = mean_and_error(&film);
    let (reference, reference_error) = mean_and_error(&complete);
    let tolerance = 4.0 * (error.powi(2) + reference_error.powi(2)).sqrt();
    assert!(
        (mean - reference).abs() <= tolerance,
        "stopped mean {mean} vs complete {reference} (tolerance {tolerance})"
    );
}

#[test]
fn a_cancel_mid_pass_leaves_counts_within_one_batch() {
    let ctx = gpu();
    let scene = scene::default_scene().expect("bundled scene");
    let mut s = settings(96, 96, 1000);
    s.max_bounces = 2;
    // Three pieces of 32 rows: three dispatches a pass, so a cancel can fall inside one.
    s.film_piece_bytes = Some(96 * 16 * 32);

    // Cancelled before it starts: the first pass is still rendered, and nothing more.
    let cancel = AtomicBool::new(true);
    let mut r = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    assert_eq!(r.film_pieces(), 3);
    let stats = r
        .render(
            0..1000,
            RenderControl {
                cancel: Some(&cancel),
                ..RenderControl::default()
            },
        )
        .unwrap();
    assert!(!stats.completed);
    assert_eq!(stats.passes, 1);
    assert_eq!(count_range(&r.read_film().unwrap()), (1, 1));

    // Unless the caller lets a cancel stop the first pass too (and throws the partial
    // film away): then nothing is dispatched, and a cleared film renders as a fresh one.
    let mut abandoned = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    let stats = abandoned
        .render(
            0..1000,
            RenderControl {
                cancel: Some(&cancel),
                cancel_first_pass: true,
                ..RenderControl::default()
            },
        )
        .unwrap();
    assert!(!stats.completed);
    assert_eq!((stats.passes, stats.dispatches), (0, 0));
    abandoned.clear_film();
    abandoned.render(0..1, RenderControl::default()).unwrap();
    let mut fresh = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    fresh.render(0..1, RenderControl::default()).unwrap();
    assert_eq!(
        abandoned.read_film().unwrap().sums,
        fresh.read_film().unwrap().sums
    );

    // Cancelled one dispatch into the third pass.
    let cancel = AtomicBool::new(false);
    let mut batch = 0;
    let mut on_progress = |p: &kiln::render::Progress| {
        if p.passes_done == 2 && p.pass_fraction > 0.0 {
            batch = p.pass_samples;
            cancel.store(true, Ordering::Relaxed);
        }
    };
    let mut r = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    let stats = r
        .render(
            0..1000,
            RenderControl {
                cancel: Some(&cancel),
                progress: Some(&mut on_progress),
                ..RenderControl::default()
            },
        )
        .unwrap();
    assert!(!stats.completed);
    assert_eq!(stats.passes, 2);
    assert_eq!(
        stats.dispatches, 7,
        "two passes of three dispatches, and one more"
    );
    let film = r.read_film().unwrap();
    let (lo, hi) = count_range(&film);
    assert!(lo >= 1);
    assert_eq!(
        hi - lo,
        batch as u64,
        "the rows of the unfinished pass have one batch more"
    );
    // The first piece's rows have the extra batch, the others not.
    assert_eq!(film.sample_count(50, 0), hi);
    assert_eq!(film.sample_count(50, 95), lo);
}

#[test]
fn a_cleared_film_starts_again_with_a_one_sample_first_pass() {
    let ctx = gpu();
    let scene = scene::default_scene().expect("bundled scene");
    let s = settings(16, 16, 500);
    let mut r = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    // Short dispatches: the batch grows well past one sample per pass.
    let stats = r.render(0..500, RenderControl::default()).unwrap();
    assert!(
        stats.passes < 100,
        "{} passes for 500 samples",
        stats.passes
    );
    assert!(r.has_whole_pass());
    r.clear_film();
    assert!(!r.has_whole_pass());
    let cancel = AtomicBool::new(true);
    let stats = r
        .render(
            0..500,
            RenderControl {
                cancel: Some(&cancel),
                ..RenderControl::default()
            },
        )
        .unwrap();
    assert_eq!(stats.passes, 1);
    assert_eq!(
        count_range(&r.read_film().unwrap()),
        (1, 1),
        "the first pass is one sample"
    );
}
