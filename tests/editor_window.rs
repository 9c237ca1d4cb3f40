//! The editor in a real window: `kiln edit` under Xvfb opens the bundled scene, renders a
//! few samples in its viewport, closes itself and exits cleanly. The kittest tests drive
//! the same app headless; this one checks what they cannot: eframe's window, surface and
//! event loop on X11. Needs `xvfb-run` (Debian's xvfb package, which CI installs); outside
//! CI a machine without it skips, loudly.

use std::process::Command;
use std::time::{Duration, Instant};

mod common;

use common::resource::in_ci;

/// Opening the window and compiling the viewport's kernel on lavapipe takes seconds; a
/// busy machine, a minute.
const WAIT: Duration = Duration::from_secs(300);

fn has_xvfb_run() -> bool {
    Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_ok_and(|o| o.status.success() || !o.stdout.is_empty() || !o.stderr.is_empty())
}

#[test]
fn kiln_edit_opens_renders_and_closes_in_a_real_window() {
    if !has_xvfb_run() {
        assert!(
            !in_ci(),
            "xvfb-run is missing (CI is set, so the real-window test must run)"
        );
        eprintln!("\n*** SKIPPED: xvfb-run is missing; the real window was not tested ***\n");
        return;
    }
    let state = tempfile::tempdir().unwrap();
    let mut child = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_kiln"))
        .args(["edit", "--samples", "2", "--quit-when-done"])
        // The software Vulkan driver; recent files and autosaves go to a scratch folder.
        .env("WGPU_BACKEND", "vulkan")
        .env("XDG_STATE_HOME", state.path())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("xvfb-run starts");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > WAIT {
            let _ = child.kill();
            panic!("kiln edit did not close within {WAIT:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(status.success(), "kiln edit failed ({status}):\n{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("viewport: "))
        .unwrap_or_else(|| panic!("no viewport report in:\n{stderr}"));
    let samples: u32 = line["viewport: ".len()..]
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("unreadable report: {line}"));
    assert!(samples >= 2, "{line}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
