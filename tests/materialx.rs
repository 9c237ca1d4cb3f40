//! MaterialX through the bundled material-format plugin: the MaterialX project's 50
//! example materials import (all but the hair shader, which is refused by name) and
//! compile and render; Kiln's bundled materials and the imported corpus survive a trip
//! out and back as equal graphs; Standard Surface and OpenPBR constants become the
//! Principled BSDF parameters the documented formulas give.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{bundled_plugins, gpu, mean, render, rmse, settings};
use glam::{Affine3A, Vec3};
use kiln::material::graph::{GROUP_INPUT, REROUTE};
use kiln::material::nodes::{self, ParamKind};
use kiln::material::texture::TextureImage;
use kiln::material::{Graph, Input, Link, Param, Value};
use kiln::plugin::PluginHost;
use kiln::scene::{Camera, Light, Material, Scene, shapes};
use kiln::shader::principled::{ParamValue, Principled};

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus/materialx");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flat_map(|d| std::fs::read_dir(d.unwrap().path()).into_iter().flatten())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mtlx"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 50, "the corpus holds the 50 examples");
    files
}

fn is_hair(file: &Path) -> bool {
    file.to_string_lossy().contains("simple_hair")
}

/// A 2×2 grey image for every texture the corpus names (its images are not included).
fn placeholder(_: &str) -> Result<TextureImage, String> {
    Ok(TextureImage {
        width: 2,
        height: 2,
        format: 0,
        texels: vec![0xff80_8080, 0xff40_4040, 0xff40_4040, 0xff80_8080],
    })
}

#[test]
fn the_corpus_imports_compiles_and_names_what_it_cannot_read() {
    let host = bundled_plugins();
    let mut count = 0;
    for file in corpus() {
        let imported = host.import_materials(&file);
        if is_hair(&file) {
            let message = imported
                .expect_err("the hair shader is refused")
                .to_string();
            assert!(
                message.contains("chiang_hair_bsdf") && message.contains("cannot render"),
                "{message}"
            );
            continue;
        }
        let imported = imported.unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(!imported.materials.is_empty(), "{}", file.display());
        let text = std::fs::read_to_string(&file).unwrap();
        if text.contains("type=\"filename\"") {
            assert!(
                imported
                    .warnings
                    .iter()
                    .any(|w| w.contains("texture") && w.contains("is not found")),
                "{}: no warning names the missing textures: {:?}",
                file.display(),
                imported.warnings
            );
        }
        for (name, graph) in imported.materials {
            let material = Material::from_graph_with(&name, graph, &placeholder)
                .unwrap_or_else(|e| panic!("{}: {name}: {e}", file.display()));
            let compiled = kiln::material::compile(&name, &graph_of(&material), "material_0")
                .unwrap_or_else(|e| panic!("{}: {name}: {e}", file.display()));
            let kernel = kiln::render::kernel::path_tracing_kernel(
                &kiln::shader::KernelFeatures::default(),
                &kiln::material::materials_wgsl(&[(0, &compiled)]),
            );
            kernel
                .validate()
                .unwrap_or_else(|e| panic!("{}: {name}: the kernel: {e}", file.display()));
            count += 1;
        }
    }
    eprintln!("{count} materials imported, compiled and validated");
    assert!(count >= 60, "only {count} materials");
}

fn graph_of(m: &Material) -> Graph {
    m.graph.as_ref().expect("a graph material").graph.clone()
}

/// Spheres of the given materials in a grid under a lamp and a sky.
fn spheres(materials: Vec<Material>, columns: usize) -> Scene {
    let rows = materials.len().div_ceil(columns);
    let mut scene = Scene::empty(Camera::look_at(
        Vec3::new(0.0, 0.0, 2.2 * columns as f32),
        Vec3::ZERO,
        40.0,
    ));
    scene.environment = Vec3::new(0.3, 0.35, 0.4);
    scene.add_light(Light::Point {
        position: Vec3::new(3.0, 4.0, 6.0),
        intensity: Vec3::splat(60.0),
        radius: 0.3,
    });
    let ball = scene.add_mesh(shapes::uv_sphere(24, 12, true));
    for (i, m) in materials.into_iter().enumerate() {
        let id = scene.add_material(m);
        let (c, r) = ((i % columns) as f32, (i / columns) as f32);
        let at = Vec3::new(
            (c - (columns - 1) as f32 / 2.0) * 1.1,
            ((rows - 1) as f32 / 2.0 - r) * 1.1,
            0.0,
        );
        scene.add_instance(
            ball,
            id,
            Affine3A::from_scale_rotation_translation(Vec3::splat(0.5), Default::default(), at),
        );
    }
    scene
}

#[test]
fn the_corpus_renders_finite_images() {
    let host = bundled_plugins();
    let mut materials = Vec::new();
    for file in corpus().into_iter().filter(|f| !is_hair(f)) {
        for (name, graph) in host.import_materials(&file).unwrap().materials {
            materials.push(Material::from_graph_with(&name, graph, &placeholder).unwrap());
        }
    }
    let n = materials.len();
    // `render` fails on any non-finite sample.
    let film = render(&gpu(), &spheres(materials, 9), settings(144, 128, 4));
    let radiance = film.radiance();
    assert!(radiance.iter().all(|p| p.is_finite()));
    assert!(mean(&radiance).max_element() > 0.01, "the spheres are lit");
    eprintln!("{n} corpus materials rendered");
}

/// `graph` in a form two graphs computing the same share: reroutes bypassed, inputs and
/// parameters left at their defaults written out, group inputs' nodes one id, the output
/// node `output`, image files by name, positions, previews and frames dropped.
fn canonical(graph: &Graph) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut add = |prefix: &str, nodes: &BTreeMap<String, kiln::material::Node>| {
        let rename = |id: &str| -> String {
            match nodes.get(id).map(|n| n.kind.as_str()) {
                Some(GROUP_INPUT) => "group_input".into(),
                Some("material_output") => "output".into(),
                _ => id.into(),
            }
        };
        // A link through reroutes, to its source.
        let source = |l: &Link| -> String {
            let mut l = l.clone();
            while let Some(Input::Link(next)) = nodes
                .get(&l.node)
                .filter(|n| n.kind == REROUTE)
                .and_then(|n| n.inputs.get("input"))
            {
                l = next.clone();
            }
            format!("{}.{}", rename(&l.node), l.socket)
        };
        for (id, node) in nodes {
            if node.kind == REROUTE {
                continue;
            }
            let mut params: BTreeMap<String, String> = BTreeMap::new();
            let mut inputs: BTreeMap<String, String> = BTreeMap::new();
            if let Some(def) = nodes::find(&node.kind) {
                for p in &def.params {
                    let default = match p.kind {
                        ParamKind::Enum(options) => format!("{:?}", Param::Text(options[0].into())),
                        ParamKind::Bool(b) => format!("{:?}", Param::Bool(b)),
                        _ => continue,
                    };
                    params.insert(p.name.into(), default);
                }
                for s in &def.inputs {
                    if let nodes::Default::Value(v) = &s.default {
                        inputs.insert(s.name.into(), value(v, s.ty));
                    }
                }
            }
            for (k, p) in &node.params {
                let p = match p {
                    Param::Text(t) if k == "file" => {
                        Param::Text(Path::new(t).file_name().unwrap().to_string_lossy().into())
                    }
                    p => p.clone(),
                };
                params.insert(k.clone(), format!("{p:?}"));
            }
            for (k, i) in &node.inputs {
                let ty = nodes::find(&node.kind)
                    .and_then(|d| d.input(k))
                    .map_or(kiln::material::SocketType::Float, |s| s.ty);
                inputs.insert(
                    k.clone(),
                    match i {
                        Input::Link(l) => source(l),
                        Input::Value(v) => value(v, ty),
                    },
                );
            }
            out.insert(
                format!("{prefix}{}", rename(id)),
                format!("{} {params:?} {inputs:?} muted={}", node.kind, node.muted),
            );
        }
    };
    add("", &graph.nodes);
    let mut interfaces = Vec::new();
    for (name, group) in &graph.groups {
        add(&format!("{name}/"), &group.nodes);
        let links: BTreeMap<_, _> = group
            .links
            .iter()
            .map(|(k, l)| (k, l.to_string()))
            .collect();
        interfaces.push((
            format!("{name}/"),
            format!("{:?} {:?} {links:?}", group.inputs, group.outputs),
        ));
    }
    out.extend(interfaces);
    out
}

/// A constant as its input reads it (a float fed to a colour is grey).
fn value(v: &Value, ty: kiln::material::SocketType) -> String {
    use kiln::material::SocketType::*;
    match ty {
        Float => format!("{:?}", v.as_f32()),
        _ => format!("{:?}", v.as_vec3()),
    }
}

fn assert_same(a: &Graph, b: &Graph, what: &str) {
    let (a, b) = (canonical(a), canonical(b));
    for (k, v) in &a {
        assert_eq!(Some(v), b.get(k), "{what}: node {k} differs");
    }
    for k in b.keys() {
        assert!(a.contains_key(k), "{what}: node {k} is new");
    }
}

/// `graph` written by the exporter to `dir` and read back.
fn round_trip(host: &PluginHost, dir: &Path, name: &str, graph: &Graph) -> Graph {
    let file = dir.join(format!("{}.mtlx", name.replace(['/', ' '], "_")));
    host.export_material(&file, name, graph)
        .unwrap_or_else(|e| panic!("{name}: export: {e}"));
    let mut back = host
        .import_materials(&file)
        .unwrap_or_else(|e| panic!("{name}: import of {}: {e}", file.display()))
        .materials;
    assert_eq!(back.len(), 1, "{name}: one material written, one read");
    back.remove(0).1
}

#[test]
fn bundled_materials_survive_export_and_import() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials");
    let mut count = 0;
    for entry in std::fs::read_dir(folder).unwrap() {
        let (name, graph) = kiln::material::load_material(&entry.unwrap().path()).unwrap();
        let back = round_trip(&host, dir.path(), &name, &graph);
        assert_same(&graph, &back, &name);
        count += 1;
    }
    assert!(count >= 17);
}

#[test]
fn the_corpus_survives_import_export_import() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    for file in corpus().into_iter().filter(|f| !is_hair(f)) {
        for (name, graph) in host.import_materials(&file).unwrap().materials {
            let back = round_trip(&host, dir.path(), &name, &graph);
            assert_same(&graph, &back, &format!("{}: {name}", file.display()));
        }
    }
}

/// A MaterialX document of one `category` shader with constant `inputs`.
fn shader_document(category: &str, inputs: &[(&str, &str, &str)]) -> String {
    let mut text = format!(
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <{category} name=\"S\" type=\"surfaceshader\">\n"
    );
    for (name, ty, value) in inputs {
        text.push_str(&format!(
            "    <input name=\"{name}\" type=\"{ty}\" value=\"{value}\" />\n"
        ));
    }
    text.push_str(&format!(
        "  </{category}>\n  <surfacematerial name=\"M\" type=\"material\">\n    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"S\" />\n  </surfacematerial>\n</materialx>\n"
    ));
    text
}

/// Standard Surface and OpenPBR materials of constants, and the Principled BSDF the
/// formulas of docs/MATERIALX.md give for each.
fn mapping_cases() -> Vec<(&'static str, String, Principled)> {
    let p = Principled::default();
    let standard = |inputs: &[(&str, &str, &str)]| shader_document("standard_surface", inputs);
    let open_pbr = |inputs: &[(&str, &str, &str)]| shader_document("open_pbr_surface", inputs);
    // Standard Surface's defaults as the Principled BSDF (the translation of
    // standard_surface_to_open_pbr, then OpenPBR's names).
    let ss = Principled {
        base_color: Vec3::splat(0.8),
        roughness: 0.2,
        coat_roughness: 0.1,
        coat_ior: 1.5,
        sheen_roughness: 0.3f32.powf(0.4),
        subsurface_radius: Vec3::ONE,
        subsurface_scale: 1.0,
        ..p
    };
    // OpenPBR's defaults.
    let op = Principled {
        roughness: 0.3,
        coat_roughness: 0.0,
        coat_ior: 1.6,
        sheen_roughness: 0.5,
        subsurface_radius: Vec3::new(1.0, 0.5, 0.25),
        subsurface_scale: 1.0,
        ..p
    };
    vec![
        (
            "standard metal",
            standard(&[
                ("base_color", "color3", "0.95, 0.64, 0.54"),
                ("metalness", "float", "1"),
                ("specular", "float", "0.5"),
                ("specular_roughness", "float", "0.25"),
            ]),
            // A metal's specular weight is 1 in the translation.
            Principled {
                base_color: Vec3::new(0.95, 0.64, 0.54),
                metallic: 1.0,
                roughness: 0.25,
                ..ss
            },
        ),
        (
            "standard glass",
            standard(&[
                ("base", "float", "0"),
                ("transmission", "float", "1"),
                ("transmission_color", "color3", "0.8, 0.9, 1"),
                ("specular_IOR", "float", "1.45"),
                ("specular_roughness", "float", "0.05"),
            ]),
            Principled {
                base_weight: 0.0,
                transmission_weight: 1.0,
                transmission_color: Vec3::new(0.8, 0.9, 1.0),
                ior: 1.45,
                roughness: 0.05,
                ..ss
            },
        ),
        (
            "standard coat",
            standard(&[
                ("base_color", "color3", "0.1, 0.2, 0.6"),
                ("coat", "float", "0.5"),
                ("coat_color", "color3", "0.9, 0.8, 0.7"),
                ("coat_roughness", "float", "0.02"),
            ]),
            // The base is tinted by mix(1, coat_color, coat).
            Principled {
                base_color: Vec3::new(0.1 * 0.95, 0.2 * 0.9, 0.6 * 0.85),
                coat_weight: 0.5,
                coat_color: Vec3::new(0.9, 0.8, 0.7),
                coat_roughness: 0.02,
                ..ss
            },
        ),
        (
            "standard sheen",
            standard(&[
                ("sheen", "float", "1"),
                ("sheen_color", "color3", "0.5, 0.2, 0.8"),
                ("sheen_roughness", "float", "0.5"),
            ]),
            Principled {
                sheen_weight: 1.0,
                sheen_color: Vec3::new(0.5, 0.2, 0.8),
                sheen_roughness: 0.5f32.powf(0.4),
                ..ss
            },
        ),
        (
            "standard subsurface",
            standard(&[
                ("base_color", "color3", "0.8, 0.8, 0.8"),
                ("subsurface", "float", "1"),
                ("subsurface_color", "color3", "0.9, 0.5, 0.4"),
                ("subsurface_radius", "color3", "1, 0.4, 0.2"),
                ("subsurface_scale", "float", "0.1"),
            ]),
            // Kiln's subsurface scatters the base colour: the subsurface colour here.
            Principled {
                base_color: Vec3::new(0.9, 0.5, 0.4),
                subsurface_weight: 1.0,
                subsurface_radius: Vec3::new(1.0, 0.4, 0.2),
                subsurface_scale: 0.1,
                ..ss
            },
        ),
        (
            "OpenPBR metal",
            open_pbr(&[
                ("base_color", "color3", "0.9, 0.7, 0.3"),
                ("base_metalness", "float", "1"),
                ("specular_roughness", "float", "0.35"),
                ("specular_color", "color3", "1, 0.9, 0.8"),
            ]),
            Principled {
                base_color: Vec3::new(0.9, 0.7, 0.3),
                metallic: 1.0,
                roughness: 0.35,
                specular_color: Vec3::new(1.0, 0.9, 0.8),
                ..op
            },
        ),
        (
            "OpenPBR glass",
            open_pbr(&[
                ("transmission_weight", "float", "1"),
                ("transmission_color", "color3", "0.7, 0.9, 0.8"),
                ("transmission_depth", "float", "0.5"),
                ("specular_ior", "float", "1.6"),
                ("specular_roughness", "float", "0.1"),
            ]),
            Principled {
                transmission_weight: 1.0,
                transmission_color: Vec3::new(0.7, 0.9, 0.8),
                transmission_depth: 0.5,
                ior: 1.6,
                roughness: 0.1,
                ..op
            },
        ),
        (
            "OpenPBR coat",
            open_pbr(&[
                ("base_color", "color3", "0.6, 0.1, 0.1"),
                ("coat_weight", "float", "1"),
                ("coat_roughness", "float", "0.1"),
                ("coat_ior", "float", "1.5"),
            ]),
            Principled {
                base_color: Vec3::new(0.6, 0.1, 0.1),
                coat_weight: 1.0,
                coat_roughness: 0.1,
                coat_ior: 1.5,
                ..op
            },
        ),
        (
            "OpenPBR sheen",
            open_pbr(&[
                ("fuzz_weight", "float", "0.8"),
                ("fuzz_color", "color3", "0.3, 0.6, 0.9"),
                ("fuzz_roughness", "float", "0.4"),
            ]),
            Principled {
                sheen_weight: 0.8,
                sheen_color: Vec3::new(0.3, 0.6, 0.9),
                sheen_roughness: 0.4,
                ..op
            },
        ),
        (
            "OpenPBR subsurface",
            open_pbr(&[
                ("base_color", "color3", "0.9, 0.6, 0.5"),
                ("subsurface_weight", "float", "1"),
                ("subsurface_radius", "float", "0.2"),
                ("subsurface_radius_scale", "color3", "1, 0.5, 0.3"),
                ("subsurface_scatter_anisotropy", "float", "0.3"),
            ]),
            Principled {
                base_color: Vec3::new(0.9, 0.6, 0.5),
                subsurface_weight: 1.0,
                subsurface_scale: 0.2,
                subsurface_radius: Vec3::new(1.0, 0.5, 0.3),
                subsurface_anisotropy: 0.3,
                ..op
            },
        ),
    ]
}

#[test]
fn standard_surface_and_open_pbr_constants_become_the_documented_principled_bsdf() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let mut imported = Vec::new();
    let mut expected = Vec::new();
    for (what, document, want) in mapping_cases() {
        let file = dir.path().join(format!("{}.mtlx", what.replace(' ', "_")));
        std::fs::write(&file, document).unwrap();
        let (_, graph) = host.import_materials(&file).unwrap().materials.remove(0);
        // The surface's parameters: every input a constant, each the formula's value.
        let surface = graph
            .nodes
            .values()
            .find(|n| n.kind == "principled_bsdf")
            .expect("a principled node");
        for p in &kiln::shader::principled::PARAMETERS {
            let Some(input) = surface.inputs.get(p.name) else {
                continue;
            };
            let Input::Value(v) = input else {
                panic!("{what}: {} is not a constant: {input:?}", p.name);
            };
            let (got, want) = match want.get(p.name).unwrap() {
                ParamValue::Float(x) => (Vec3::splat(v.as_f32()), Vec3::splat(x)),
                ParamValue::Color(c) => (Vec3::from(v.as_vec3()), c),
                ParamValue::Bool(_) => continue,
            };
            assert!(
                (got - want).abs().max_element() < 1e-5,
                "{what}: {} is {got}, the formula gives {want}",
                p.name
            );
        }
        imported.push(Material::from_graph(what, graph).unwrap());
        expected.push(Material {
            name: what.into(),
            principled: want,
            ..Material::default()
        });
    }
    // And they render as the hand-written materials do.
    let s = settings(100, 48, 32);
    let a = render(&gpu(), &spheres(expected, 5), s).radiance();
    let b = render(&gpu(), &spheres(imported, 5), s).radiance();
    let error = rmse(&a, &b) / mean(&a).max_element() as f64;
    eprintln!("relative RMSE, imported vs hand-written: {error:e}");
    assert!(
        error < 1e-3,
        "imported materials render differently: {error}"
    );
}

/// Runs MaterialX's own validation (`Document.validate()` with the standard libraries)
/// on `files`, in a virtual environment with the `MaterialX` package from PyPI made in
/// the target folder on first use.
fn materialx_validate(files: &[PathBuf]) {
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/materialx-venv");
    let python = target.join("bin/python");
    if !python.exists() {
        let made = std::process::Command::new("python3")
            .args(["-m", "venv"])
            .arg(&target)
            .status()
            .expect("python3 runs");
        assert!(
            made.success(),
            "cannot make a virtual environment at {}",
            target.display()
        );
    }
    let has = std::process::Command::new(&python)
        .args(["-c", "import MaterialX"])
        .status()
        .unwrap();
    if !has.success() {
        let pip = std::process::Command::new(target.join("bin/pip"))
            .args(["install", "--quiet", "MaterialX==1.39.5"])
            .status()
            .unwrap();
        assert!(pip.success(), "pip cannot install MaterialX from PyPI");
    }
    // Valid, and MaterialX's own code generators (GLSL for surfaces, MDL for volumes,
    // which its GLSL generator lacks) turn every shader whose nodes all have an
    // implementation into code: the implementations are complete and well typed.
    let script = r#"
import sys, MaterialX as mx
import MaterialX.PyMaterialXGenShader as gen
import MaterialX.PyMaterialXGenGlsl as glsl
import MaterialX.PyMaterialXGenMdl as mdl
lib = mx.createDocument()
mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
generators = [
    (mx.SURFACE_SHADER_TYPE_STRING, glsl.GlslShaderGenerator.create()),
    (mx.VOLUME_SHADER_TYPE_STRING, mdl.MdlShaderGenerator.create()),
]
bad = generated = 0
skipped = set()
for f in sys.argv[1:]:
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, f)
    doc.importLibrary(lib)
    ok, message = doc.validate()
    if not ok:
        bad += 1
        print(f"{f}: {message}")
        continue
    unimplemented = [d.getNodeString() for d in doc.getNodeDefs()
                     if d.getNodeString().startswith("kiln_") and d.getImplementation() is None]
    for material in doc.getMaterialNodes():
        for kind, generator in generators:
            context = gen.GenContext(generator)
            context.registerSourceCodeSearchPath(mx.getDefaultDataSearchPath())
            for shader in mx.getShaderNodes(material, kind):
                try:
                    generator.generate(shader.getName(), shader, context)
                    generated += 1
                except Exception as e:
                    if unimplemented:
                        skipped.add(f"{material.getName()} ({', '.join(unimplemented)})")
                    else:
                        bad += 1
                        print(f"{f}: {material.getName()}: {e}")
print(f"{generated} shaders generated; not generated, for nodes without an implementation: {sorted(skipped)}", file=sys.stderr)
sys.exit(1 if bad else 0)
"#;
    let out = std::process::Command::new(&python)
        .arg("-c")
        .arg(script)
        .args(files)
        .output()
        .unwrap();
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "MaterialX finds invalid files:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn every_file_the_exporter_writes_passes_materialx_validation() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials");
    let mut graphs = Vec::new();
    for entry in std::fs::read_dir(folder).unwrap() {
        graphs.push(kiln::material::load_material(&entry.unwrap().path()).unwrap());
    }
    for file in corpus().into_iter().filter(|f| !is_hair(f)) {
        graphs.extend(host.import_materials(&file).unwrap().materials);
    }
    // The implementations no bundled material uses: distorted and plain waves, the
    // Geometry node's outputs MaterialX has no node for, Vector Math's refract, modulo
    // and wrap.
    graphs.push(
        kiln::material::parse_material(
            r#"(
    version: 1,
    name: "Implementations",
    nodes: {
        "geometry": (type: "geometry"),
        "wave": (type: "wave_texture", params: { "wave_type": "rings", "profile": "saw" }, inputs: { "distortion": 2.0, "detail": 3.0 }),
        "plain": (type: "wave_texture", inputs: { "vector": "geometry.incoming" }),
        "refract": (type: "vector_math", params: { "operation": "refract" }, inputs: { "a": "geometry.incoming", "b": "geometry.true_normal", "scale": 0.7 }),
        "modulo": (type: "vector_math", params: { "operation": "modulo" }, inputs: { "a": "refract.vector", "b": (0.3, 0.5, 0.0) }),
        "wrap": (type: "vector_math", params: { "operation": "wrap" }, inputs: { "a": "modulo.vector", "b": (1.0, 1.0, 1.0), "c": (-1.0, 0.0, 0.5) }),
        "mix": (type: "mix_color", inputs: { "factor": "geometry.backfacing", "a": "wave.color", "b": "plain.color" }),
        "surface": (type: "principled_bsdf", inputs: { "base_color": "mix.result", "normal": "wrap.vector" }),
        "out": (type: "material_output", inputs: { "surface": "surface.bsdf" }),
    },
)"#,
            "implementations.kmat",
        )
        .unwrap(),
    );
    // Brick, White Noise, Voronoi F2 and Smooth F1 (Minkowski), Object Info, every blend mode of the
    // Mix node, and the three volume shaders.
    let mut nodes = vec![
        r#""info": (type: "object_info")"#.to_owned(),
        r#""brick": (type: "brick_texture", inputs: { "vector": "info.location", "bias": 0.3 })"#.to_owned(),
        r#""white": (type: "white_noise_texture")"#.to_owned(),
        r#""f2": (type: "voronoi_texture", params: { "feature": "f2" })"#.to_owned(),
        r#""smooth": (type: "voronoi_texture", params: { "feature": "smooth_f1", "distance": "minkowski" }, inputs: { "vector": "f2.position" })"#.to_owned(),
        r#""blend0": (type: "mix_color", inputs: { "factor": "white.value", "a": "brick.color", "b": "f2.color" })"#.to_owned(),
    ];
    let blends = kiln::material::nodes::find("mix_color")
        .and_then(|d| d.param("blend"))
        .map(|p| match &p.kind {
            kiln::material::nodes::ParamKind::Enum(options) => options.to_vec(),
            _ => Vec::new(),
        })
        .unwrap();
    for (i, blend) in blends.iter().enumerate() {
        nodes.push(format!(
            r#""blend{}": (type: "mix_color", params: {{ "blend": "{blend}" }}, inputs: {{ "factor": "smooth.distance", "a": "blend{i}.result", "b": "white.color" }})"#,
            i + 1
        ));
    }
    nodes.push(format!(
        r#""surface": (type: "principled_bsdf", inputs: {{ "base_color": "blend{}.result", "roughness": "info.random" }})"#,
        blends.len()
    ));
    nodes.push(
        r#""volume": (type: "principled_volume", inputs: { "emission_strength": 0.5 })"#.to_owned(),
    );
    nodes.push(r#""out": (type: "material_output", inputs: { "surface": "surface.bsdf", "volume": "volume.volume" })"#.to_owned());
    let text = format!(
        "(version: 1, name: \"Implementations 2\", nodes: {{ {} }})",
        nodes.join(", ")
    );
    graphs.push(kiln::material::parse_material(&text, "implementations2.kmat").unwrap());
    for (name, volume) in [
        (
            "Absorption",
            r#"(type: "volume_absorption", inputs: { "density": 2.0 })"#,
        ),
        (
            "Scatter",
            r#"(type: "volume_scatter", inputs: { "anisotropy": 0.4 })"#,
        ),
    ] {
        let text = format!(
            r#"(version: 1, name: "{name}", nodes: {{ "v": {volume}, "out": (type: "material_output", inputs: {{ "volume": "v.volume" }}) }})"#
        );
        graphs.push(kiln::material::parse_material(&text, "volume.kmat").unwrap());
    }
    // Those read back as they were written (Voronoi's `distance` output is renamed apart
    // from its `distance` parameter in the file).
    let extra = graphs.len() - 3;
    for (name, graph) in &graphs[extra..] {
        let back = round_trip(&host, dir.path(), name, graph);
        assert_same(graph, &back, name);
    }
    for (i, (name, graph)) in graphs.iter().enumerate() {
        let file = dir.path().join(format!("{i}.mtlx"));
        host.export_material(&file, name, graph)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        files.push(file);
    }
    eprintln!("{} exported files", files.len());
    materialx_validate(&files);
}

/// A float of an imported graph: the few nodes the 2D ramps and splits import as, evaluated
/// at constant inputs (Kiln's semantics: mix_float clamps its factor).
fn evaluate(graph: &Graph, input: &Input, socket_type: &str) -> f32 {
    match input {
        Input::Value(Value::Float(x)) => *x,
        Input::Value(v) => panic!("a {socket_type} constant {v:?}"),
        Input::Link(link) => {
            let node = &graph.nodes[&link.node];
            let get = |name: &str| evaluate(graph, &node.inputs[name], name);
            match (node.kind.as_str(), link.socket.as_str()) {
                ("separate_xyz", axis) => {
                    let i = ["x", "y", "z"].iter().position(|a| *a == axis).unwrap();
                    match &node.inputs["vector"] {
                        Input::Value(Value::Vec3(v)) => v[i],
                        Input::Value(Value::Vec2(v)) => v[i],
                        other => panic!("separate_xyz of {other:?}"),
                    }
                }
                ("mix_float", "result") => {
                    let t = get("factor").clamp(0.0, 1.0);
                    get("a") + (get("b") - get("a")) * t
                }
                ("math", "value") => {
                    assert_eq!(node.params["operation"], Param::Text("greater_than".into()));
                    if get("a") > get("b") { 1.0 } else { 0.0 }
                }
                (kind, socket) => panic!("unexpected {kind}.{socket}"),
            }
        }
    }
}

#[test]
fn ramps_and_splits_of_texture_coordinates_import_as_materialx_defines_them() {
    let dir = tempfile::tempdir().unwrap();
    let host = bundled_plugins();
    let ramp4 = "<input name=\"valuetl\" type=\"float\" value=\"0.1\" /><input name=\"valuetr\" type=\"float\" value=\"0.9\" /><input name=\"valuebl\" type=\"float\" value=\"0.3\" /><input name=\"valuebr\" type=\"float\" value=\"0.6\" />";
    let lr = "<input name=\"valuel\" type=\"float\" value=\"0.2\" /><input name=\"valuer\" type=\"float\" value=\"0.7\" /><input name=\"center\" type=\"float\" value=\"0.4\" />";
    let tb = "<input name=\"valuet\" type=\"float\" value=\"0.2\" /><input name=\"valueb\" type=\"float\" value=\"0.7\" />";
    for (s, t) in [(0.25f32, 0.8f32), (0.6, 0.1), (-0.5, 1.5)] {
        let (sc, tc) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let lerp = |a: f32, b: f32, x: f32| a + (b - a) * x;
        let step = |center: f32, x: f32| if x > center { 1.0 } else { 0.0 };
        for (category, inputs, expected) in [
            (
                "ramp4",
                ramp4,
                lerp(lerp(0.1, 0.9, sc), lerp(0.3, 0.6, sc), tc),
            ),
            ("splitlr", lr, lerp(0.2, 0.7, step(0.4, s))),
            ("splittb", tb, lerp(0.2, 0.7, step(0.5, t))),
        ] {
            let text = format!(
                "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <{category} name=\"pattern\" type=\"float\">{inputs}<input name=\"texcoord\" type=\"vector2\" value=\"{s}, {t}\" /></{category}>\n  <open_pbr_surface name=\"surface\" type=\"surfaceshader\"><input name=\"specular_roughness\" type=\"float\" nodename=\"pattern\" /></open_pbr_surface>\n  <surfacematerial name=\"M\" type=\"material\"><input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"surface\" /></surfacematerial>\n</materialx>\n"
            );
            let path = dir.path().join(format!("{category}.mtlx"));
            std::fs::write(&path, text).unwrap();
            let imported = host.import_materials(&path).unwrap();
            assert!(
                imported.warnings.is_empty(),
                "{category}: {:?}",
                imported.warnings
            );
            let graph = &imported.materials[0].1;
            let bsdf = graph
                .nodes
                .values()
                .find(|n| n.kind == "principled_bsdf")
                .expect("the surface");
            let value = evaluate(graph, &bsdf.inputs["roughness"], "roughness");
            assert!(
                (value - expected).abs() < 1e-6,
                "{category} at ({s}, {t}): {value}, MaterialX gives {expected}"
            );
        }
    }
}

/// A document whose material's surface is pbrlib's `surface` node `S` with `inputs`,
/// beside closure nodes `nodes`.
fn closure_document(nodes: &str, inputs: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n{nodes}\n  <surface name=\"S\" type=\"surfaceshader\">\n{inputs}\n  </surface>\n  <surfacematerial name=\"M\" type=\"material\">\n    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"S\" />\n  </surfacematerial>\n</materialx>\n"
    )
}

const DIFFUSE: &str = r#"  <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF">
    <input name="color" type="color3" value="0.7, 0.3, 0.2" />
    <input name="roughness" type="float" value="0.5" />
  </oren_nayar_diffuse_bsdf>"#;

const SPECULAR_OVER_DIFFUSE: &str = r#"  <roughness_anisotropy name="alpha" type="vector2">
    <input name="roughness" type="float" value="0.35" />
  </roughness_anisotropy>
  <dielectric_bsdf name="specular" type="BSDF">
    <input name="ior" type="float" value="1.4" />
    <input name="roughness" type="vector2" nodename="alpha" />
  </dielectric_bsdf>
  <layer name="plastic" type="BSDF">
    <input name="top" type="BSDF" nodename="specular" />
    <input name="base" type="BSDF" nodename="diffuse" />
  </layer>"#;

const GOLD: &str = r#"  <conductor_bsdf name="metal" type="BSDF">
    <input name="ior" type="color3" value="0.143, 0.374, 1.442" />
    <input name="extinction" type="color3" value="3.983, 2.385, 1.603" />
    <input name="roughness" type="vector2" value="0.09, 0.09" />
  </conductor_bsdf>"#;

/// Closure graphs as other tools write them (the structures Standard Surface and OpenPBR
/// are built of), with the Principled BSDF inputs docs/MATERIALX.md says they fold to.
/// What a closure graph is called, its document, and the Principled BSDF inputs (Kiln
/// names) it folds to.
type ClosureCase = (&'static str, String, Vec<(&'static str, [f32; 3])>);

fn closure_cases() -> Vec<ClosureCase> {
    // Normal-incidence reflectance of gold's complex index.
    let gold_f0 = {
        let f0 = |n: f32, k: f32| ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        [f0(0.143, 3.983), f0(0.374, 2.385), f0(1.442, 1.603)]
    };
    let doc = |nodes: &[&str], top: &str, extra: &str| {
        let bsdf = format!(r#"    <input name="bsdf" type="BSDF" nodename="{top}" />"#);
        closure_document(&nodes.join("\n"), &format!("{bsdf}\n{extra}"))
    };
    vec![
        (
            "diffuse",
            doc(&[DIFFUSE], "diffuse", ""),
            vec![
                ("base_weight", [1.0; 3]),
                ("base_color", [0.7, 0.3, 0.2]),
                ("diffuse_roughness", [0.5; 3]),
                ("specular_weight", [0.0; 3]),
                ("metallic", [0.0; 3]),
            ],
        ),
        (
            "plastic",
            doc(&[DIFFUSE, SPECULAR_OVER_DIFFUSE], "plastic", ""),
            vec![
                ("base_weight", [1.0; 3]),
                ("base_color", [0.7, 0.3, 0.2]),
                ("specular_weight", [1.0; 3]),
                ("ior", [1.4; 3]),
                ("roughness", [0.35; 3]),
                ("anisotropy", [0.0; 3]),
                ("coat_weight", [0.0; 3]),
            ],
        ),
        (
            "gold",
            doc(&[GOLD], "metal", ""),
            vec![
                ("metallic", [1.0; 3]),
                ("base_color", gold_f0),
                ("roughness", [0.3; 3]),
                ("specular_weight", [0.0; 3]),
            ],
        ),
        (
            "metal mixed with plastic",
            doc(
                &[
                    DIFFUSE,
                    SPECULAR_OVER_DIFFUSE,
                    GOLD,
                    r#"  <mix name="mixed" type="BSDF">
    <input name="fg" type="BSDF" nodename="metal" />
    <input name="bg" type="BSDF" nodename="plastic" />
    <input name="mix" type="float" value="0.3" />
  </mix>"#,
                ],
                "mixed",
                "",
            ),
            vec![
                ("metallic", [0.3; 3]),
                ("base_weight", [1.0; 3]),
                ("specular_weight", [1.0; 3]),
                (
                    "base_color",
                    std::array::from_fn(|i| [0.7, 0.3, 0.2][i] * 0.7 + gold_f0[i] * 0.3),
                ),
                ("roughness", [0.35 * 0.7 + 0.3 * 0.3; 3]),
            ],
        ),
        (
            "glass",
            doc(
                &[r#"  <dielectric_bsdf name="glass" type="BSDF">
    <input name="tint" type="color3" value="0.8, 0.9, 1" />
    <input name="ior" type="float" value="1.45" />
    <input name="roughness" type="vector2" value="0.0025, 0.0025" />
    <input name="scatter_mode" type="string" value="RT" />
  </dielectric_bsdf>"#],
                "glass",
                "",
            ),
            vec![
                ("transmission_weight", [1.0; 3]),
                ("transmission_color", [0.8, 0.9, 1.0]),
                ("specular_weight", [1.0; 3]),
                ("ior", [1.45; 3]),
                ("roughness", [0.05; 3]),
                ("base_weight", [0.0; 3]),
            ],
        ),
        (
            "coat",
            doc(
                &[
                    DIFFUSE,
                    SPECULAR_OVER_DIFFUSE,
                    r#"  <dielectric_bsdf name="coat" type="BSDF">
    <input name="weight" type="float" value="0.6" />
    <input name="ior" type="float" value="1.6" />
    <input name="roughness" type="vector2" value="0.01, 0.01" />
  </dielectric_bsdf>
  <layer name="coated" type="BSDF">
    <input name="top" type="BSDF" nodename="coat" />
    <input name="base" type="BSDF" nodename="plastic" />
  </layer>"#,
                ],
                "coated",
                "",
            ),
            vec![
                ("coat_weight", [0.6; 3]),
                ("coat_ior", [1.6; 3]),
                ("coat_roughness", [0.1; 3]),
                ("specular_weight", [1.0; 3]),
                ("ior", [1.4; 3]),
                ("base_color", [0.7, 0.3, 0.2]),
            ],
        ),
        (
            "sheen",
            doc(
                &[
                    DIFFUSE,
                    r#"  <sheen_bsdf name="sheen" type="BSDF">
    <input name="weight" type="float" value="0.7" />
    <input name="color" type="color3" value="0.5, 0.2, 0.8" />
    <input name="roughness" type="float" value="0.5" />
    <input name="mode" type="string" value="zeltner" />
  </sheen_bsdf>
  <layer name="cloth" type="BSDF">
    <input name="top" type="BSDF" nodename="sheen" />
    <input name="base" type="BSDF" nodename="diffuse" />
  </layer>"#,
                ],
                "cloth",
                "",
            ),
            vec![
                ("sheen_weight", [0.7; 3]),
                ("sheen_color", [0.5, 0.2, 0.8]),
                ("sheen_roughness", [0.5; 3]),
                ("base_weight", [1.0; 3]),
            ],
        ),
        (
            "subsurface",
            doc(
                &[r#"  <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF">
    <input name="color" type="color3" value="0.9, 0.5, 0.4" />
  </oren_nayar_diffuse_bsdf>
  <subsurface_bsdf name="skin" type="BSDF">
    <input name="color" type="color3" value="0.9, 0.5, 0.4" />
    <input name="radius" type="color3" value="0.1, 0.04, 0.02" />
    <input name="anisotropy" type="float" value="0.3" />
  </subsurface_bsdf>
  <mix name="mixed" type="BSDF">
    <input name="fg" type="BSDF" nodename="skin" />
    <input name="bg" type="BSDF" nodename="diffuse" />
    <input name="mix" type="float" value="0.8" />
  </mix>"#],
                "mixed",
                "",
            ),
            vec![
                ("subsurface_weight", [0.8; 3]),
                ("base_weight", [1.0; 3]),
                ("base_color", [0.9, 0.5, 0.4]),
                ("subsurface_scale", [0.1; 3]),
                ("subsurface_radius", [1.0, 0.4, 0.2]),
                ("subsurface_anisotropy", [0.3; 3]),
            ],
        ),
        (
            "emission and opacity",
            doc(
                &[
                    DIFFUSE,
                    r#"  <uniform_edf name="glow" type="EDF">
    <input name="color" type="color3" value="2, 1, 0.5" />
  </uniform_edf>"#,
                ],
                "diffuse",
                r#"    <input name="edf" type="EDF" nodename="glow" />
    <input name="opacity" type="float" value="0.4" />"#,
            ),
            vec![
                ("emission_color", [1.0, 0.5, 0.25]),
                ("emission_strength", [2.0; 3]),
                ("alpha", [0.4; 3]),
                ("base_color", [0.7, 0.3, 0.2]),
            ],
        ),
    ]
}

#[test]
fn closure_graphs_fold_onto_the_documented_principled_bsdf() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let mut imported = Vec::new();
    for (what, document, want) in closure_cases() {
        let file = dir.path().join(format!("{}.mtlx", what.replace(' ', "_")));
        std::fs::write(&file, document).unwrap();
        let (_, graph) = host
            .import_materials(&file)
            .unwrap_or_else(|e| panic!("{what}: {e}"))
            .materials
            .remove(0);
        let surface = graph
            .nodes
            .values()
            .find(|n| n.kind == "principled_bsdf")
            .expect("a principled node");
        for (name, value) in want {
            let Some(Input::Value(v)) = surface.inputs.get(name) else {
                panic!(
                    "{what}: {name} is not a constant: {:?}",
                    surface.inputs.get(name)
                );
            };
            let got = match v {
                Value::Float(x) => [*x; 3],
                v => v.as_vec3(),
            };
            assert!(
                (0..3).all(|i| (got[i] - value[i]).abs() < 1e-4),
                "{what}: {name} is {got:?}, the fold gives {value:?}"
            );
        }
        imported.push(Material::from_graph(what, graph).unwrap());
    }
    // And they render, finite.
    let image = render(&gpu(), &spheres(imported, 5), settings(100, 48, 8)).radiance();
    assert!(image.iter().all(|p| p.is_finite()));

    // A varying factor stays a connection; a hair closure is refused by name.
    let varying = doc_with_varying_metal();
    let file = dir.path().join("varying.mtlx");
    std::fs::write(&file, varying).unwrap();
    let (_, graph) = host.import_materials(&file).unwrap().materials.remove(0);
    let surface = graph
        .nodes
        .values()
        .find(|n| n.kind == "principled_bsdf")
        .unwrap();
    assert!(
        matches!(surface.inputs.get("metallic"), Some(Input::Link(_))),
        "{:?}",
        surface.inputs.get("metallic")
    );
    // A custom shader whose node graph is made of closures reads its interface.
    let file = dir.path().join("custom.mtlx");
    std::fs::write(&file, CUSTOM_PLASTIC).unwrap();
    let read = host.import_materials(&file).unwrap();
    assert!(read.warnings.is_empty(), "{:?}", read.warnings);
    let graph = &read.materials[0].1;
    let inside = graph
        .groups
        .get("my_plastic")
        .and_then(|g| g.nodes.values().find(|n| n.kind == "principled_bsdf"))
        .expect("the shader's graph as a group with a principled node");
    for (input, link) in [
        ("base_color", "group_input.base"),
        ("roughness", "group_input.rough"),
    ] {
        assert!(
            matches!(inside.inputs.get(input), Some(Input::Link(l)) if l.to_string() == link),
            "{input}: {:?}",
            inside.inputs.get(input)
        );
    }
    let hair = closure_document(
        r#"  <chiang_hair_bsdf name="strands" type="BSDF" />"#,
        r#"    <input name="bsdf" type="BSDF" nodename="strands" />"#,
    );
    let file = dir.path().join("hair.mtlx");
    std::fs::write(&file, hair).unwrap();
    let message = host.import_materials(&file).unwrap_err().to_string();
    assert!(
        message.contains("strands (chiang_hair_bsdf)") && message.contains("cannot render"),
        "{message}"
    );
}

fn doc_with_varying_metal() -> String {
    closure_document(
        &[
            DIFFUSE,
            GOLD,
            r#"  <noise3d name="noise" type="float" />
  <mix name="mixed" type="BSDF">
    <input name="fg" type="BSDF" nodename="metal" />
    <input name="bg" type="BSDF" nodename="diffuse" />
    <input name="mix" type="float" nodename="noise" />
  </mix>"#,
        ]
        .join("\n"),
        r#"    <input name="bsdf" type="BSDF" nodename="mixed" />"#,
    )
}

/// A `volumematerial` of pbrlib's closures becomes a Principled Volume with the same
/// coefficients (per unit length) in Kiln's kernel.
#[test]
fn a_volume_of_closures_becomes_a_principled_volume_of_the_same_coefficients() {
    let host = bundled_plugins();
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            r#"<anisotropic_vdf name="medium" type="VDF">
    <input name="absorption" type="vector3" value="0.2, 0.5, 1.0" />
    <input name="scattering" type="vector3" value="1.5, 0.8, 0.1" />
    <input name="anisotropy" type="float" value="0.3" />
  </anisotropic_vdf>
  <uniform_edf name="glow" type="EDF">
    <input name="color" type="color3" value="0.4, 0.2, 0.0" />
  </uniform_edf>"#,
            ([0.2, 0.5, 1.0], [1.5, 0.8, 0.1], [0.4, 0.2, 0.0], 0.3),
        ),
        (
            r#"<absorption_vdf name="medium" type="VDF">
    <input name="absorption" type="vector3" value="3, 0.5, 0" />
  </absorption_vdf>"#,
            ([3.0, 0.5, 0.0], [0.0; 3], [0.0; 3], 0.0),
        ),
    ];
    for (i, (nodes, (absorption, scattering, emission, g))) in cases.into_iter().enumerate() {
        let edf = if nodes.contains("glow") {
            r#"<input name="edf" type="EDF" nodename="glow" />"#
        } else {
            ""
        };
        let document = format!(
            r#"<?xml version="1.0"?>
<materialx version="1.39">
  {nodes}
  <volume name="V" type="volumeshader">
    <input name="vdf" type="VDF" nodename="medium" />
    {edf}
  </volume>
  <volumematerial name="M" type="material">
    <input name="volumeshader" type="volumeshader" nodename="V" />
  </volumematerial>
</materialx>
"#
        );
        let file = dir.path().join(format!("{i}.mtlx"));
        std::fs::write(&file, document).unwrap();
        let (_, graph) = host.import_materials(&file).unwrap().materials.remove(0);
        let material = Material::from_graph("volume", graph).unwrap();
        let k = material
            .graph
            .unwrap()
            .traits
            .volume
            .expect("a homogeneous volume");
        for (what, got, want) in [
            ("absorption", k.absorption, absorption),
            ("scattering", k.scattering, scattering),
            ("emission", k.emission, emission),
            ("anisotropy", [k.g; 3], [g; 3]),
        ] {
            assert!(
                (0..3).all(|c| (got[c] - want[c]).abs() < 1e-4),
                "case {i}: {what} is {got:?}, MaterialX says {want:?}"
            );
        }
    }
}

/// A custom shader implemented by a node graph of closures, its roughness through
/// `roughness_anisotropy`.
const CUSTOM_PLASTIC: &str = r#"<?xml version="1.0"?>
<materialx version="1.39">
  <nodedef name="ND_my_plastic" node="my_plastic">
    <input name="base" type="color3" value="0.2, 0.5, 0.8" />
    <input name="rough" type="float" value="0.25" />
    <output name="out" type="surfaceshader" />
  </nodedef>
  <nodegraph name="NG_my_plastic" nodedef="ND_my_plastic">
    <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF">
      <input name="color" type="color3" interfacename="base" />
    </oren_nayar_diffuse_bsdf>
    <roughness_anisotropy name="alpha" type="vector2">
      <input name="roughness" type="float" interfacename="rough" />
    </roughness_anisotropy>
    <dielectric_bsdf name="spec" type="BSDF">
      <input name="roughness" type="vector2" nodename="alpha" />
    </dielectric_bsdf>
    <layer name="plastic" type="BSDF">
      <input name="top" type="BSDF" nodename="spec" />
      <input name="base" type="BSDF" nodename="diffuse" />
    </layer>
    <surface name="surf" type="surfaceshader">
      <input name="bsdf" type="BSDF" nodename="plastic" />
    </surface>
    <output name="out" type="surfaceshader" nodename="surf" />
  </nodegraph>
  <my_plastic name="S" type="surfaceshader">
    <input name="base" type="color3" value="0.9, 0.1, 0.1" />
  </my_plastic>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>
"#;
