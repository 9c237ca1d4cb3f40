//! The editor as egui_kittest drives it headless on lavapipe, shared by the editor's test
//! binaries (`tests/editor.rs`, `tests/node_editor.rs`; included by `#[path]`, not
//! through `common/mod.rs`, so that other tests do not link egui_kittest).

// Each including binary uses a part.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use kiln::editor::viewport::{GraphKernels, ViewportStatus};
use kiln::editor::{DeviceLost, EditorApp, EditorOptions, ScriptedDialogs};
use kiln::plugin::PluginHost;
use kiln::render::KernelKind;

/// Samples per pixel the viewport stops at: tests wait for it, then the app rests.
pub const SAMPLE_LIMIT: u32 = 2;
/// The viewport renders one pixel per 4×4 of the window's: what the tests look at (which
/// object is where, a colour at the centre) survives it, and an image of a 1920×1000
/// window's viewport on lavapipe comes in seconds rather than minutes.
pub const PIXEL_SIZE: u32 = 4;
/// Building the viewport's kernel on lavapipe takes seconds on a busy machine.
pub const WAIT: Duration = Duration::from_secs(300);

/// How a test's editor starts.
pub struct Setup {
    pub dialogs: ScriptedDialogs,
    pub plugins: PluginHost,
    /// The folder for recent files and autosaves (None keeps neither).
    pub state_dir: Option<PathBuf>,
    pub autosave_every: Duration,
    /// The window's size in points.
    pub size: egui::Vec2,
    /// Material thumbnails (off unless a test looks at them: they share the device).
    pub thumbnails: bool,
    /// The file to open (None: the bundled Cornell box).
    pub file: Option<PathBuf>,
    /// How the viewport holds graphs (interpreted: no background compiles, which
    /// tests counting builds would see).
    pub graph_kernels: GraphKernels,
    /// Samples per pixel the viewport stops at.
    pub sample_limit: u32,
    /// Screen pixels per viewport pixel ([`PIXEL_SIZE`]).
    pub pixel_size: u32,
    /// What a lost device does (by default the test fails naming the reason).
    pub on_device_lost: Box<dyn FnMut(DeviceLost)>,
    pub restarted_after_device_loss: Option<String>,
    /// Compile the viewport's kernels on the background device first, as `kiln edit`
    /// does (off: it builds each new kernel's scene twice).
    pub rehearse_compiles: bool,
}

impl Default for Setup {
    fn default() -> Self {
        Self {
            dialogs: ScriptedDialogs::default(),
            plugins: PluginHost::default(),
            state_dir: None,
            autosave_every: kiln::editor::AUTOSAVE_EVERY,
            size: egui::vec2(1280.0, 800.0),
            thumbnails: false,
            file: None,
            graph_kernels: GraphKernels::Interpreted,
            sample_limit: SAMPLE_LIMIT,
            pixel_size: PIXEL_SIZE,
            on_device_lost: Box::new(|lost| panic!("the GPU device was lost: {}", lost.reason)),
            restarted_after_device_loss: None,
            rehearse_compiles: false,
        }
    }
}

/// The real app on the bundled Cornell box, with a software adapter.
pub fn start(setup: Setup) -> Harness<'static, EditorApp> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread of this test starts a device.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let Setup {
        dialogs,
        plugins,
        state_dir,
        autosave_every,
        size,
        thumbnails,
        file,
        graph_kernels,
        sample_limit,
        pixel_size,
        on_device_lost,
        restarted_after_device_loss,
        rehearse_compiles,
    } = setup;
    Harness::builder()
        .with_size(size)
        .wgpu_setup(kiln::editor::wgpu_setup(true))
        .build_eframe(move |cc| {
            EditorApp::new(
                cc,
                EditorOptions {
                    file,
                    dialogs: Box::new(dialogs),
                    plugins,
                    sample_limit: Some(sample_limit),
                    state_dir,
                    autosave_every,
                    quit_when_done: false,
                    thumbnails,
                    graph_kernels,
                    pixel_size: Some(pixel_size),
                    on_device_lost,
                    restarted_after_device_loss,
                    rehearse_compiles,
                },
            )
        })
}

/// Steps frames until `done` holds; fails naming `what` after [`WAIT`].
pub fn step_until(
    harness: &mut Harness<'_, EditorApp>,
    what: &str,
    mut done: impl FnMut(&EditorApp) -> bool,
) {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(
            start.elapsed() < WAIT,
            "timed out waiting for {what}; viewport: {}",
            harness
                .state()
                .viewport_status()
                .map_or("no status".to_owned(), |s| describe(&s))
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    harness.step();
}

/// Asserts that the edit between `before` and `after` went into the standby renderers
/// ([`ViewportStatus::standby_returns`]), which came back with `kernel` and no renderer
/// built or kernel compiled.
pub fn assert_standby_returned(
    before: &ViewportStatus,
    after: &ViewportStatus,
    kernel: KernelKind,
) {
    assert_eq!(after.kernel, Some(kernel));
    assert_eq!(after.standby_returns, before.standby_returns + 1);
    assert_eq!(
        (after.renderer_builds, after.kernel_builds),
        (before.renderer_builds, before.kernel_builds),
        "no renderer built, no kernel compiled"
    );
}

/// Steps until specialised renderers have replaced the ones on screen since `before`;
/// returns the status then.
pub fn step_until_specialised(
    harness: &mut Harness<'_, EditorApp>,
    what: &str,
    before: &ViewportStatus,
) -> ViewportStatus {
    step_until(harness, what, |app| {
        app.viewport_status()
            .is_some_and(|s| s.compiled_swaps > before.compiled_swaps)
    });
    let status = harness.state().viewport_status().unwrap();
    assert_eq!(status.kernel, Some(KernelKind::Specialized));
    status
}

/// The bundled plugins, as `cargo build` left them next to the test executable.
pub fn bundled_plugins() -> PluginHost {
    let exe = std::env::current_exe().unwrap();
    let mut plugins = PluginHost::default();
    plugins.load_dir(exe.parent().unwrap(), true);
    plugins
}

/// A binary glTF of a unit quad (two triangles) in `dir`.
pub fn quad_glb(dir: &Path) -> PathBuf {
    let glb = dir.join("quad.glb");
    kiln::bench::write_glb(&kiln::scene::shapes::quad(), &glb).unwrap();
    glb
}

/// The viewport's progress in one line, for a timeout's message.
fn describe(s: &kiln::editor::viewport::ViewportStatus) -> String {
    format!(
        "kernel {:?}, {} spp shown ({} passes), building {}, compiling {}, \
         {} renderers / {} kernels built, {} compiled swaps, error {:?}",
        s.kernel,
        s.samples,
        s.passes,
        s.building.is_some(),
        s.compiling,
        s.renderer_builds,
        s.kernel_builds,
        s.compiled_swaps,
        s.error
    )
}
