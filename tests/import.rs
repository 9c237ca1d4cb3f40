//! Importing through the bundled plugins: the Khronos glTF-Validator corpus (no crash, no
//! escaped panic, no hang; every file the validator finds errors in is refused or imported
//! with warnings, every file it finds valid is imported), hostile inputs, exporter
//! round trips, and the host's own OBJ reader and image writers giving what the plugins
//! give (they run the same code, `kiln-formats`).

mod common;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use base64::Engine as _;
use common::resource;
use glam::{Vec2, Vec3, Vec4};
use kiln::plugin::{ExportFilm, ExportLayer, PluginHost, PluginKind};

const CORPUS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/corpus/gltf-validator/test"
);

/// The corpus as stored holds 372 .gltf/.glb files, each with its validator report, 129 of
/// them without errors. Fewer means the corpus is incomplete and the test checks less than
/// it says.
const MIN_CORPUS_FILES: usize = 372;
const MIN_VALID_FILES: usize = 129;

/// Files the validator finds no error in that Kiln refuses, by path below the corpus, each
/// with the reason. Every other valid file must import; a listed file that imports fails
/// the test too, so the list cannot go stale.
/// None at present: the last one, `base/data/buffer/non_relative_uri.gltf` (an unused
/// buffer at an http: URL), imports since unreachable buffers fail only where they are read.
const REFUSED_VALID_FILES: &[(&str, &str)] = &[];

/// A guard against hangs, not a performance assertion (timings belong in the benchmarks):
/// an import of these small files that gives no answer in a minute is stuck.
const HANG_GUARD: Duration = Duration::from_secs(60);

/// The bundled plugins, as `cargo build` left them next to the test executable.
fn host() -> PluginHost {
    let exe = std::env::current_exe().unwrap();
    let mut host = PluginHost::default();
    host.load_dir(exe.parent().unwrap(), true);
    for kind in [
        PluginKind::Importer,
        PluginKind::Exporter,
        PluginKind::Material,
    ] {
        for ext in match kind {
            PluginKind::Importer => ["gltf", "glb", "obj"].as_slice(),
            PluginKind::Exporter => ["png", "exr"].as_slice(),
            PluginKind::Material => ["mtlx"].as_slice(),
        } {
            assert!(
                host.handles(kind, Path::new(&format!("x.{ext}"))),
                "no bundled {kind} for .{ext}; refused: {:?}",
                host.rejected
            );
        }
    }
    host
}

/// The validator's error count for `file`: `issues.numErrors` in the report written beside
/// it.
fn validator_errors(file: &Path) -> Result<u64, String> {
    let path = format!("{}.report.json", file.display());
    let report =
        std::fs::read_to_string(&path).map_err(|e| format!("no validator report {path}: {e}"))?;
    let report: serde_json::Value = serde_json::from_str(&report)
        .map_err(|e| format!("unparsable validator report {path}: {e}"))?;
    report["issues"]["numErrors"]
        .as_u64()
        .ok_or_else(|| format!("validator report {path}: no whole number at issues.numErrors"))
}

/// Runs `work` on a worker thread, giving up after [`HANG_GUARD`]; the error says whether
/// it hung or panicked.
fn bounded<T: Send + 'static>(work: impl FnOnce() -> T + Send + 'static) -> Result<T, String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(work());
    });
    rx.recv_timeout(HANG_GUARD).map_err(|e| match e {
        mpsc::RecvTimeoutError::Timeout => format!("no answer within {HANG_GUARD:?} (hang guard)"),
        mpsc::RecvTimeoutError::Disconnected => "the importing thread panicked".to_owned(),
    })
}

/// Imports `file` with a host of its own on a worker thread: the triangle count and the
/// warnings, or the error message.
fn import_bounded(file: &Path) -> Result<Result<(u64, Vec<String>), String>, String> {
    let file = file.to_owned();
    bounded(move || {
        host()
            .import(&file)
            .map(|i| (i.scene.triangle_count(), i.warnings))
            .map_err(|e| e.to_string())
    })
}

#[test]
fn every_validator_corpus_file_imports_or_fails_cleanly_and_in_bounded_time() {
    let Some(dir) = resource::require(Path::new(CORPUS), "the glTF-Validator corpus") else {
        return;
    };
    let all =
        resource::files_with_extensions(&dir, &["gltf", "glb"]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        all.len() >= MIN_CORPUS_FILES,
        "only {} .gltf/.glb files under {}, expected at least {MIN_CORPUS_FILES}",
        all.len(),
        dir.display()
    );
    let (mut ok, mut warned, mut refused, mut valid) = (0, 0, 0, 0);
    let mut problems = Vec::new();
    let mut slowest = (Duration::ZERO, String::new());
    for file in &all {
        let name = file
            .strip_prefix(&dir)
            .expect("found below the corpus")
            .to_string_lossy()
            .replace('\\', "/");
        let t = Instant::now();
        let result = match import_bounded(file) {
            Ok(result) => result,
            Err(e) => {
                problems.push(format!("{name}: {e}"));
                continue;
            }
        };
        let took = t.elapsed();
        if took > slowest.0 {
            slowest = (took, name.clone());
        }
        let errors = match validator_errors(file) {
            Ok(errors) => errors,
            Err(e) => {
                problems.push(format!("{name}: {e}"));
                continue;
            }
        };
        if errors == 0 {
            valid += 1;
        }
        let listed = REFUSED_VALID_FILES.iter().find(|(f, _)| *f == name);
        match result {
            Ok((_, w)) if w.is_empty() && errors > 0 => problems.push(format!(
                "{name}: the validator finds {errors} errors, the import neither failed nor warned"
            )),
            Ok(_) if listed.is_some() => problems.push(format!(
                "{name}: imports, but REFUSED_VALID_FILES says it is refused; remove it there"
            )),
            Ok((_, w)) if w.is_empty() => ok += 1,
            Ok(_) => warned += 1,
            Err(e) if e.is_empty() => problems.push(format!("{name}: refused without a message")),
            Err(e) if e.contains("panicked") => problems.push(format!("{name}: {e}")),
            Err(e) if errors == 0 && listed.is_none() => problems.push(format!(
                "{name}: the validator finds no errors, but the import was refused: {e}"
            )),
            Err(_) => refused += 1,
        }
    }
    eprintln!(
        "{} files ({valid} valid): {ok} clean, {warned} with warnings, {refused} refused; slowest {:?} ({})",
        all.len(),
        slowest.0,
        slowest.1
    );
    for (listed, _) in REFUSED_VALID_FILES {
        if !all.iter().any(|f| f.ends_with(listed)) {
            problems.push(format!(
                "{listed}: in REFUSED_VALID_FILES but not in the corpus"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "{} problems:\n{}",
        problems.len(),
        problems.join("\n")
    );
    assert!(
        valid >= MIN_VALID_FILES,
        "only {valid} files the validator finds valid, expected at least {MIN_VALID_FILES}"
    );
}

/// A small valid .glb: a quad.
fn quad_glb(dir: &Path) -> PathBuf {
    let path = dir.join("quad.glb");
    kiln::bench::write_glb(&kiln::scene::shapes::quad(), &path).unwrap();
    path
}

/// An import run out of process (`--isolate-importers`, the editor's way) gives what the
/// same import gives in process: the same scene, warnings and images, or the same error;
/// on every third corpus file (valid and broken ones, with embedded and external
/// textures, lights and cameras).
#[test]
fn isolated_imports_equal_imports_in_process() {
    let Some(dir) = resource::require(Path::new(CORPUS), "the glTF-Validator corpus") else {
        return;
    };
    let mut files =
        resource::files_with_extensions(&dir, &["gltf", "glb"]).unwrap_or_else(|e| panic!("{e}"));
    files.sort();
    let in_process = host();
    let mut isolated = host();
    isolated.isolate_importers(kiln::plugin::Isolation {
        exe: assert_cmd::cargo::cargo_bin("kiln"),
        plugin_dirs: Vec::new(),
        timeout: HANG_GUARD,
    });
    let (mut imported, mut refused) = (0, 0);
    for file in files.iter().step_by(3) {
        match (in_process.import(file), isolated.import(file)) {
            (Ok(a), Ok(b)) => {
                assert!(a.scene == b.scene, "{}: the scenes differ", file.display());
                assert_eq!(a.warnings, b.warnings, "{}", file.display());
                assert_eq!(a.images, b.images, "{}", file.display());
                assert_eq!(
                    (a.has_camera, a.has_lights),
                    (b.has_camera, b.has_lights),
                    "{}",
                    file.display()
                );
                imported += 1;
            }
            (Err(a), Err(b)) => {
                assert_eq!(a.to_string(), b.to_string());
                refused += 1;
            }
            (a, b) => panic!(
                "{}: in process {:?}, isolated {:?}",
                file.display(),
                a.map(|i| i.warnings),
                b.map(|i| i.warnings)
            ),
        }
    }
    assert!(
        imported > 40 && refused > 10,
        "{imported} imported, {refused} refused"
    );
}

#[test]
fn hostile_gltf_inputs_are_refused_with_a_message() {
    let host = host();
    let dir = tempfile::tempdir().unwrap();
    let good = quad_glb(dir.path());
    let imported = host.import(&good).unwrap();
    assert_eq!(imported.scene.triangle_count(), 2);

    // Truncated GLB.
    let bytes = std::fs::read(&good).unwrap();
    for cut in [10, 40, bytes.len() / 2, bytes.len() - 3] {
        let p = dir.path().join(format!("cut{cut}.glb"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        match host.import(&p) {
            Err(e) => assert!(!e.to_string().contains("panicked"), "{e}"),
            Ok(i) => assert!(
                !i.warnings.is_empty(),
                "truncated at {cut}: imported silently"
            ),
        }
    }

    let gltf = |name: &str, json: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, json).unwrap();
        p
    };
    // 36 bytes: three positions; then three indices.
    let b64 = |data: &[u8]| base64::engine::general_purpose::STANDARD.encode(data);
    let triangle = |positions: [f32; 9], indices: [u32; 3], count: &str| {
        let mut data: Vec<u8> = bytemuck::cast_slice(&positions).to_vec();
        data.extend(bytemuck::cast_slice(&indices));
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
            "buffers":[{{"byteLength":48,"uri":"data:application/octet-stream;base64,{}"}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":12}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5125,"count":3,"type":"SCALAR"}}]}}"#,
            b64(&data)
        )
    };
    let ok = triangle([0., 0., 0., 1., 0., 0., 0., 1., 0.], [0, 1, 2], "3");
    assert_eq!(
        host.import(&gltf("ok.gltf", &ok))
            .unwrap()
            .scene
            .triangle_count(),
        1
    );
    let cases = [
        (
            "huge count",
            triangle(
                [0., 0., 0., 1., 0., 0., 0., 1., 0.],
                [0, 1, 2],
                "1000000000",
            ),
        ),
        (
            "index out of range",
            triangle([0., 0., 0., 1., 0., 0., 0., 1., 0.], [0, 1, 9], "3"),
        ),
        (
            "NaN position",
            triangle([0., 0., 0., f32::NAN, 0., 0., 0., 1., 0.], [0, 1, 2], "3"),
        ),
    ];
    for (what, json) in cases {
        match import_bounded(&gltf("bad.gltf", &json)).unwrap_or_else(|e| panic!("{what}: {e}")) {
            Err(e) => assert!(!e.contains("panicked"), "{what}: {e}"),
            Ok((triangles, warnings)) => {
                assert_eq!(triangles, 0, "{what}: the bad triangle was kept");
                assert!(!warnings.is_empty(), "{what}: no warning");
            }
        }
    }

    // A texture whose PNG header claims 100000 × 100000 pixels: refused before decoding;
    // the triangle is kept and the import says what happened to the texture.
    let textured = ok.replace(
        r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"#,
        &format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
            "textures":[{{"source":0}}],
            "images":[{{"uri":"data:image/png;base64,{}"}}],"#,
            b64(&common::png_header(100_000, 100_000))
        ),
    );
    assert_ne!(textured, ok, "the material was not spliced in");
    let (triangles, warnings) = import_bounded(&gltf("huge_texture.gltf", &textured))
        .unwrap_or_else(|e| panic!("huge texture: {e}"))
        .unwrap();
    assert_eq!(triangles, 1);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("image") || w.contains("texture")),
        "no warning about the huge image: {warnings:?}"
    );
}

/// A film with every value distinct: radiance up to 3, display values in [0, 1], and
/// albedo, normal and depth AOVs.
fn sample_film(w: u32, h: u32) -> ExportFilm {
    let n = (w * h) as usize;
    let radiance: Vec<f32> = (0..4 * n)
        .map(|i| {
            if i % 4 == 3 {
                1.0
            } else {
                (i as f32 * 0.37).sin().abs() * 3.0
            }
        })
        .collect();
    let display: Vec<f32> = radiance.iter().map(|v| (v / (1.0 + v)).min(1.0)).collect();
    let layer = |name: &str, channels: u32| ExportLayer {
        name: name.into(),
        channels,
        data: (0..n * channels as usize)
            .map(|i| i as f32 * 0.25 - 1.0)
            .collect(),
    };
    ExportFilm {
        width: w,
        height: h,
        radiance,
        display,
        layers: vec![layer("albedo", 3), layer("normal", 3), layer("depth", 1)],
    }
}

#[test]
fn exporters_round_trip_the_film() {
    let host = host();
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (7u32, 5u32);
    let film = sample_film(w, h);
    let (radiance, display) = (&film.radiance, &film.display);
    // EXR: read back with the image crate (the main RGBA layer), bit for bit.
    let exr = dir.path().join("film.exr");
    host.export(&exr, &film, "").unwrap();
    let back = image::open(&exr).unwrap().to_rgba32f();
    assert_eq!((back.width(), back.height()), (w, h));
    for (a, b) in back.as_raw().iter().zip(radiance) {
        assert_eq!(a.to_bits(), b.to_bits(), "EXR changed a value");
    }
    // PNG: the display image, quantized to 8 bits.
    let png = dir.path().join("film.png");
    host.export(&png, &film, "").unwrap();
    let back = image::open(&png).unwrap().to_rgba8();
    for (a, b) in back.as_raw().iter().zip(display) {
        assert_eq!(*a, (b * 255.0).round() as u8);
    }
    // 16-bit PNG on request.
    let png16 = dir.path().join("film16.png");
    host.export(&png16, &film, "bits=16").unwrap();
    assert_eq!(
        image::open(&png16).unwrap().color(),
        image::ColorType::Rgba16
    );
    // An unwritable path is an error naming it, and no file is left behind.
    let e = host
        .export(&dir.path().join("missing/dir/x.png"), &film, "")
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing/dir/x.png"), "{e}");
}

#[test]
fn the_host_writes_the_same_bytes_as_the_exporter_plugins() {
    // Without a plugin for the format the host writes the image itself, through the
    // plugins' own writers: same film and options, same file.
    let host = host();
    let dir = tempfile::tempdir().unwrap();
    let film = sample_film(9, 4);
    for (name, options) in [
        ("film.png", ""),
        ("film16.png", "bits=16"),
        ("film.jpg", "quality=70"),
        ("film.exr", ""),
        ("film_piz.exr", "compression=piz"),
    ] {
        let by_plugin = dir.path().join(format!("plugin_{name}"));
        let by_host = dir.path().join(format!("host_{name}"));
        host.export(&by_plugin, &film, options).unwrap();
        kiln::film::output::write_image(&by_host, &film, options).unwrap();
        let (plugin_bytes, host_bytes) = (
            std::fs::read(&by_plugin).unwrap(),
            std::fs::read(&by_host).unwrap(),
        );
        assert!(
            plugin_bytes == host_bytes,
            "{name} ({options}): the host wrote {} bytes, the plugin {}, not the same",
            host_bytes.len(),
            plugin_bytes.len()
        );
        if name.ends_with(".exr") {
            // The AOV layers are in both (channel names are stored as text).
            let text = String::from_utf8_lossy(&host_bytes);
            for channel in ["albedo.R", "normal.X", "depth.Z"] {
                assert!(text.contains(channel), "{name} lacks {channel}");
            }
        }
    }
}

/// The mesh of `obj` as a scene file's `Obj(...)` mesh loads it, through the host.
fn host_obj_mesh(obj: &Path) -> kiln::scene::Mesh {
    let scene = obj.with_extension("kiln");
    std::fs::write(
        &scene,
        format!(
            r#"(
                version: 1,
                camera: (position: (0, 0, 5), look_at: (0, 0, 0), projection: Perspective(fov_y: 40)),
                materials: {{ "grey": (base_color: (0.5, 0.5, 0.5)) }},
                meshes: {{ "it": Obj("{}") }},
                instances: [(mesh: "it", material: "grey")],
            )"#,
            obj.file_name().unwrap().to_str().unwrap()
        ),
    )
    .unwrap();
    let mut scene = kiln::scene::load_scene(&scene).unwrap();
    assert_eq!(scene.meshes.len(), 1);
    scene.meshes.remove(0)
}

#[test]
fn the_host_reads_an_obj_mesh_as_the_importer_plugin_does() {
    let host = host();
    let dir = tempfile::tempdir().unwrap();
    let files = [
        // As Kiln saves meshes: aligned corners, an unused vertex, a second UV set and
        // colour alpha, read in file order.
        (
            "aligned.obj",
            "# saved (written by Kiln; vertices are aligned)\n\
             v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 9 9 9 1 1 1\n\
             #kiln alpha 0.5\n#kiln alpha 1\n#kiln alpha 0.25\n#kiln alpha 0\n\
             vt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n\
             #kiln uv1 0.1 0.2\n#kiln uv1 0.3 0.4\n#kiln uv1 0.5 0.6\n#kiln uv1 0.7 0.8\n\
             vn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 1 0\n\
             f 3/3/3 1/1/1 2/2/2\n",
        ),
        // Any other file: a quad whose corners index positions and texture coordinates
        // differently, re-indexed by first use and split into two triangles.
        (
            "quad.obj",
            "o quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\n\
             vn 0 0 1\nf 1/2/1 2/1/1 3/2/1 4/1/1\n",
        ),
    ];
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let by_host = host_obj_mesh(&path);
        let imported = host.import(&path).unwrap();
        assert_eq!(imported.scene.meshes.len(), 1, "{name}");
        let by_plugin = &imported.scene.meshes[0];
        assert_eq!(
            (
                &by_host.positions,
                &by_host.normals,
                &by_host.uvs,
                &by_host.uvs1,
                &by_host.colors,
                &by_host.indices
            ),
            (
                &by_plugin.positions,
                &by_plugin.normals,
                &by_plugin.uvs,
                &by_plugin.uvs1,
                &by_plugin.colors,
                &by_plugin.indices
            ),
            "{name}: the host and the plugin read different meshes"
        );
        assert!(
            !by_host.normals.is_empty() && !by_host.uvs.is_empty(),
            "{name}"
        );
    }
    // The aligned file kept its order, its unused vertex and its extensions.
    let aligned = host_obj_mesh(&dir.path().join("aligned.obj"));
    assert_eq!(aligned.positions.len(), 4);
    assert_eq!(aligned.indices, vec![[2, 0, 1]]);
    assert_eq!(aligned.uvs1[3], Vec2::new(0.7, 0.8));
    assert_eq!(aligned.colors[2], Vec4::new(0.0, 0.0, 1.0, 0.25));
}

#[test]
fn kiln_renders_and_converts_imported_files() {
    let dir = tempfile::tempdir().unwrap();
    let glb = quad_glb(dir.path());
    let kiln = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_kiln"))
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    // Rendered directly, framed by the default camera under the default sky.
    let png = dir.path().join("quad.png");
    let (code, err) = kiln(&[
        "render",
        glb.to_str().unwrap(),
        "--size",
        "16x16",
        "--spp",
        "2",
        "-q",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(
        img.pixels().any(|p| p.0 != img.get_pixel(0, 0).0),
        "a uniform image: the quad is not in view"
    );
    // Converted to a scene file, which renders too, with AOV layers in the EXR.
    let scene = dir.path().join("quad.kiln");
    let (code, err) = kiln(&[
        "import",
        glb.to_str().unwrap(),
        "-o",
        scene.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(dir.path().join("quad.assets/mesh_0.obj").exists());
    let exr = dir.path().join("quad.exr");
    let (code, err) = kiln(&[
        "render",
        scene.to_str().unwrap(),
        "--size",
        "16x16",
        "--spp",
        "2",
        "-q",
        "-o",
        exr.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let header = std::fs::read(&exr).unwrap();
    let text = String::from_utf8_lossy(&header[..header.len().min(4096)]).into_owned();
    assert!(
        text.contains("albedo.R") && text.contains("depth.Z"),
        "no AOV channels in the EXR header"
    );
    // A broken file is one clear error.
    let broken = dir.path().join("broken.glb");
    std::fs::write(&broken, b"glTF\x02\x00\x00\x00").unwrap();
    let (code, err) = kiln(&[
        "render",
        broken.to_str().unwrap(),
        "-q",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("broken.glb") && !err.contains("panicked"),
        "{err}"
    );
}

#[test]
fn obj_files_import_with_their_materials() {
    let host = host();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("box.mtl"),
        "newmtl red\nKd 0.8 0.1 0.1\nNs 100\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("box.obj"),
        "mtllib box.mtl\no a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\nf 1 2 3\no b\nusemtl lamp\nf 2 4 3\n",
    )
    .unwrap();
    let imported = host.import(&dir.path().join("box.obj")).unwrap();
    assert_eq!(imported.scene.triangle_count(), 2);
    assert_eq!(imported.scene.instances.len(), 2);
    let lamp = imported
        .scene
        .materials
        .iter()
        .find(|m| m.name == "lamp")
        .expect("the lamp material");
    assert_eq!(
        lamp.emission(),
        Vec3::splat(5.0),
        "a constant emitter is a light"
    );
}
