//! `kiln render` loses no work to its output: a path that cannot be written is refused
//! before anything renders, and an image that cannot be written at the end (the folder
//! vanished, the disk filled up) goes to a fallback file the error names.
#![cfg(unix)]

mod common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::exr::read_exr;

/// A 16×16, 1-spp render of the default scene to `output`, with `extra` arguments.
fn tiny_render(output: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kiln"))
        .args(["render", "--size", "16x16", "--spp", "1", "-q"])
        .args(extra)
        .arg("-o")
        .arg(output)
        .output()
        .expect("kiln runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The fallback file an error says the render was saved to.
fn fallback_named(err: &str) -> PathBuf {
    err.split("the render was saved to ")
        .nth(1)
        .and_then(|rest| rest.split(" instead").next())
        .map(PathBuf::from)
        .unwrap_or_else(|| panic!("no fallback named in:\n{err}"))
}

/// Refused before the GPU is even opened: no "adapter:" line, a non-zero exit, the message.
fn assert_refused_up_front(out: &Output, message: &str) {
    let err = stderr(out);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains(message), "expected {message:?} in:\n{err}");
    assert!(
        !err.contains("adapter:"),
        "the check ran after the render started:\n{err}"
    );
}

#[test]
fn a_missing_or_read_only_folder_is_refused_before_rendering() {
    let out = tiny_render(Path::new("/no/such/folder/x.png"), &[]);
    assert_refused_up_front(&out, "the folder /no/such/folder does not exist");

    // Root may write anywhere; the read-only case only means something for other users.
    let dir = tempfile::tempdir().unwrap();
    let read_only = dir.path().join("ro");
    std::fs::create_dir(&read_only).unwrap();
    std::fs::set_permissions(
        &read_only,
        std::os::unix::fs::PermissionsExt::from_mode(0o555),
    )
    .unwrap();
    if std::fs::write(read_only.join("probe"), b"").is_err() {
        let out = tiny_render(&read_only.join("x.png"), &[]);
        assert_refused_up_front(&out, "is not writable");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "the check leaves nothing behind"
    );
}

#[test]
fn options_and_formats_no_writer_takes_are_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = tiny_render(&dir.path().join("x.png"), &["--export-options", "bits=7"]);
    assert_refused_up_front(&out, "bits=7");
    let out = tiny_render(&dir.path().join("x.tga"), &[]);
    assert_refused_up_front(&out, "x.tga");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no image and no scratch folder left behind"
    );
}

#[test]
fn an_image_that_cannot_be_written_at_the_end_goes_to_a_fallback_file() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("renders");
    std::fs::create_dir(&folder).unwrap();
    let target = folder.join("final.png");
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiln"))
        .arg("render")
        .args(["--size", "64x64", "--time-limit", "2", "-q", "-o"])
        .arg(&target)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("kiln starts");
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut seen = Vec::new();
    // "scene:" comes once the kernel is built, when rendering starts: the folder goes then.
    for line in lines.by_ref().map_while(Result::ok) {
        let rendering = line.starts_with("scene:");
        seen.push(line);
        if rendering {
            break;
        }
    }
    std::fs::remove_dir_all(&folder).unwrap();
    seen.extend(lines.map_while(Result::ok));
    let status = child.wait().unwrap();
    let err = seen.join("\n");
    assert!(!status.success(), "{err}");
    let saved = fallback_named(&err);
    let image = read_exr(&saved);
    std::fs::remove_file(&saved).unwrap();
    assert_eq!((image.width, image.height), (64, 64));
    let samples = image.channel("samples.Y");
    assert!(
        samples.iter().all(|&n| n >= 1.0),
        "every pixel has a sample"
    );
    assert!(image.mean().iter().all(|&m| m > 0.0), "{:?}", image.mean());
    assert!(!Path::new(&target).exists());
}

/// A tmpfs mounted over a folder for as long as it lives, unmounted on drop.
struct SmallDisk {
    folder: PathBuf,
}

impl SmallDisk {
    /// A `size` tmpfs over `folder`; None where this process may not mount (not root).
    fn mount(folder: &Path, size: &str) -> Option<Self> {
        // SAFETY: geteuid has no preconditions.
        if unsafe { libc::geteuid() } != 0 {
            return None;
        }
        let status = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(folder)
            .status()
            .expect("mount runs");
        assert!(status.success(), "mount a tmpfs on {}", folder.display());
        Some(Self {
            folder: folder.to_path_buf(),
        })
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.folder).status();
    }
}

/// A real full disk, the case: a 16 KiB tmpfs takes the check's probe file but not
/// a 128 × 128 EXR. The render goes to the fallback file the error names, and the small
/// disk is left without a half-written image. Needs root to mount (CI runs as root);
/// elsewhere it says so and checks nothing.
#[test]
fn an_image_that_does_not_fit_on_a_full_disk_goes_to_a_fallback_file() {
    let dir = tempfile::tempdir().unwrap();
    let (disk_folder, temp) = (dir.path().join("disk"), dir.path().join("tmp"));
    std::fs::create_dir(&disk_folder).unwrap();
    std::fs::create_dir(&temp).unwrap();
    let Some(disk) = SmallDisk::mount(&disk_folder, "16k") else {
        eprintln!("not root: no tmpfs can be mounted, so the full disk is not tested here");
        return;
    };
    let target = disk.folder.join("final.exr");
    let out = Command::new(env!("CARGO_BIN_EXE_kiln"))
        .args(["render", "--size", "128x128", "--spp", "2", "-q", "-o"])
        .arg(&target)
        // The fallback goes to the temporary folder: this test's own.
        .env("TMPDIR", &temp)
        .output()
        .expect("kiln runs");
    let err = stderr(&out);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("No space left on device"),
        "the error names the cause:\n{err}"
    );
    let saved = fallback_named(&err);
    assert!(saved.starts_with(&temp), "{}", saved.display());
    let image = read_exr(&saved);
    assert_eq!((image.width, image.height), (128, 128));
    assert!(image.mean().iter().all(|&m| m > 0.0), "{:?}", image.mean());
    let left: Vec<_> = std::fs::read_dir(&disk.folder)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left on the full disk: {left:?}");
}
