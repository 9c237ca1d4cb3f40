//! Checkpoint and resume: a render continued from its film's state, in the same process or
//! from `kiln render --resume`, is bit for bit the uninterrupted render; a checkpoint of
//! other settings is refused; a finished render removes its checkpoint.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::{Arc, OnceLock};
use std::time::Instant;

use common::exr::{Exr, read_exr};
use common::{gpu, settings};
use kiln::render::{RenderControl, RenderSettings, Renderer};
use kiln::scene::default_scene;

/// The film, AOVs and noise estimate after `render` ran on a new renderer.
fn state(r: &Renderer) -> (Vec<[f64; 4]>, Option<kiln::render::Aovs>, Option<Vec<f32>>) {
    (
        r.read_film().unwrap().sums,
        r.read_aovs().unwrap(),
        r.read_noise().unwrap(),
    )
}

#[test]
fn a_render_resumed_from_its_film_state_is_the_uninterrupted_one() {
    let ctx = gpu();
    let scene = default_scene().unwrap();
    for (aovs, noise_threshold) in [(false, 0.0), (true, 0.3)] {
        let s = RenderSettings {
            aovs,
            noise_threshold,
            ..settings(24, 24, 40)
        };
        let mut whole = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
        whole.render(0..40, RenderControl::default()).unwrap();

        // Stopped at the end of its first pass by a deadline already past.
        let mut first = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
        let stats = first
            .render(
                0..40,
                RenderControl {
                    pass_deadline: Some(Instant::now()),
                    ..RenderControl::default()
                },
            )
            .unwrap();
        assert!(stats.checkpoint && !stats.completed);
        assert!(
            (1..40).contains(&stats.next_sample),
            "{}",
            stats.next_sample
        );
        let saved = first.film_state().unwrap();

        let mut resumed = Renderer::new(Arc::clone(&ctx), &scene, s).unwrap();
        resumed.restore_film_state(&saved).unwrap();
        let rest = resumed
            .render(stats.next_sample..40, RenderControl::default())
            .unwrap();
        assert!(rest.completed && !rest.checkpoint);
        assert_eq!(
            state(&resumed),
            state(&whole),
            "AOVs {aovs}, threshold {noise_threshold}"
        );

        // A state from another film is refused, not written over this one.
        let mut other = Renderer::new(Arc::clone(&ctx), &scene, settings(16, 16, 1)).unwrap();
        let e = other.restore_film_state(&saved).unwrap_err().to_string();
        assert!(e.contains("does not fit"), "{e}");
    }
}

fn kiln(args: &[&str], output: &Path) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kiln"))
        .arg("render")
        .args(args)
        .args(["-q", "-o"])
        .arg(output)
        .output()
        .expect("kiln runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The render both resume tests interrupt: 300 spp at 48×48 takes ~4 s here.
const ARGS: [&str; 4] = ["--size", "48x48", "--spp", "300"];

/// `ARGS` rendered without interruption, once for both tests.
fn uninterrupted() -> &'static Exr {
    static WHOLE: OnceLock<Exr> = OnceLock::new();
    WHOLE.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("whole.exr");
        let (ok, err) = kiln(&ARGS, &path);
        assert!(ok, "{err}");
        read_exr(&path)
    })
}

/// Asserts that the colour, sample counts, noise estimate and AOVs of a resumed render
/// agree with the uninterrupted one's bit for bit.
fn assert_uninterrupted(resumed: &Path) {
    let (whole, resumed) = (uninterrupted(), read_exr(resumed));
    for channel in [
        "R",
        "G",
        "B",
        "samples.Y",
        "noise.Y",
        "albedo.R",
        "normal.X",
    ] {
        assert_eq!(
            whole.channel(channel),
            resumed.channel(channel),
            "channel {channel} differs"
        );
    }
}

/// Killed with SIGKILL mid-render (no chance to write anything on its way out), then
/// `--resume`d from the last checkpoint it wrote: the uninterrupted render, bit for bit.
#[test]
fn a_render_killed_mid_way_resumes_to_the_uninterrupted_render_bit_for_bit() {
    // The reference first, so that its render does not share the cores with the one
    // interrupted below.
    uninterrupted();
    let dir = tempfile::tempdir().unwrap();
    let killed_path = dir.path().join("killed.exr");
    // After the first checkpoint, ~3 s of the render are left to kill it in.
    let checkpoint = dir.path().join("killed.exr.kiln-checkpoint");
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiln"))
        .arg("render")
        .args(ARGS)
        .args(["--checkpoint-every", "0.1", "-q", "-o"])
        .arg(&killed_path)
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("kiln starts");
    let start = Instant::now();
    while !checkpoint.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render ended before its first checkpoint"
        );
        assert!(start.elapsed().as_secs() < 120, "no checkpoint was written");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    // Past the first checkpoint, into the next pass.
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the render finished before it could be killed"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!killed_path.exists(), "a killed render wrote its image");

    let resume = [&ARGS[..], &["--resume"]].concat();
    let (ok, err) = kiln(&resume, &killed_path);
    assert!(ok, "{err}");
    assert!(err.contains("resuming from"), "{err}");
    assert!(!checkpoint.exists());
    assert_uninterrupted(&killed_path);
}

#[test]
fn kiln_render_resume_continues_a_stopped_render_bit_for_bit() {
    // The reference first, as above.
    uninterrupted();
    let dir = tempfile::tempdir().unwrap();
    let stopped_path = dir.path().join("cut.exr");
    // Stopped by its time limit after a few checkpoints.
    let stop = [
        &ARGS[..],
        &["--time-limit", "1", "--checkpoint-every", "0.1"],
    ]
    .concat();
    let (ok, err) = kiln(&stop, &stopped_path);
    assert!(ok, "{err}");
    let checkpoint = dir.path().join("cut.exr.kiln-checkpoint");
    assert!(err.contains("--resume continues"), "{err}");
    assert!(checkpoint.exists());

    // Other settings: refused, the checkpoint and the image left as they were.
    let before = std::fs::read(&stopped_path).unwrap();
    let other = [&ARGS[..], &["--seed", "3", "--resume"]].concat();
    let (ok, err) = kiln(&other, &stopped_path);
    assert!(
        !ok && err.contains("another scene or other settings"),
        "{err}"
    );
    assert_eq!(std::fs::read(&stopped_path).unwrap(), before);

    let resume = [&ARGS[..], &["--resume"]].concat();
    let (ok, err) = kiln(&resume, &stopped_path);
    assert!(ok, "{err}");
    assert!(err.contains("resuming from"), "{err}");
    assert!(
        !checkpoint.exists(),
        "a finished render removes its checkpoint"
    );
    assert_uninterrupted(&stopped_path);

    // Nothing to resume from: said, and nothing written.
    let (ok, err) = kiln(&resume, &dir.path().join("new.exr"));
    assert!(!ok && err.contains("cannot resume from"), "{err}");
    assert!(!dir.path().join("new.exr").exists());

    // A checkpoint that is not a file (a FIFO, which would block whoever opens it):
    // refused at once, naming it.
    let fifo = dir.path().join("fifo.exr.kiln-checkpoint");
    let made = Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", fifo.display());
    let (ok, err) = kiln(&resume, &dir.path().join("fifo.exr"));
    assert!(!ok && err.contains("not a regular file"), "{err}");
}
