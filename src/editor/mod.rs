//! The editor (`kiln edit`): an eframe window on the wgpu backend whose device the
//! renderer shares, with a live path-traced viewport, an outliner and an inspector over
//! one [`Document`].
//!
//! - [`document`]: the scene and the editor's state of it, changed only by commands, with
//!   undo/redo;
//! - [`viewport`]: the progressive render on a worker thread, shown through
//!   [`display`]'s GPU pass without read-back; [`navigation`] moves its view, [`pick`]
//!   finds what a click hits and [`gizmo`] moves, turns and scales the selection;
//! - [`outliner`] and [`inspector`]: views of the document that return commands;
//! - [`files`]: open, import and save, with the file dialogs behind a trait; [`session`]:
//!   recent files and the autosave that recovers work after a crash;
//! - [`settings_panel`]: the Render and World tabs; [`final_render`]: Render Image (F12)
//!   in the background, shown and exported through the exporter plugins;
//! - [`node_editor`]: the material list and the node editor of the shown material's
//!   graph, whose edits are [`graph_edit::GraphEdit`]s applied as document commands;
//!   [`node_previews`] renders its nodes' preview images and [`viewport_preview`] the
//!   viewport's "preview this node" (Ctrl+Shift+click);
//! - [`app`]: the window that ties them together.

pub mod app;
pub mod display;
pub mod document;
pub mod files;
pub mod final_render;
pub mod gizmo;
pub mod graph_edit;
pub mod inspector;
pub mod navigation;
pub mod node_editor;
pub mod node_previews;
pub mod outliner;
pub mod pick;
pub mod session;
pub mod settings_panel;
pub mod thumbnails;
pub mod viewport;
pub mod viewport_preview;

pub use app::{
    AUTOSAVE_EVERY, DEFAULT_SAMPLE_LIMIT, DeviceLost, EditorApp, EditorOptions, GRAPH_KERNELS,
    PIXEL_SIZES, RunReport,
};
pub use document::{Command, Document, Selection};
pub use files::{FileDialogs, NativeDialogs, ScriptedDialogs};

use std::sync::Arc;

/// How the editor asks wgpu for its device: the adapter's own limits and the features
/// Kiln uses, as the renderer's [`GpuContext::new`](crate::render::GpuContext::new) does
/// (eframe's default asks for WebGPU's limits, too small for the path-tracing kernel, and
/// on GL for WebGL2's, which have no compute at all). `prefer_software` picks a CPU
/// adapter first (lavapipe), for tests.
pub fn wgpu_setup(prefer_software: bool) -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(|adapter: &wgpu::Adapter| wgpu::DeviceDescriptor {
        label: Some("kiln editor"),
        required_features: crate::render::context::device_features(adapter),
        required_limits: adapter.limits(),
        ..Default::default()
    });
    if prefer_software {
        setup.native_adapter_selector = Some(Arc::new(|adapters, _surface| {
            let mut adapters: Vec<&wgpu::Adapter> = adapters.iter().collect();
            adapters.sort_by_key(|a| a.get_info().device_type != wgpu::DeviceType::Cpu);
            adapters
                .first()
                .map(|a| (*a).clone())
                .ok_or_else(|| "no adapter found".to_owned())
        }));
    }
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// The window's options: wgpu with [`wgpu_setup`], Blender-like default size.
pub fn native_options() -> eframe::NativeOptions {
    eframe::NativeOptions {
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: wgpu_setup(false),
            ..Default::default()
        },
        viewport: egui::ViewportBuilder::default()
            .with_title("Kiln")
            .with_inner_size([1280.0, 800.0])
            .with_min_inner_size([640.0, 400.0]),
        ..Default::default()
    }
}

/// Opens the editor's window and returns when it is closed.
pub fn run(options: EditorOptions) -> Result<RunReport, eframe::Error> {
    let report = Arc::new(std::sync::Mutex::new(RunReport::default()));
    let app_report = Arc::clone(&report);
    eframe::run_native(
        "Kiln",
        native_options(),
        Box::new(|cc| {
            let mut app = EditorApp::new(cc, options);
            app.report_to(app_report);
            Ok(Box::new(app))
        }),
    )?;
    let report = report.lock().unwrap_or_else(|e| e.into_inner()).clone();
    Ok(report)
}
