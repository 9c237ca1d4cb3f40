//! A render is a pure function of (scene, settings, seed, sample range): repeated renders
//! are bit-identical, sample ranges rendered apart merge into the whole bit for bit, and the film's
//! sums do not drift over 10^5 samples.

mod common;

use std::sync::Arc;

use common::{furnace_scene, gpu, render, settings};
use glam::Vec3;
use kiln::film::ExactFilm;
use kiln::render::{RenderControl, Renderer};
use kiln::scene::{self, Camera, Scene};

fn cornell() -> Scene {
    scene::default_scene().expect("bundled scene")
}

#[test]
fn same_seed_renders_are_bit_identical() {
    let ctx = gpu();
    let s = settings(32, 32, 8);
    let a = render(&ctx, &cornell(), s);
    let b = render(&ctx, &cornell(), s);
    assert!(a == b, "two renders with the same seed differ");
    let mut other = s;
    other.seed = 2;
    assert!(
        render(&ctx, &cornell(), other) != a,
        "the seed has no effect"
    );
}

/// The editor renders its thumbnails, node previews and final renders on a second device
/// of the adapter (`GpuContext::sibling`), so that their submissions never wait behind the
/// window's or hold them up: a device of its own, which renders the same bits.
#[test]
fn a_sibling_device_is_a_device_of_its_own_and_renders_the_same_bits() {
    let ctx = gpu();
    let sibling = ctx.sibling().expect("a second device on the adapter");
    assert!(
        sibling.device != ctx.device,
        "the sibling shares the device"
    );
    assert_eq!(sibling.describe(), ctx.describe());
    let s = settings(32, 32, 4);
    let here = render(&ctx, &cornell(), s);
    let there = render(&sibling, &cornell(), s);
    assert!(here == there, "the sibling device's film differs");
}

#[test]
fn split_sample_ranges_merge_into_the_whole() {
    let ctx = gpu();
    let s = settings(32, 32, 24);
    let whole = render(&ctx, &cornell(), s);

    // The same renderer continuing from sample 7: exactly the same bits, because each
    // pixel adds its samples in index order whatever the dispatch cut.
    let mut r = Renderer::new(Arc::clone(&ctx), &cornell(), s).unwrap();
    r.render(0..7, RenderControl::default()).unwrap();
    r.render(7..24, RenderControl::default()).unwrap();
    assert!(
        r.read_film().unwrap() == whole,
        "continuing a render changed its result"
    );

    // Separate renderers (as on two machines), merged in any order: the same bits, since
    // the film's sums are fixed point and integer addition is associative.
    let exact_whole = {
        let mut r = Renderer::new(Arc::clone(&ctx), &cornell(), s).unwrap();
        r.render(0..24, RenderControl::default()).unwrap();
        r.read_exact_film().unwrap()
    };
    assert!(exact_whole.to_film() == whole);
    let part = |range: std::ops::Range<u32>| {
        let mut r = Renderer::new(Arc::clone(&ctx), &cornell(), s).unwrap();
        r.render(range, RenderControl::default()).unwrap();
        r.read_exact_film().unwrap()
    };
    let (a, b, c) = (part(0..5), part(5..17), part(17..24));
    for order in [[&a, &b, &c], [&c, &a, &b]] {
        let mut merged = ExactFilm::new(s.width, s.height);
        for p in order {
            merged.merge(p).unwrap();
        }
        assert!(merged == exact_whole, "merged parts differ from the whole");
        assert!(merged.to_film() == whole);
    }
}

#[test]
fn aovs_do_not_depend_on_how_a_render_is_cut_into_dispatches() {
    // The AOV layers, like the film, add sample by sample in index order: one call, or
    // two cut anywhere, give the same bits (the batch size adapts to time, so a render
    // cuts where the clock says).
    let ctx = gpu();
    let mut s = settings(32, 32, 24);
    s.aovs = true;
    let aovs = |cuts: &[u32]| {
        let mut r = Renderer::new(Arc::clone(&ctx), &cornell(), s).unwrap();
        for pair in cuts.windows(2) {
            r.render(pair[0]..pair[1], RenderControl::default())
                .unwrap();
        }
        r.read_aovs().unwrap().expect("AOVs asked for")
    };
    let whole = aovs(&[0, 24]);
    for cuts in [&[0, 7, 24][..], &[0, 1, 2, 3, 24], &[0, 23, 24]] {
        let cut = aovs(cuts);
        assert!(
            (&cut.albedo, &cut.normal, &cut.depth) == (&whole.albedo, &whole.normal, &whole.depth),
            "AOVs rendered in dispatches {cuts:?} differ from one dispatch"
        );
    }
}

#[test]
fn film_does_not_drift_over_100000_samples() {
    let ctx = gpu();
    // Nothing but an environment whose radiance is not a binary fraction: every sample is
    // the same f32, so the exact mean is known. Plain f32 summation would be off by ~1e-3.
    let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    scene.environment = Vec3::new(0.7, 0.1, 3.3);
    let film = render(&ctx, &scene, settings(4, 4, 100_000));
    for y in 0..4 {
        for x in 0..4 {
            assert_eq!(film.sample_count(x, y), 100_000);
            let p = film.pixel(x, y);
            let rel = ((p - scene.environment) / scene.environment)
                .abs()
                .max_element();
            assert!(rel < 1e-6, "pixel ({x}, {y}) = {p}, relative error {rel}");
        }
    }
}

#[test]
fn every_pixel_receives_exactly_its_samples_on_long_paths() {
    // Paths that bounce many times in long dispatches: lavapipe once dropped whole SIMD
    // rows of samples when one dispatch carried hundreds of samples per pixel.
    let ctx = gpu();
    let f = render(&ctx, &furnace_scene(1.0, 1.0), settings(4, 4, 1000));
    for y in 0..4 {
        for x in 0..4 {
            assert_eq!(f.sample_count(x, y), 1000, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn the_film_adds_fixed_point_samples_exactly_and_saturates_instead_of_wrapping() {
    let ctx = gpu();
    let step = (ExactFilm::FRACTION_BITS as f64).exp2();
    let exact = |environment: Vec3, spp: u32| {
        let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
        scene.environment = environment;
        let mut r = Renderer::new(Arc::clone(&ctx), &scene, settings(2, 2, spp)).unwrap();
        r.render(0..spp, RenderControl::default()).unwrap();
        r.read_exact_film().unwrap()
    };
    // Every sample the same f32: the sum is the count times its rounded value, carries
    // into the high word included (3.3 · 2^28 · 10^4 > 2^32).
    let v = Vec3::new(0.7, 0.1, 3.3);
    let film = exact(v, 10_000);
    for s in &film.sums {
        for c in 0..3 {
            assert_eq!(s[c], 10_000 * (v[c] as f64 * step).round() as i64);
        }
    }
    // A sample is clamped to 2^24; a sum saturates at the high word's limit.
    let film = exact(Vec3::new(1e9, 1e7, 0.0), 4096);
    for s in &film.sums {
        assert_eq!(
            s[0] >> 32,
            ExactFilm::HIGH_LIMIT,
            "saturated, not wrapped: {s:?}"
        );
        assert_eq!(
            s[1] >> 32,
            ExactFilm::HIGH_LIMIT,
            "saturated, not wrapped: {s:?}"
        );
        assert_eq!(s[2], 0);
    }
    let film = exact(Vec3::new(1e9, 0.0, 0.0), 16);
    assert_eq!(film.sums[0][0], 16 * (2f64.powi(24) * step) as i64);
}
