//! Ctrl-C during `kiln render` (README: "Ctrl-C stops early and still writes what has
//! accumulated (a second Ctrl-C quits at once)", and files are written atomically): a
//! real `kiln` process gets real SIGINTs, sent with `kill -INT`. A render stopped by
//! Ctrl-C or by its time limit, even during its first pass over the image, writes a
//! sample in every pixel (the EXR's `samples` layer) and the mean of a complete render.
#![cfg(unix)]

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::OnceLock;
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use common::exr::{Exr, read_exr};

/// Hang guard for anything these tests wait on; never a pass/fail timing.
const PATIENCE: Duration = Duration::from_secs(120);

/// `kiln render` with `args`, its stderr lines arriving on the receiver.
fn spawn_render(args: &[&str], out: &Path) -> (Child, Receiver<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiln"))
        .arg("render")
        .args(args)
        .args(["-q", "-o"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("kiln starts");
    let stderr = child.stderr.take().unwrap();
    let (send, lines) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                break;
            }
        }
    });
    (child, lines)
}

/// Waits for the "scene:" line, which kiln prints once its Ctrl-C handler is installed
/// (src/main.rs); returns the lines read so far.
fn wait_until_rendering(child: &mut Child, lines: &Receiver<String>) -> Vec<String> {
    let mut seen = Vec::new();
    let deadline = Instant::now() + PATIENCE;
    while Instant::now() < deadline {
        match lines.recv_timeout(Duration::from_millis(200)) {
            Ok(line) => {
                let ready = line.starts_with("scene:");
                seen.push(line);
                if ready {
                    return seen;
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
        }
    }
    let _ = child.kill();
    panic!("kiln did not start rendering:\n{}", seen.join("\n"));
}

/// SIGINT, as Ctrl-C sends it, through the shell's `kill` (a builtin wherever there
/// is a shell, unlike a `kill` executable).
fn interrupt(child: &Child) {
    let status = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .expect("sh runs");
    assert!(status.success(), "kill -INT {} failed", child.id());
}

/// The exit status, and the rest of stderr once the process has ended.
fn finish(mut child: Child, lines: &Receiver<String>) -> (ExitStatus, String) {
    let deadline = Instant::now() + PATIENCE;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("kiln did not end within {PATIENCE:?} of Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    // The reader thread ends with the pipe.
    let rest: Vec<String> = lines.iter().collect();
    (status, rest.join("\n"))
}

/// Asserts that `dir` holds `name` and nothing else: the temporary file was renamed.
fn assert_only_file(dir: &Path, name: &str) {
    let names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, [name], "the temporary file was renamed");
}

#[test]
fn ctrl_c_stops_the_render_and_writes_what_accumulated() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("partial.exr");
    // Hours of work at 32×32 on lavapipe (≈ 0.1 Msamples/s).
    let (mut child, lines) = spawn_render(&["--size", "32x32", "--spp", "1000000"], &out);
    wait_until_rendering(&mut child, &lines);
    // Let some samples accumulate (measured: ≈ 100 spp per second at 32×32).
    std::thread::sleep(Duration::from_secs(1));
    interrupt(&child);
    let (status, err) = finish(child, &lines);
    assert!(status.success(), "{status}:\n{err}");
    let summary = err
        .lines()
        .find(|l| l.starts_with("wrote "))
        .unwrap_or_else(|| panic!("no summary:\n{err}"));
    assert!(summary.contains("(interrupted)"), "{summary}");
    let average: f64 = summary
        .split_whitespace()
        .nth(2)
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no spp average in \"{summary}\""));
    assert!(
        average > 0.0 && average < 1_000_000.0,
        "{average} spp average: {summary}"
    );
    // A complete image of what accumulated, not a black or uniform one.
    common::assert_lit_image(&out, 32, 32);
    assert_only_file(dir.path(), "partial.exr");
}

#[test]
fn a_second_ctrl_c_quits_at_once_without_a_half_written_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.png");
    // A large image, so that after the first Ctrl-C the rest of the first pass (which a
    // first Ctrl-C waits for; tens of seconds at 2048×2048 on lavapipe), reading the film
    // back, tonemapping and encoding it take long enough for the second to arrive first.
    let (mut child, lines) = spawn_render(&["--size", "2048x2048", "--spp", "1000000"], &out);
    wait_until_rendering(&mut child, &lines);
    interrupt(&child);
    // Apart, so that the two signals are not merged into one pending SIGINT.
    std::thread::sleep(Duration::from_millis(50));
    interrupt(&child);
    let (status, err) = finish(child, &lines);
    // 130: the exit of the second Ctrl-C (128 + SIGINT), not the end of a complete write.
    assert_eq!(status.code(), Some(130), "{status}:\n{err}");
    assert!(!err.contains("wrote "), "{err}");
    // The image is absent or complete, never truncated.
    if out.exists() {
        let img = image::open(&out).expect("a complete image");
        assert_eq!((img.width(), img.height()), (2048, 2048));
    }
    // And no temporary file is left behind, wherever the write was.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".part"))
        .collect();
    assert!(left.is_empty(), "temporary files left behind: {left:?}");
}

/// The size and bounces of the renders compared with a complete one: a first pass of
/// about two seconds on lavapipe (measured: 0.09 Msamples/s on two busy cores).
const STOPPED_ARGS: [&str; 4] = ["--size", "384x384", "--max-bounces", "4"];

/// Mean luminance of an EXR's radiance, and the standard error of that mean from the
/// pixels' spread (image content and noise together: an upper bound of the noise).
fn mean_and_error(exr: &Exr) -> (f64, f64) {
    let n = exr.width * exr.height;
    let values: Vec<f64> = (0..n)
        .map(|p| exr.rgb(p).iter().map(|&v| v as f64).sum::<f64>() / 3.0)
        .collect();
    let mean = values.iter().sum::<f64>() / n as f64;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, (variance / n as f64).sqrt())
}

/// A complete render with `STOPPED_ARGS` at 4 spp: its mean and error, rendered once for
/// the tests of this file.
fn complete_mean() -> (f64, f64) {
    static MEAN: OnceLock<(f64, f64)> = OnceLock::new();
    *MEAN.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("complete.exr");
        let (child, lines) = spawn_render(&[&STOPPED_ARGS[..], &["--spp", "4"]].concat(), &out);
        let (status, err) = finish(child, &lines);
        assert!(status.success(), "{status}:\n{err}");
        mean_and_error(&read_exr(&out))
    })
}

/// A stopped render's image: complete, a sample in every pixel, and the mean of a
/// complete render within four standard errors.
fn assert_whole_image(path: &Path) {
    let exr = read_exr(path);
    assert_eq!((exr.width, exr.height), (384, 384));
    let samples = exr.channel("samples.Y");
    let fewest = samples.iter().copied().fold(f32::MAX, f32::min);
    assert!(fewest >= 1.0, "a pixel with {fewest} samples");
    let (mean, error) = mean_and_error(&exr);
    let (reference, reference_error) = complete_mean();
    let tolerance = 4.0 * (error.powi(2) + reference_error.powi(2)).sqrt();
    assert!(
        (mean - reference).abs() <= tolerance,
        "stopped mean {mean} vs complete {reference} (tolerance {tolerance})"
    );
}

#[test]
fn ctrl_c_during_the_first_pass_still_writes_a_sample_in_every_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("first-pass.exr");
    let (mut child, lines) =
        spawn_render(&[&STOPPED_ARGS[..], &["--spp", "1000000"]].concat(), &out);
    wait_until_rendering(&mut child, &lines);
    // At once: the first pass (about two seconds) is under way.
    interrupt(&child);
    let (status, err) = finish(child, &lines);
    assert!(status.success(), "{status}:\n{err}");
    assert!(err.contains("(interrupted)"), "{err}");
    assert_whole_image(&out);
    assert_only_file(dir.path(), "first-pass.exr");
}

#[test]
fn a_time_limit_shorter_than_the_first_pass_still_writes_a_sample_in_every_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("limited.exr");
    let args = [&STOPPED_ARGS[..], &["--spp", "64", "--time-limit", "0.001"]].concat();
    let (child, lines) = spawn_render(&args, &out);
    let (status, err) = finish(child, &lines);
    assert!(status.success(), "{status}:\n{err}");
    let summary = err
        .lines()
        .find(|l| l.starts_with("wrote "))
        .unwrap_or_else(|| panic!("no summary:\n{err}"));
    assert!(summary.contains("(time limit reached)"), "{summary}");
    assert!(
        summary.contains("the first whole pass took") && summary.contains("0.001 s time limit"),
        "the overrun is not reported: {summary}"
    );
    assert_whole_image(&out);
}
