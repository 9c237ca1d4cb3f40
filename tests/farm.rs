//! Split renders: any partition of a render's samples merges to the very film of the
//! whole (a property test on the renderer), `kiln render --samples` and `kiln merge` give
//! the bits of the unsplit render and refuse parts that do not belong together, and
//! `--frames`/`--turntable` render numbered frames.

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::sync::Arc;

use common::exr::read_exr;
use common::{gpu, settings};
use kiln::film::ExactFilm;
use kiln::render::{RenderControl, Renderer};
use proptest::prelude::*;

fn kiln(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kiln"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("kiln runs")
}

fn ok(out: Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "kiln failed: {stderr}");
    stderr
}

fn fails(out: Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "kiln succeeded: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

/// The cut points of a partition of `0..total` into at most 6 ranges.
fn partition(total: u32) -> impl Strategy<Value = Vec<u32>> {
    proptest::collection::btree_set(1..total, 0..6).prop_map(move |cuts| {
        let mut points = vec![0];
        points.extend(cuts);
        points.push(total);
        points
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn merging_any_partition_of_the_samples_gives_the_whole_bit_for_bit(
        points in partition(40),
        reversed in any::<bool>(),
    ) {
        thread_local! {
            static WHOLE: (Arc<kiln::render::GpuContext>, ExactFilm) = {
                let ctx = gpu();
                let mut r = Renderer::new(Arc::clone(&ctx), &kiln::scene::default_scene().unwrap(), settings(12, 10, 40)).unwrap();
                r.render(0..40, RenderControl::default()).unwrap();
                let film = r.read_exact_film().unwrap();
                (ctx, film)
            };
        }
        WHOLE.with(|(ctx, whole)| {
            // Each part in a renderer of its own, as on machines of their own.
            let mut parts: Vec<ExactFilm> = points
                .windows(2)
                .map(|w| {
                    let scene = kiln::scene::default_scene().unwrap();
                    let mut r = Renderer::new(Arc::clone(ctx), &scene, settings(12, 10, 40)).unwrap();
                    r.render(w[0]..w[1], RenderControl::default()).unwrap();
                    r.read_exact_film().unwrap()
                })
                .collect();
            if reversed {
                parts.reverse();
            }
            let mut merged = ExactFilm::new(12, 10);
            for p in &parts {
                merged.merge(p).unwrap();
            }
            prop_assert!(&merged == whole, "the parts {points:?} merge to another film");
            Ok(())
        })?;
    }
}

#[test]
fn kiln_merge_gives_the_bits_of_the_unsplit_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let common = ["--size", "40x30", "--spp", "24", "-q"];
    let render = |extra: &[&str]| ok(kiln(d, &[&["render"][..], &common, extra].concat()));
    render(&["-o", "whole.exr"]);
    render(&["-o", "whole.png"]);
    for (range, name) in [("0..7", "a.exr"), ("7..8", "b.exr"), ("8..24", "c.exr")] {
        let said = render(&["--samples", range, "-o", name]);
        assert!(said.contains(&format!("samples {range} of 24")), "{said}");
    }
    ok(kiln(
        d,
        &["merge", "c.exr", "a.exr", "b.exr", "-o", "merged.exr"],
    ));
    ok(kiln(
        d,
        &["merge", "a.exr", "b.exr", "c.exr", "-o", "merged.png"],
    ));
    let (whole, merged) = (
        read_exr(&d.join("whole.exr")),
        read_exr(&d.join("merged.exr")),
    );
    for c in ["R", "G", "B", "samples.Y"] {
        let same = whole
            .channel(c)
            .iter()
            .zip(merged.channel(c))
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same,
            "channel {c} of the merged image differs from the whole render's"
        );
    }
    assert_eq!(
        std::fs::read(d.join("whole.png")).unwrap(),
        std::fs::read(d.join("merged.png")).unwrap(),
        "the merged PNG differs from the whole render's"
    );
    // A part is an image any viewer shows: its mean radiance is in R, G, B.
    let part = read_exr(&d.join("c.exr"));
    assert!(part.mean().iter().all(|&m| m > 0.01), "{:?}", part.mean());

    // Parts that do not belong together, or do not cover the render.
    let e = fails(kiln(d, &["merge", "a.exr", "c.exr", "-o", "x.png"]));
    assert!(
        e.contains("samples 7..8 of 24 per pixel are in none of the parts"),
        "{e}"
    );
    let e = ok(kiln(
        d,
        &["merge", "a.exr", "c.exr", "--allow-partial", "-o", "x.png"],
    ));
    assert!(
        e.contains("samples 7..8 of 24 per pixel are missing"),
        "{e}"
    );
    render(&["--samples", "6..9", "-o", "overlap.exr"]);
    let e = fails(kiln(
        d,
        &["merge", "a.exr", "overlap.exr", "c.exr", "-o", "x.png"],
    ));
    assert!(
        e.contains("a.exr (samples 0..7) and overlap.exr (samples 6..9) overlap"),
        "{e}"
    );
    render(&["--samples", "7..8", "--seed", "5", "-o", "seeded.exr"]);
    let e = fails(kiln(
        d,
        &["merge", "a.exr", "seeded.exr", "c.exr", "-o", "x.png"],
    ));
    assert!(e.contains("are not parts of one render"), "{e}");
    let e = fails(kiln(d, &["merge", "whole.exr", "-o", "x.png"]));
    assert!(e.contains("whole.exr is not a usable part"), "{e}");
    assert!(!d.join("x.exr").exists());

    // What a part cannot be.
    let e = fails(kiln(
        d,
        &[
            &["render"][..],
            &common,
            &["--samples", "0..4", "-o", "p.png"],
        ]
        .concat(),
    ));
    assert!(e.contains("name the output .exr"), "{e}");
    let e = fails(kiln(
        d,
        &[
            &["render"][..],
            &common,
            &["--samples", "0..30", "-o", "p.exr"],
        ]
        .concat(),
    ));
    assert!(
        e.contains("goes past the render's 24 samples per pixel"),
        "{e}"
    );
    let e = fails(kiln(
        d,
        &[
            &["render"][..],
            &common,
            &[
                "--samples",
                "0..4",
                "--noise-threshold",
                "0.05",
                "-o",
                "p.exr",
            ],
        ]
        .concat(),
    ));
    assert!(e.contains("adaptive sampling"), "{e}");
    let e = fails(kiln(
        d,
        &[
            &["render"][..],
            &common,
            &["--samples", "4..2", "-o", "p.exr"],
        ]
        .concat(),
    ));
    assert!(e.contains("is empty"), "{e}");
}

#[test]
fn a_turntable_renders_numbered_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = [
        "render",
        "--size",
        "24x16",
        "--spp",
        "2",
        "-q",
        "--frames",
        "3..6",
        "--turntable",
        "90",
    ];
    ok(kiln(d, &[&args[..], &["-o", "turn_##.png"]].concat()));
    let frames: Vec<Vec<u8>> = (3..6)
        .map(|f| std::fs::read(d.join(format!("turn_0{f}.png"))).unwrap())
        .collect();
    assert!(
        frames[0] != frames[1] && frames[1] != frames[2],
        "the camera does not move"
    );
    // One frame alone (what an array task renders) is the same image.
    ok(kiln(
        d,
        &[&args[..], &["--frame", "4", "-o", "single.png"]].concat(),
    ));
    assert_eq!(std::fs::read(d.join("single_0004.png")).unwrap(), frames[1]);
    let e = fails(kiln(
        d,
        &[&args[..], &["--frame", "9", "-o", "x.png"]].concat(),
    ));
    assert!(e.contains("--frame 9 is not one of --frames 3..6"), "{e}");
}
