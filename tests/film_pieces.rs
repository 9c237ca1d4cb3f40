//! A film larger than one buffer binding is split into pieces of whole rows
//! (`RenderSettings::film_piece_bytes` forces the split on small films): the pieces render
//! the same bits as one buffer would, AOVs included, and a film the memory cannot hold is
//! refused before anything is allocated.

mod common;

use std::sync::Arc;

use common::{fresh_gpu, gpu, settings};
use kiln::render::{RenderControl, RenderSettings, Renderer};
use kiln::scene;

#[test]
fn a_film_split_into_pieces_renders_the_same_bits_as_one_piece_aovs_included() {
    let ctx = gpu();
    let scene = scene::default_scene().expect("bundled scene");
    let mut s = settings(512, 512, 2);
    s.max_bounces = 3;
    s.aovs = true;
    let render = |s: RenderSettings, cuts: &[u32]| {
        let mut r = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
        for pair in cuts.windows(2) {
            let stats = r
                .render(pair[0]..pair[1], RenderControl::default())
                .unwrap();
            assert!(stats.completed);
        }
        let pieces = r.film_pieces();
        (
            pieces,
            r.read_film().unwrap(),
            r.read_aovs().unwrap().unwrap(),
        )
    };
    let (one, film, aovs) = render(s, &[0, 2]);
    assert_eq!(one, 1, "a 512×512 film fits one binding");
    // 100 rows of AOVs (48 bytes a pixel) to a piece at most: six pieces of 85 or 86 rows,
    // four of whose seams fall inside the 256-row tiles of the unsplit film. Rendered in
    // two calls, so passes are cut differently too.
    s.film_piece_bytes = Some(512 * 48 * 100);
    let (pieces, split_film, split_aovs) = render(s, &[0, 1, 2]);
    assert_eq!(pieces, 6);
    assert!(
        split_film == film,
        "the split film differs from the whole one"
    );
    assert_eq!(split_film.sample_count(300, 300), 2);
    assert!(
        (&split_aovs.albedo, &split_aovs.normal, &split_aovs.depth)
            == (&aovs.albedo, &aovs.normal, &aovs.depth),
        "the split AOVs differ from the whole ones"
    );
    // Rows read back across a seam are the same rows.
    let mut r = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
    r.render(0..2, RenderControl::default()).unwrap();
    let band = r.read_film_rows(80..90).unwrap();
    assert_eq!(band.sums[..], film.sums[80 * 512..90 * 512]);
}

#[test]
fn a_film_row_wider_than_a_piece_is_refused_with_the_numbers() {
    let mut s = settings(64, 4, 1);
    s.film_piece_bytes = Some(512);
    let scene = scene::default_scene().expect("bundled scene");
    let err = Renderer::new(gpu(), &scene, s).err().expect("refused");
    let message = err.to_string();
    // 64 pixels of 16 bytes: 1024 bytes, over the 512 allowed.
    assert!(
        message.contains("1024") && message.contains("512"),
        "{message}"
    );
}

#[test]
fn a_device_lost_in_the_middle_of_a_render_fails_it_naming_the_cause_and_the_scene() {
    // A device of its own: destroying it must not touch other tests' renders.
    let ctx = fresh_gpu();
    let scene = scene::default_scene().expect("bundled scene");
    let mut r = Renderer::new(Arc::clone(&ctx), &scene, settings(64, 64, 4096)).unwrap();
    r.render(0..1, RenderControl::default()).unwrap();
    let device = ctx.device.clone();
    let destroyer = std::thread::spawn(move || {
        std::thread::sleep(std::time::Duration::from_millis(300));
        device.destroy();
    });
    let started = std::time::Instant::now();
    let error = r
        .render(1..4096, RenderControl::default())
        .expect_err("a render on a destroyed device cannot succeed")
        .to_string();
    destroyer.join().unwrap();
    assert!(
        started.elapsed() < std::time::Duration::from_secs(60),
        "the render noticed the loss only after {:?}",
        started.elapsed()
    );
    for part in [
        "device",
        "was lost",
        "destroyed",
        "36 triangles",
        "64x64 image",
    ] {
        assert!(error.contains(part), "{part:?} missing from: {error}");
    }
    // Every later use of the renderer says the same, rather than reading garbage.
    let again = r.read_film().unwrap_err().to_string();
    assert!(again.contains("was lost"), "{again}");
}
