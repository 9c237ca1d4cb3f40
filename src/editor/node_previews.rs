//! Node previews: a node's output as a small image under it in the node editor (Blender's
//! node preview), made on a worker thread that shares the viewport's device.
//!
//! A preview compiles one output with the compiler's socket-preview path
//! ([`compile_value_with_textures`]) and evaluates it at one shading point per pixel of a
//! unit sphere seen head-on through an orthographic camera ([`sphere_points`]), in the
//! small kernel of `shaders/editor/node_preview.wgsl` run as a [`crate::render::probe`].
//! It is not a path trace: no rays, lights or samples, so the kernel compiles in a
//! fraction of the path tracer's time. Values are shown as they are: colours and
//! vectors channel for channel, floats as grey, all through the display's sRGB encoding
//! (clamped to [0, 1]). A shader output (a BSDF) shows the material's look cheaply: the
//! surface that node makes, compiled as a material, shades the sphere with its base colour
//! under one light from the upper left plus an ambient share, and adds its emission —
//! an approximation of the thumbnail's path-traced sphere ([`super::thumbnails`]) that
//! costs no path-tracing kernel per edit.
//!
//! The worker keeps the compiled code of each preview and renders again only when it
//! changed, so an edit outside what feeds the node (which the compiler prunes) costs a
//! compile and no GPU work; and the UI asks again only when the graph changed other than
//! by layout ([`Graph::same_but_layout`]), so moving nodes costs nothing. While a preview
//! renders, the node shows its previous image.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::graph_edit::sockets_of;
use crate::film::tonemap::srgb_encode;
use crate::material::compile::{Constants, compile_value_with_textures, compile_with};
use crate::material::graph::REROUTE;
use crate::material::nodes::MATERIAL_OUTPUT;
use crate::material::{Graph, Link, Node, SocketType, library};
use crate::render::GpuContext;
use crate::render::probe::{Probe, run_probe};
use crate::render::{KernelKind, RenderSettings, materials::scene_textures};
use crate::scene::{Camera, Material, Scene};

/// Side of a preview image in pixels.
pub const PREVIEW_SIZE: u32 = 96;
/// The share of the image's width the sphere spans.
const SPHERE_FILL: f32 = 0.9;
/// The light a shader's preview is lit by (toward the light, world space: upper left,
/// in front), and the share of light that comes from everywhere.
const LIGHT_DIRECTION: [f32; 3] = [-0.5, 0.6, 0.62];
const AMBIENT: f32 = 0.2;

/// Which node's preview: a material (by index) and a node id of its graph.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PreviewKey {
    pub material: usize,
    pub node: String,
}

/// The output a preview shows.
#[derive(Clone, Debug, PartialEq)]
struct Wanted {
    node: String,
    socket: String,
    ty: SocketType,
}

/// One preview asked of the worker.
#[derive(Clone)]
struct Request {
    key: PreviewKey,
    socket: String,
    ty: SocketType,
    graph: Arc<Graph>,
    /// The document's material: its name for messages, its images for image textures.
    material: Material,
}

/// What the worker made of a request.
struct Rendered {
    key: PreviewKey,
    graph: Arc<Graph>,
    socket: String,
    image: Result<egui::ColorImage, String>,
    took: Duration,
}

#[derive(Default)]
struct State {
    wanted: Vec<Request>,
    done: Vec<Rendered>,
    quit: bool,
}

struct Shared {
    state: Mutex<State>,
    wake: Condvar,
}

fn lock(shared: &Shared) -> MutexGuard<'_, State> {
    shared.state.lock().unwrap_or_else(|e| e.into_inner())
}

/// A preview as the node editor shows it.
struct Shown {
    /// The graph and output it was made of.
    graph: Arc<Graph>,
    socket: String,
    texture: Option<egui::TextureHandle>,
    image: Option<egui::ColorImage>,
    error: Option<String>,
    took: Duration,
}

/// What the node editor draws for one node's preview.
pub struct PreviewView<'a> {
    /// The latest image (while a new one renders, the previous one).
    pub texture: Option<&'a egui::TextureHandle>,
    /// Whether the image shows the graph as it is now.
    pub current: bool,
    /// Why the latest preview failed, if it did.
    pub error: Option<&'a str>,
}

/// The previews of the shown material's nodes, kept up to date in the background.
pub struct NodePreviews {
    shared: Arc<Shared>,
    worker: Option<JoinHandle<()>>,
    shown: BTreeMap<PreviewKey, Shown>,
    /// What was last asked for: the material, its graph and the previewed outputs.
    asked: Option<(usize, Arc<Graph>, Vec<Wanted>)>,
}

impl NodePreviews {
    /// Starts the worker on `ctx`; `repaint` is called when a preview is ready.
    pub fn new(ctx: Arc<GpuContext>, repaint: impl Fn() + Send + 'static) -> Self {
        let shared = Arc::new(Shared {
            state: Mutex::new(State::default()),
            wake: Condvar::new(),
        });
        let worker_shared = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("kiln node previews".into())
            .spawn(move || work(&ctx, &worker_shared, &repaint))
            .ok();
        Self {
            shared,
            worker,
            shown: BTreeMap::new(),
            asked: None,
        }
    }

    /// Asks for the previews of `graph`, the graph of material `material` (`source`, the
    /// document's material, holds its images): one per node whose preview is on. Costs
    /// nothing when only the layout changed since the last call.
    pub fn want(&mut self, material: usize, graph: &Graph, source: &Material) {
        let wanted = previewed_outputs(graph);
        let same = self
            .asked
            .as_ref()
            .is_some_and(|(m, g, w)| *m == material && *w == wanted && g.same_but_layout(graph));
        if same {
            return;
        }
        let graph = Arc::new(graph.clone());
        let requests = wanted
            .iter()
            .map(|w| Request {
                key: PreviewKey {
                    material,
                    node: w.node.clone(),
                },
                socket: w.socket.clone(),
                ty: w.ty,
                graph: Arc::clone(&graph),
                material: source.clone(),
            })
            .collect();
        self.asked = Some((material, graph, wanted));
        lock(&self.shared).wanted = requests;
        self.shared.wake.notify_all();
    }

    /// Takes finished previews into textures of `ctx`.
    pub fn poll(&mut self, ctx: &egui::Context) {
        let done = std::mem::take(&mut lock(&self.shared).done);
        for rendered in done {
            let name = format!(
                "node preview {} {}",
                rendered.key.material, rendered.key.node
            );
            let previous = self.shown.remove(&rendered.key);
            let shown = match rendered.image {
                Ok(image) => Shown {
                    graph: rendered.graph,
                    socket: rendered.socket,
                    texture: Some(ctx.load_texture(
                        name,
                        image.clone(),
                        egui::TextureOptions::LINEAR,
                    )),
                    image: Some(image),
                    error: None,
                    took: rendered.took,
                },
                // A failed preview keeps showing the last image it had.
                Err(error) => Shown {
                    graph: rendered.graph,
                    socket: rendered.socket,
                    texture: previous.as_ref().and_then(|p| p.texture.clone()),
                    image: None,
                    error: Some(error),
                    took: rendered.took,
                },
            };
            self.shown.insert(rendered.key, shown);
        }
    }

    /// What to draw for node `node` of material `material`, whose graph is now `graph`.
    pub fn view(&self, material: usize, node: &str, graph: &Graph) -> PreviewView<'_> {
        let key = PreviewKey {
            material,
            node: node.to_owned(),
        };
        let Some(shown) = self.shown.get(&key) else {
            return PreviewView {
                texture: None,
                current: false,
                error: None,
            };
        };
        let current = self.is_current(shown, node, graph);
        PreviewView {
            texture: shown.texture.as_ref(),
            current,
            error: shown.error.as_deref(),
        }
    }

    /// The pixels of node `node`'s preview if it shows `graph` (material `material`'s
    /// graph) as it is now.
    pub fn image(&self, material: usize, node: &str, graph: &Graph) -> Option<&egui::ColorImage> {
        let key = PreviewKey {
            material,
            node: node.to_owned(),
        };
        let shown = self.shown.get(&key)?;
        self.is_current(shown, node, graph)
            .then_some(shown.image.as_ref())
            .flatten()
    }

    /// How long the worker took to make node `node`'s latest preview (compile, kernel
    /// and render), for measurements.
    pub fn took(&self, material: usize, node: &str) -> Option<Duration> {
        let key = PreviewKey {
            material,
            node: node.to_owned(),
        };
        self.shown.get(&key).map(|s| s.took)
    }

    fn is_current(&self, shown: &Shown, node: &str, graph: &Graph) -> bool {
        let socket = previewed_outputs(graph)
            .into_iter()
            .find(|w| w.node == node)
            .map(|w| w.socket);
        socket.as_deref() == Some(shown.socket.as_str()) && shown.graph.same_but_layout(graph)
    }
}

impl Drop for NodePreviews {
    fn drop(&mut self) {
        lock(&self.shared).quit = true;
        self.shared.wake.notify_all();
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The nodes of `graph` whose preview is on, with the output each shows (its first; a
/// reroute and a node without outputs show none).
fn previewed_outputs(graph: &Graph) -> Vec<Wanted> {
    graph
        .nodes
        .iter()
        .filter(|(_, n)| n.preview && n.kind != REROUTE)
        .filter_map(|(id, n)| {
            let sockets = sockets_of(graph, n).ok()?;
            let (socket, ty) = sockets.outputs.into_iter().next()?;
            Some(Wanted {
                node: id.clone(),
                socket,
                ty,
            })
        })
        .collect()
}

/// The shading points of the preview sphere, one per pixel of a `size`² image, row by row
/// from the top: the unit sphere at the origin seen from +z through an orthographic
/// camera, spanning [`SPHERE_FILL`] of the image. Each is `[(p, u), (n, v), (generated,
/// coverage)]`: the point (object space = world space) and its UVs as
/// `shapes::uv_sphere` has them, the outward normal, the generated coordinates (the point
/// in the sphere's bounding box, [0, 1]³), and how much of the pixel the sphere covers
/// (0 off it; pixels on the outline take the outline's point, so its edge is smooth).
pub fn sphere_points(size: u32) -> Vec<[[f32; 4]; 3]> {
    let size = size.max(1);
    let pixel = 2.0 / (size as f32 * SPHERE_FILL);
    let mut points = Vec::with_capacity((size * size) as usize);
    for row in 0..size {
        for column in 0..size {
            let x = ((column as f32 + 0.5) / size as f32 * 2.0 - 1.0) / SPHERE_FILL;
            let y = -((row as f32 + 0.5) / size as f32 * 2.0 - 1.0) / SPHERE_FILL;
            let r = (x * x + y * y).sqrt();
            // The share of the pixel inside the outline, from its distance to it.
            let coverage = ((1.0 - r) / pixel + 0.5).clamp(0.0, 1.0);
            let p = if r <= 1.0 {
                Vec3::new(x, y, (1.0 - r * r).max(0.0).sqrt())
            } else {
                Vec3::new(x / r, y / r, 0.0)
            };
            let p = p.normalize();
            let theta = p.y.clamp(-1.0, 1.0).acos();
            let phi = (-p.z).atan2(p.x).rem_euclid(std::f32::consts::TAU);
            let u = phi / std::f32::consts::TAU;
            let v = theta / std::f32::consts::PI;
            let generated = (p + Vec3::ONE) * 0.5;
            points.push([
                [p.x, p.y, p.z, u],
                [p.x, p.y, p.z, v],
                [generated.x, generated.y, generated.z, coverage],
            ]);
        }
    }
    points
}

/// The WGSL of a preview: `node_preview(sp: ShadingPoint) -> vec3<f32>`, the linear
/// colour shown for output `socket` (of type `ty`) of node `node`, with everything it calls.
fn preview_wgsl(
    graph: &Graph,
    node: &str,
    socket: &str,
    ty: SocketType,
    material: &str,
    textures: &mut BTreeMap<String, u32>,
) -> Result<String, String> {
    let at = Link::new(node, socket);
    let mut calls = BTreeSet::from([
        "ShadingPoint".to_owned(),
        "MaterialEval".to_owned(),
        // A shader's code wraps its result in it (kernel assembly always adds it).
        "material_eval".to_owned(),
        "nd_finite3".to_owned(),
    ]);
    let (code, body) = if ty.is_shader() {
        // The node's shader as a material: an output node reading it.
        let mut surface = graph.clone();
        let mut output = format!("{node}~preview_output");
        while surface.nodes.contains_key(&output) {
            output.push('~');
        }
        let input = if ty == SocketType::Volume {
            "volume"
        } else {
            "surface"
        };
        surface.add(&output, Node::new(MATERIAL_OUTPUT).input(input, at.clone()));
        surface.output = Some(output);
        let compiled = compile_with(
            material,
            &surface,
            "node_preview_surface",
            textures,
            Constants::Inline,
        )
        .map_err(|e| e.to_string())?;
        calls.extend(compiled.calls);
        let [lx, ly, lz] = LIGHT_DIRECTION;
        let shade = if ty == SocketType::Volume {
            // A unit thickness of the volume: what it scatters, lit, and what it emits.
            "let v = e.volume;\n    \
             let sigma_t = v.absorption + v.scattering;\n    \
             let kept = exp(-sigma_t);\n    \
             let albedo = select(vec3<f32>(0.0), v.scattering / sigma_t, sigma_t > vec3<f32>(0.0));\n    \
             let glow = select(v.emission, v.emission * (1.0 - kept) / sigma_t, sigma_t > vec3<f32>(0.0));\n    \
             return albedo * (1.0 - kept) * lit + glow;\n"
        } else {
            "return e.principled.base_color * e.principled.base_weight * lit + e.emission;\n"
        };
        let body = format!(
            "    let e = node_preview_surface(sp);\n    \
             let light = normalize(vec3<f32>({lx:?}, {ly:?}, {lz:?}));\n    \
             let lit = {AMBIENT:?} + {:?} * max(dot(e.normal, light), 0.0);\n    \
             {shade}",
            1.0 - AMBIENT
        );
        (compiled.code, body)
    } else {
        let compiled =
            compile_value_with_textures(material, graph, &at, "node_preview_value", textures)
                .map_err(|e| e.to_string())?;
        calls.extend(compiled.calls);
        let value = match ty {
            SocketType::Float => "vec3<f32>(v.x)",
            SocketType::Vec2 => "vec3<f32>(v.xy, 0.0)",
            _ => "v.xyz",
        };
        let body = format!("    let v = node_preview_value(sp);\n    return {value};\n");
        (compiled.code, body)
    };
    Ok(format!(
        "{}{code}fn node_preview(sp: ShadingPoint) -> vec3<f32> {{\n{body}}}\n",
        library::closure(calls)
    ))
}

/// The scene a preview runs in: empty but for `material`, so its images are bound.
fn preview_scene(material: &Material) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    scene.materials = vec![material.clone()];
    scene
}

/// The WGSL of `request` in `scene` ([`preview_scene`]).
fn request_wgsl(request: &Request, scene: &Scene) -> Result<String, String> {
    preview_wgsl(
        &request.graph,
        &request.key.node,
        &request.socket,
        request.ty,
        &request.material.name,
        &mut scene_textures(scene).index,
    )
}

/// The preview kernel's entry point.
const PREVIEW_ENTRY: &str = "node_preview_main";

/// What follows the shader library in the preview kernel: the preview's `code`
/// ([`preview_wgsl`]) and the kernel that calls it.
fn kernel_parts(code: &str) -> [(&str, &str); 2] {
    [
        ("generated: node preview", code),
        (
            "shaders/editor/node_preview.wgsl",
            include_str!("../../shaders/editor/node_preview.wgsl"),
        ),
    ]
}

/// Runs the preview kernel with `code` over the sphere's points; the image in sRGB.
fn evaluate(ctx: &GpuContext, scene: &Scene, code: &str) -> Result<egui::ColorImage, String> {
    let points = sphere_points(PREVIEW_SIZE);
    let mut input: Vec<[f32; 4]> = vec![[points.len() as f32, 0.0, 0.0, 0.0]];
    input.extend(points.iter().flatten());
    let settings = RenderSettings {
        width: 1,
        height: 1,
        samples_per_pixel: 1,
        kernel: KernelKind::General,
        noise_threshold: 0.0,
        ..RenderSettings::from_scene(scene)
    };
    let out = run_probe(
        ctx,
        scene,
        &settings,
        &Probe {
            name: "node preview",
            parts: &kernel_parts(code),
            entry: PREVIEW_ENTRY,
            input: bytemuck::cast_slice(&input),
            output_bytes: 16 * points.len() as u64,
            invocations: points.len() as u32,
            material_params: &[],
        },
    )
    .map_err(|e| e.to_string())?;
    let colours: &[[f32; 4]] = bytemuck::cast_slice(&out);
    Ok(display_image(colours, PREVIEW_SIZE))
}

/// The display transform of a preview: each linear channel clamped to [0, 1] and
/// sRGB-encoded, the sphere's coverage as alpha.
pub fn display_image(colours: &[[f32; 4]], size: u32) -> egui::ColorImage {
    let byte = |x: f32| (srgb_encode(x.clamp(0.0, 1.0)) * 255.0).round() as u8;
    let pixels = colours
        .iter()
        .map(|&[r, g, b, a]| {
            egui::Color32::from_rgba_unmultiplied(byte(r), byte(g), byte(b), byte_linear(a))
        })
        .collect();
    egui::ColorImage::new([size as usize; 2], pixels)
}

fn byte_linear(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// What the worker last made of a preview: of which graph and output, its code and image.
struct Made {
    graph: Arc<Graph>,
    socket: String,
    code: Option<String>,
    image: Result<egui::ColorImage, String>,
}

/// The worker: makes the first wanted preview that is missing or stale, until told to
/// quit.
fn work(ctx: &Arc<GpuContext>, shared: &Shared, repaint: &dyn Fn()) {
    let mut made: BTreeMap<PreviewKey, Made> = BTreeMap::new();
    loop {
        let request = {
            let mut state = lock(shared);
            loop {
                if state.quit {
                    return;
                }
                let stale = state.wanted.iter().find(|r| {
                    made.get(&r.key)
                        .is_none_or(|m| m.socket != r.socket || !m.graph.same_but_layout(&r.graph))
                });
                if let Some(request) = stale {
                    break request.clone();
                }
                state = shared
                    .wake
                    .wait_timeout(state, Duration::from_secs(1))
                    .map(|(s, _)| s)
                    .unwrap_or_else(|e| e.into_inner().0);
            }
        };
        let start = Instant::now();
        let scene = preview_scene(&request.material);
        let code = request_wgsl(&request, &scene);
        let image = match (&code, made.remove(&request.key)) {
            // The same code (an edit elsewhere, pruned from this output): the same image.
            (Ok(code), Some(m)) if m.code.as_deref() == Some(code.as_str()) => m.image,
            (Ok(code), _) => evaluate(ctx, &scene, code),
            (Err(e), _) => Err(e.clone()),
        };
        let took = start.elapsed();
        made.insert(
            request.key.clone(),
            Made {
                graph: Arc::clone(&request.graph),
                socket: request.socket.clone(),
                code: code.ok(),
                image: image.clone(),
            },
        );
        lock(shared).done.push(Rendered {
            key: request.key,
            graph: request.graph,
            socket: request.socket,
            image,
            took,
        });
        repaint();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_points_have_unit_normals_and_generated_coordinates_in_the_unit_box() {
        let points = sphere_points(PREVIEW_SIZE);
        assert_eq!(points.len(), (PREVIEW_SIZE * PREVIEW_SIZE) as usize);
        let mut covered = 0;
        for [a, b, c] in &points {
            let n = Vec3::new(b[0], b[1], b[2]);
            assert!((n.length() - 1.0).abs() < 1e-5, "normal {n} is not unit");
            let p = Vec3::new(a[0], a[1], a[2]);
            assert!((p - n).length() < 1e-5, "on a unit sphere p = n: {p} {n}");
            assert!(p.z >= -1e-6, "only the hemisphere facing the camera: {p}");
            for g in &c[..3] {
                assert!((0.0..=1.0).contains(g), "generated {c:?} outside [0, 1]");
            }
            assert!((0.0..=1.0).contains(&a[3]) && (0.0..=1.0).contains(&b[3]));
            assert!((0.0..=1.0).contains(&c[3]));
            if c[3] > 0.0 {
                covered += 1;
            }
        }
        // The sphere covers π/4 · fill² of the square, within its one-pixel outline.
        let want = std::f32::consts::FRAC_PI_4 * SPHERE_FILL * SPHERE_FILL;
        let got = covered as f32 / points.len() as f32;
        assert!(
            (got - want).abs() < 0.03,
            "covered {got}, want {want} ± 0.03"
        );
    }

    #[test]
    fn the_sphere_faces_the_camera_at_the_centre_and_is_empty_in_the_corners() {
        let size = 33;
        let points = sphere_points(size);
        let centre = points[(16 * size + 16) as usize];
        assert!(centre[1][2] > 0.999, "centre normal {:?}", centre[1]);
        assert_eq!(centre[2][3], 1.0);
        let g = &centre[2];
        assert!((g[0] - 0.5).abs() < 0.05 && (g[1] - 0.5).abs() < 0.05 && g[2] > 0.99);
        assert_eq!(
            points[0][2][3], 0.0,
            "the top-left corner is off the sphere"
        );
        // The top of the image is the sphere's top (+y).
        let top = points[(2 * size + 16) as usize];
        assert!(top[1][1] > 0.8, "{:?}", top[1]);
    }

    #[test]
    fn uvs_follow_the_uv_sphere_mesh() {
        // The mesh's vertex at (u, v) sits where the preview's point with those UVs is.
        for [a, b, _] in sphere_points(24) {
            let (u, v) = (a[3], b[3]);
            let theta = v * std::f32::consts::PI;
            let phi = u * std::f32::consts::TAU;
            let mesh = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            let p = Vec3::new(a[0], a[1], a[2]);
            assert!((mesh - p).length() < 1e-4, "uv ({u}, {v}): {mesh} vs {p}");
        }
    }

    #[test]
    fn the_display_transform_encodes_srgb_and_keeps_coverage() {
        let pair = [[0.5, 0.0, 2.0, 1.0], [0.2, 0.2, 0.2, 0.0]];
        let image = display_image(&[pair, pair].concat(), 2);
        let p = image.pixels[0];
        // sRGB(0.5) = 0.7354; above 1 clamps.
        assert_eq!(p.to_srgba_unmultiplied(), [188, 0, 255, 255]);
        assert_eq!(image.pixels[1].a(), 0);
    }

    #[test]
    fn a_preview_kernel_of_each_output_type_is_valid_wgsl() {
        let mut g = Graph::default();
        g.add("noise", Node::new("noise_texture"));
        g.add(
            "surface",
            Node::new("principled_bsdf").input("base_color", Link::new("noise", "color")),
        );
        g.add(
            "output",
            Node::new(MATERIAL_OUTPUT).input("surface", Link::new("surface", "bsdf")),
        );
        for (node, socket, ty) in [
            ("noise", "color", SocketType::Color),
            ("noise", "fac", SocketType::Float),
            ("surface", "bsdf", SocketType::Bsdf),
        ] {
            let wgsl = preview_wgsl(&g, node, socket, ty, "m", &mut BTreeMap::new())
                .unwrap_or_else(|e| panic!("{node}.{socket}: {e}"));
            assert_eq!(
                wgsl.matches("fn node_preview(sp: ShadingPoint)").count(),
                1,
                "{wgsl}"
            );
            // As run_probe assembles it, checked by naga without a device.
            let mut source = crate::render::kernel::KernelSource::with_library(
                "node preview",
                &crate::shader::KernelFeatures::default(),
            );
            for (path, part) in kernel_parts(&wgsl) {
                source.push(path, part);
            }
            if let Err(e) = source.validate() {
                panic!("{node}.{socket}: {e}");
            }
        }
        // The graph is left as it was: the output the BSDF preview adds is a copy's.
        assert_eq!(g.nodes.len(), 3);
    }
}
