//! The promises of `kiln render`'s flags, `$KILN_PLUGIN_PATH` and `kiln bench` (README,
//! "Using it"), each checked by its effect on what the command writes: a flag that is
//! parsed and then ignored fails here. Renders are the bundled Cornell box at 16×16 or
//! 32×32 written as EXR, so the linear radiance and the AOV layers can be read back.
//! Tolerances come from measurements on lavapipe, stated where they are used.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;

use common::exr::{Exr, read_exr};

fn kiln() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kiln"))
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `kiln render ARGS -q -o OUT`, which must succeed; returns its stderr.
fn render(out: &Path, args: &[&str]) -> String {
    let result = kiln()
        .arg("render")
        .args(args)
        .args(["-q", "-o"])
        .arg(out)
        .output()
        .expect("kiln runs");
    let err = stderr(&result);
    assert!(
        result.status.success(),
        "kiln render {args:?} failed:\n{err}"
    );
    err
}

fn mean_of(v: [f64; 3]) -> f64 {
    v.iter().sum::<f64>() / 3.0
}

/// Root-mean-square difference of the radiance of two images over `pixels`.
fn rmse_over(a: &Exr, b: &Exr, pixels: &[usize]) -> f64 {
    let sum: f64 = pixels
        .iter()
        .flat_map(|&p| a.rgb(p).into_iter().zip(b.rgb(p)))
        .map(|(x, y)| ((x - y) as f64).powi(2))
        .sum();
    (sum / (3 * pixels.len()) as f64).sqrt()
}

/// Renders the Cornell box at `size` and `spp` with `extra` flags into `dir/name.exr`.
fn cornell(dir: &Path, name: &str, size: &str, spp: &str, extra: &[&str]) -> Exr {
    let out = dir.join(format!("{name}.exr"));
    let mut args = vec!["--size", size, "--spp", spp];
    args.extend(extra);
    render(&out, &args);
    read_exr(&out)
}

#[test]
fn environment_flag_sets_the_sky_radiance_per_channel() {
    let dir = tempfile::tempdir().unwrap();
    let env = |rgb: &str| cornell(dir.path(), rgb, "32x32", "64", &["--environment", rgb]);
    let (black, white, blue) = (env("0,0,0"), env("1,1,1"), env("0,0,2"));
    let [b, w, bl] = [&black, &white, &blue].map(Exr::mean);
    // The box's open front lets the sky in: measured, a white sky of 1 adds 0.31, 0.29
    // and 0.26 to the mean red, green and blue of the closed box's 0.20, 0.13, 0.04.
    for c in 0..3 {
        assert!(
            w[c] - b[c] > 0.1,
            "a white sky barely lights channel {c}: {b:?} → {w:?}"
        );
    }
    // A blue sky of 2 adds blue only, twice what a white sky of 1 does (radiance is
    // linear in the sky's; the paths differ only by the sky's share of light
    // sampling, measured < 1 % apart). Red and green rise only by the little blue the
    // walls reflect as red and green (measured 2 % of the blue rise).
    let blue_rise = bl[2] - b[2];
    let white_blue_rise = w[2] - b[2];
    assert!(
        (blue_rise / (2.0 * white_blue_rise) - 1.0).abs() < 0.1,
        "--environment 0,0,2 raised blue by {blue_rise}, 1,1,1 by {white_blue_rise}"
    );
    for c in 0..2 {
        assert!(
            (bl[c] - b[c]).abs() < 0.1 * blue_rise,
            "a blue sky changed channel {c} by {} (blue by {blue_rise})",
            bl[c] - b[c]
        );
    }
}

#[test]
fn seed_flag_same_seed_same_bits_other_seed_other_noise() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(format!("{name}.exr"));
        let mut args = vec!["--size", "16x16", "--spp", "8"];
        args.extend(extra);
        render(&out, &args);
        (std::fs::read(&out).unwrap(), read_exr(&out))
    };
    let (default_bytes, default) = run("default", &[]);
    let (zero_bytes, _) = run("zero", &["--seed", "0"]);
    let (_, seven) = run("seven", &["--seed", "7"]);
    // The documented default is 0, and the same seed gives the same file, bit for bit.
    assert!(
        default_bytes == zero_bytes,
        "--seed 0 differs from the default seed"
    );
    let differing = (0..256).filter(|&p| default.rgb(p) != seven.rgb(p)).count();
    // At 8 spp nearly every pixel's noise differs; pixels that see only the light (its
    // emission is constant) may agree.
    assert!(
        differing > 200,
        "--seed 7 changed only {differing} of 256 pixels"
    );
    // Same image, other noise: the means agree (measured within 9 % at 16×16, 8 spp,
    // where a few samples on the light move the mean).
    let (a, b) = (mean_of(default.mean()), mean_of(seven.mean()));
    assert!((a / b - 1.0).abs() < 0.25, "means {a} and {b}");
}

#[test]
fn max_bounces_flag_limits_the_light_that_reaches_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let bounces = |n: &str| cornell(dir.path(), n, "32x32", "64", &["--max-bounces", n]);
    let (zero, one, eight) = (bounces("0"), bounces("1"), bounces("8"));
    let pixels = 32 * 32;
    // The same seed traces the same paths: a higher limit only adds light the lower one
    // cut off, in every pixel (Kahan sums of the same terms first, then more).
    for p in 0..pixels {
        for (lo, hi) in one.rgb(p).into_iter().zip(eight.rgb(p)) {
            assert!(
                hi >= lo * (1.0 - 1e-6),
                "pixel {p}: 8 bounces {hi} < 1 bounce {lo}"
            );
        }
    }
    // Without bounces the camera sees only the light; with one, direct light; with
    // eight, the interreflections too (measured: mean 0.098, 0.147, 0.198).
    let lit = (0..pixels)
        .filter(|&p| zero.rgb(p).iter().any(|&v| v > 0.0))
        .count();
    let on_light = pixels - one.pixels_off_the_light().len();
    assert_eq!(
        lit, on_light,
        "with no bounce, exactly the pixels that see the light are lit"
    );
    assert!(lit > 0 && lit < pixels / 20, "{lit} pixels see the light");
    let (m0, m1, m8) = (
        mean_of(zero.mean()),
        mean_of(one.mean()),
        mean_of(eight.mean()),
    );
    assert!(m1 > 1.2 * m0, "direct light adds little: {m0} → {m1}");
    assert!(m8 > 1.2 * m1, "indirect light missing: {m1} → {m8}");
}

#[test]
fn no_light_sampling_is_noisier_with_the_same_mean() {
    let dir = tempfile::tempdir().unwrap();
    let run = |seed: &str, nee: bool| {
        let mut extra = vec!["--seed", seed];
        if !nee {
            extra.push("--no-light-sampling");
        }
        let name = format!("{seed}-{nee}");
        cornell(dir.path(), &name, "32x32", "64", &extra)
    };
    let (nee_1, nee_2) = (run("1", true), run("2", true));
    let (bsdf_1, bsdf_2) = (run("1", false), run("2", false));
    // Pixels that see the light are as noisy either way (sub-pixel coverage of a bright
    // emitter); the rest is lit by the small light, which next-event estimation finds
    // every time and BSDF sampling rarely.
    let off: Vec<usize> = [&nee_1, &nee_2, &bsdf_1, &bsdf_2]
        .iter()
        .map(|e| e.pixels_off_the_light())
        .reduce(|a, b| a.into_iter().filter(|p| b.contains(p)).collect())
        .unwrap();
    assert!(off.len() > 900, "only {} pixels off the light", off.len());
    // Noise as the difference of two seeds: measured 0.0117 with light sampling, 0.120
    // to 0.134 without (three seed pairs).
    let nee_noise = rmse_over(&nee_1, &nee_2, &off);
    let bsdf_noise = rmse_over(&bsdf_1, &bsdf_2, &off);
    assert!(
        bsdf_noise > 4.0 * nee_noise,
        "BSDF sampling alone should be far noisier: {bsdf_noise} vs {nee_noise} with light sampling"
    );
    // Both are unbiased. Measured over six seeds: light sampling 0.0571 to 0.0576, BSDF
    // sampling 0.0542 to 0.0634 (σ ≈ 5.7 % per image, 4 % for the mean of two); 15 % is
    // 3.7 σ.
    let nee = (mean_of(nee_1.mean_over(&off)) + mean_of(nee_2.mean_over(&off))) / 2.0;
    let bsdf = (mean_of(bsdf_1.mean_over(&off)) + mean_of(bsdf_2.mean_over(&off))) / 2.0;
    assert!(
        (bsdf / nee - 1.0).abs() < 0.15,
        "means differ: {bsdf} without light sampling, {nee} with"
    );
}

#[test]
fn backend_flag_picks_the_api_and_an_unknown_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let vulkan_out = dir.path().join("vulkan.exr");
    let err = render(
        &vulkan_out,
        &["--backend", "vulkan", "--size", "16x16", "--spp", "4"],
    );
    assert!(err.contains("(Vulkan,"), "not run on Vulkan:\n{err}");
    let vulkan = read_exr(&vulkan_out);

    // GL needs Mesa's EGL (llvmpipe) besides its Vulkan driver; where it is missing the
    // refusal must be the clean one.
    let gl_out = dir.path().join("gl.exr");
    let gl = kiln()
        .args([
            "render",
            "--backend",
            "gl",
            "--size",
            "16x16",
            "--spp",
            "4",
            "-q",
            "-o",
        ])
        .arg(&gl_out)
        .output()
        .unwrap();
    let err = stderr(&gl);
    if gl.status.success() {
        assert!(err.contains("(Gl,"), "not run on GL:\n{err}");
        // The same kernel and seed: measured 4e-8 RMS apart (float rounding only).
        let gl = read_exr(&gl_out);
        for p in 0..256 {
            for (a, b) in vulkan.rgb(p).into_iter().zip(gl.rgb(p)) {
                assert!(
                    (a - b).abs() <= 1e-4 * a.abs().max(1.0),
                    "pixel {p}: Vulkan {a}, GL {b}"
                );
            }
        }
    } else {
        assert_eq!(gl.status.code(), Some(1), "{err}");
        assert!(
            err.contains("no usable GPU adapter for backend Gl"),
            "{err}"
        );
    }

    let unknown = kiln()
        .args(["render", "--backend", "directx", "-o"])
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    let err = stderr(&unknown);
    assert_eq!(unknown.status.code(), Some(2), "{err}");
    assert!(
        err.contains("'directx'") && err.contains("vulkan, gl"),
        "the refusal should name the value and the choices:\n{err}"
    );
    assert!(!err.contains("panicked"), "{err}");

    // An API this build cannot use is a clear error, not a fallback to another one.
    #[cfg(target_os = "linux")]
    {
        let metal = kiln()
            .args(["render", "--backend", "metal", "-o"])
            .arg(dir.path().join("x.png"))
            .output()
            .unwrap();
        let err = stderr(&metal);
        assert_eq!(metal.status.code(), Some(1), "{err}");
        assert!(
            err.contains("no usable GPU adapter for backend Metal"),
            "{err}"
        );
        assert!(!dir.path().join("x.png").exists());
    }
}

#[test]
fn exr_normal_layer_holds_unit_normals_facing_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let e = cornell(dir.path(), "layers", "32x32", "4", &[]);
    assert_eq!((e.width, e.height), (32, 32));
    let normal = |p: usize| ["normal.X", "normal.Y", "normal.Z"].map(|c| e.channel(c)[p]);
    let depth = e.channel("depth.Z");
    // Unit normals where a camera sample met a surface, zero where none did (depth 0).
    let mut hits = 0;
    for (p, &d) in depth.iter().enumerate() {
        let n = normal(p);
        let length = n.iter().map(|v| v * v).sum::<f32>().sqrt();
        if d > 0.0 {
            hits += 1;
            assert!((length - 1.0).abs() < 1e-4, "pixel {p}: |{n:?}| = {length}");
        } else {
            assert_eq!(n, [0.0; 3], "pixel {p} met nothing");
        }
    }
    // The box fills the view; only rays through the top and bottom rows' outer halves
    // pass just over the ceiling's and under the floor's front edges.
    assert!(hits >= 32 * 30, "only {hits} pixels met a surface");
    // Two-sided walls face the camera: floor up, ceiling down, the red wall (left)
    // toward −x, the green one (right) toward +x. Regions a pixel or more inside the
    // walls' edges in the 32×32 view; the walls are flat, so every sample agrees.
    let region = |xs: std::ops::Range<usize>,
                  ys: std::ops::Range<usize>,
                  expected: [f32; 3],
                  tolerance: f32| {
        for y in ys.clone() {
            for x in xs.clone() {
                let n = normal(y * 32 + x);
                let off = n
                    .iter()
                    .zip(expected)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f32::max);
                assert!(
                    off < tolerance,
                    "pixel ({x}, {y}): normal {n:?}, expected {expected:?}"
                );
            }
        }
    };
    // Floor (y = 0; left of the short block), ceiling (y = 548.8) and green wall
    // (x = 0) are axis-aligned.
    region(4..13, 29..31, [0.0, 1.0, 0.0], 1e-4);
    region(8..24, 1..3, [0.0, -1.0, 0.0], 1e-4);
    region(28..32, 10..20, [1.0, 0.0, 0.0], 1e-4);
    // The measured red wall leans: x runs from 549.6 to 556 over 559.2 mm of depth and
    // 548.8 of height, tilting its normal by about 0.006 in y and z.
    region(0..4, 10..20, [-1.0, 0.0, 0.0], 0.01);
}

/// A plugin library no standard place holds: the panicking test importer is named
/// `libpanicking_test_plugin`, which the build folder's scan skips (not `libkiln_*`).
fn test_plugin() -> PathBuf {
    let exe = Path::new(env!("CARGO_BIN_EXE_kiln"));
    let lib = exe
        .with_file_name("deps")
        .join("libpanicking_test_plugin.so");
    assert!(lib.exists(), "{} was not built", lib.display());
    lib
}

fn list_plugins(env_path: Option<&std::ffi::OsStr>, plugin_dir: Option<&Path>) -> String {
    let mut cmd = kiln();
    cmd.env_remove("KILN_PLUGIN_PATH");
    if let Some(p) = env_path {
        cmd.env("KILN_PLUGIN_PATH", p);
    }
    if let Some(d) = plugin_dir {
        cmd.arg("--plugin-dir").arg(d);
    }
    let out = cmd.arg("plugins").output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    String::from_utf8(out.stdout).unwrap()
}

#[cfg(target_os = "linux")]
#[test]
fn kiln_plugin_path_adds_folders_searched_before_the_executables() {
    let empty = tempfile::tempdir().unwrap();
    let extra = tempfile::tempdir().unwrap();
    let lib = extra.path().join("libpanicking_test_plugin.so");
    std::fs::copy(test_plugin(), &lib).unwrap();
    // A bundled plugin too: the copy in $KILN_PLUGIN_PATH wins over the build folder's.
    let exe_dir = Path::new(env!("CARGO_BIN_EXE_kiln")).parent().unwrap();
    let exr = extra.path().join("libkiln_exr.so");
    // `cargo build` leaves it next to the executable; `cargo test` only in deps/.
    let bundled_exr = [
        exe_dir.join("libkiln_exr.so"),
        exe_dir.join("deps/libkiln_exr.so"),
    ]
    .into_iter()
    .find(|p| p.exists())
    .expect("libkiln_exr.so was not built");
    std::fs::copy(bundled_exr, &exr).unwrap();

    let without = list_plugins(None, None);
    assert!(!without.contains("panicking test importer"), "{without}");
    assert!(
        without.contains(&format!("{}", exe_dir.display())),
        "the bundled plugins are found next to the executable:\n{without}"
    );

    // A list of folders, the first of which holds nothing.
    let path = std::env::join_paths([empty.path(), extra.path()]).unwrap();
    let with = list_plugins(Some(&path), None);
    let line = |name: &str| {
        with.lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_else(|| panic!("no {name} in:\n{with}"))
            .to_owned()
    };
    assert!(
        line("panicking test importer")
            .ends_with(&format!("(importer; .panic): {}", lib.display())),
        "{with}"
    );
    assert!(
        line("OpenEXR").ends_with(&format!(": {}", exr.display())),
        "{with}"
    );
    assert_eq!(
        with.lines().filter(|l| l.starts_with("OpenEXR")).count(),
        1,
        "the first plugin of a name wins:\n{with}"
    );

    // --plugin-dir is searched before $KILN_PLUGIN_PATH.
    let first = tempfile::tempdir().unwrap();
    let first_exr = first.path().join("libkiln_exr.so");
    std::fs::copy(&exr, &first_exr).unwrap();
    let both = list_plugins(Some(&path), Some(first.path()));
    let exr_line = both.lines().find(|l| l.starts_with("OpenEXR")).unwrap();
    assert!(
        exr_line.ends_with(&format!(": {}", first_exr.display())),
        "{both}"
    );
}

/// One row of the Markdown table: its cells, trimmed.
fn cells(row: &str) -> Vec<&str> {
    row.trim()
        .trim_start_matches('|')
        .trim_end_matches('|')
        .split('|')
        .map(str::trim)
        .collect()
}

fn number(cell: &str, unit: &str) -> f64 {
    cell.strip_suffix(unit)
        .unwrap_or_else(|| panic!("\"{cell}\" lacks the unit \"{unit}\""))
        .trim()
        .parse()
        .unwrap_or_else(|e| panic!("\"{cell}\": {e}"))
}

#[test]
fn bench_prints_a_markdown_table_of_its_measurements() {
    let out = kiln()
        .args([
            "bench",
            "--scene",
            "sphere",
            "--triangles",
            "2000",
            "--seconds",
            "0.2",
            "--size",
            "16",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert!(
        lines.next().unwrap().starts_with("Adapter: ") && text.contains("16x16 px"),
        "{text}"
    );
    let header = text
        .lines()
        .find(|l| l.starts_with("| scene |"))
        .unwrap_or_else(|| panic!("no table header:\n{text}"));
    let columns = cells(header);
    assert_eq!(
        columns,
        [
            "scene",
            "kernel",
            "triangles",
            "BVH build",
            "kernel build (naga + pipeline + volume bake)",
            "volume bake",
            "first dispatch",
            "Msamples/s",
            "Mrays/s"
        ]
    );
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("| ") && *l != header)
        .map(cells)
        .collect();
    // --scene keeps the displaced sphere alone, measured with each kernel (its material
    // is a graph, so the interpreting kernel too).
    assert_eq!(rows.len(), 3, "{text}");
    let mut triangles = 0;
    for (row, kernel) in rows
        .iter()
        .zip(["specialised", "everything", "interpreted"])
    {
        assert_eq!(row.len(), columns.len(), "{row:?}");
        assert_eq!(row[0], "displaced sphere (2000 tris)");
        assert_eq!(row[1], kernel);
        triangles = row[2].parse::<u64>().expect("a triangle count");
        // A generated sphere near the requested size, on a floor and under a light.
        assert!((2000..2200).contains(&triangles), "{row:?}");
        for (cell, unit) in [(row[3], "ms"), (row[4], "ms"), (row[6], "ms")] {
            assert!(number(cell, unit) >= 0.0, "{row:?}");
        }
        assert_eq!(row[5], "–", "the sphere has no volume to bake");
        // Work was done and counted (no timing is judged): a sample traces at least
        // its camera ray.
        let (samples, rays) = (number(row[7], ""), number(row[8], ""));
        assert!(samples > 0.0 && rays >= samples, "{row:?}");
    }
    let import = text
        .lines()
        .find(|l| l.starts_with("glTF import ("))
        .unwrap_or_else(|| panic!("no import line:\n{text}"));
    // The import reads the sphere the table rendered, less the floor and light quads.
    assert!(
        import.starts_with(&format!("glTF import ({} triangles,", triangles - 4)),
        "{import}"
    );

    let none = kiln()
        .args(["bench", "--scene", "no such scene", "--triangles", "100"])
        .output()
        .unwrap();
    assert_eq!(none.status.code(), Some(1));
    assert!(stderr(&none).contains("no benchmark scene matches"));
}

#[test]
fn bench_convergence_falls_at_the_monte_carlo_rate() {
    let out = kiln()
        .args([
            "bench",
            "--convergence",
            "--scene",
            "sphere",
            "--triangles",
            "2000",
            "--size",
            "16",
            "--reference-spp",
            "512",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let header = text
        .lines()
        .find(|l| l.starts_with("| scene |"))
        .unwrap_or_else(|| panic!("no table header:\n{text}"));
    assert_eq!(
        cells(header),
        [
            "scene",
            "sampler",
            "spp",
            "seconds",
            "RMSE",
            "RMSE × √seconds"
        ]
    );
    let rows = |sampler: &str| -> Vec<(u32, f64)> {
        text.lines()
            .filter(|l| l.starts_with("| displaced"))
            .map(cells)
            .filter(|r| r[1] == sampler)
            .map(|r| (r[2].parse().unwrap(), number(r[4], "")))
            .collect()
    };
    let slope = |sampler: &str| -> f64 {
        let line = text
            .lines()
            .find(|l| l.contains(&format!("{sampler}: RMSE ∝ spp^")))
            .unwrap_or_else(|| panic!("no fitted rate for {sampler}:\n{text}"));
        line.split("spp^")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{line}"))
    };
    for sampler in ["independent", "sobol"] {
        let rows = rows(sampler);
        // Doubling from 1 to an eighth of the reference's samples.
        let spp: Vec<u32> = rows.iter().map(|r| r.0).collect();
        assert_eq!(spp, [1, 2, 4, 8, 16, 32, 64], "{text}");
        // 64 times the samples: 8 times less error at the Monte Carlo rate; at least 4
        // (the estimate of each RMSE has its own noise).
        assert!(rows[0].1 > 4.0 * rows[6].1 && rows[6].1 > 0.0, "{text}");
    }
    let independent = slope("independent");
    assert!((-0.7..=-0.35).contains(&independent), "{text}");
    // Stratified samples have less error at equal samples: measured 0.58 and 0.57 times
    // independent's at 32 and 64 spp (each RMSE known to about 5% over 256 pixels).
    let (sobol, independent) = (rows("sobol"), rows("independent"));
    for i in [5, 6] {
        assert!(sobol[i].1 < 0.85 * independent[i].1, "{text}");
    }
    assert!(
        text.contains("RMSE of sobol / independent at equal spp: 1: "),
        "{text}"
    );
}

#[test]
fn noise_threshold_flag_stops_converged_pixels_and_writes_the_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("adaptive.exr");
    let err = render(
        &out,
        &["--size", "24x24", "--spp", "96", "--noise-threshold", "0.3"],
    );
    assert!(err.contains("of pixels converged"), "{err}");
    let e = read_exr(&out);
    let samples = e.channel("samples.Y");
    let noise = e.channel("noise.Y");
    // Converged pixels stopped at a check (16, 32, …), short of the 96 asked for, with
    // their estimate below the threshold.
    let stopped: Vec<usize> = (0..samples.len()).filter(|&p| samples[p] < 96.0).collect();
    assert!(stopped.len() > samples.len() / 2, "{samples:?}");
    for &p in &stopped {
        assert!(
            samples[p] % 16.0 == 0.0,
            "pixel {p}: {} samples",
            samples[p]
        );
        assert!(noise[p] < 0.3, "pixel {p}: noise {}", noise[p]);
    }
    for bad in ["-0.1", "nan", "inf", "x"] {
        let result = kiln()
            .args(["render", "--noise-threshold", bad, "-q", "-o"])
            .arg(dir.path().join("bad.png"))
            .output()
            .unwrap();
        let err = stderr(&result);
        assert!(
            !result.status.success(),
            "--noise-threshold {bad} was taken"
        );
        assert!(err.contains("--noise-threshold"), "{err}");
    }
}

#[test]
fn denoise_flag_writes_the_denoised_image_and_keeps_the_noisy_one() {
    let dir = tempfile::tempdir().unwrap();
    let e = cornell(
        dir.path(),
        "denoised",
        "24x24",
        "8",
        &["--denoise", "atrous"],
    );
    let noisy = e.channel("noisy.R");
    assert_eq!(noisy.len(), 24 * 24);
    // The image differs from the noisy layer (it was filtered), with the same mean
    // within 3 % (the energy test in tests/denoise.rs is tighter).
    let red: Vec<f32> = (0..24 * 24).map(|p| e.rgb(p)[0]).collect();
    assert!(red.iter().zip(noisy).any(|(a, b)| a != b));
    let (a, b) = (
        red.iter().sum::<f32>() / red.len() as f32,
        noisy.iter().sum::<f32>() / noisy.len() as f32,
    );
    assert!((a / b - 1.0).abs() < 0.03, "means {a} and {b}");
    let result = kiln()
        .args(["render", "--denoise", "magic", "-q", "-o"])
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    assert!(!result.status.success());
    assert!(stderr(&result).contains("atrous"), "{}", stderr(&result));
}

/// A build without Open Image Denoise refuses `--denoise oidn` before it renders (no
/// adapter is even opened), saying how to get it.
#[cfg(not(feature = "oidn"))]
#[test]
fn denoise_oidn_without_the_library_is_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let result = kiln()
        .args(["render", "--denoise", "oidn", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = stderr(&result);
    assert!(!result.status.success());
    assert!(err.contains("--features oidn"), "{err}");
    assert!(!err.contains("adapter:"), "it rendered first:\n{err}");
    assert!(!out.exists());
}

#[test]
fn quality_presets_are_described_in_the_help_and_flags_beside_them_win() {
    let help = kiln().args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for q in kiln::scene::Quality::ALL {
        assert!(
            help.contains(&q.describe()),
            "--help lacks {}:\n{help}",
            q.key()
        );
    }
    let dir = tempfile::tempdir().unwrap();
    // Draft denoises (the noisy layer is there) at its 16 spp, unless --spp says otherwise.
    let draft = cornell(dir.path(), "draft", "16x16", "4", &["--quality", "draft"]);
    assert!(draft.channel("samples.Y").iter().all(|&n| n == 4.0));
    assert_eq!(draft.channel("noisy.R").len(), 16 * 16);
    let out = dir.path().join("final.exr");
    render(
        &out,
        &[
            "--size",
            "16x16",
            "--quality",
            "final",
            "--denoise",
            "atrous",
            "--spp",
            "16",
        ],
    );
    let final_ = read_exr(&out);
    assert_eq!(final_.channel("noisy.R").len(), 16 * 16);
}

/// `kiln ARGS` (which must fail); its stderr.
fn fails(args: &[&str]) -> String {
    let out = kiln().args(args).output().expect("kiln runs");
    assert!(!out.status.success(), "kiln {args:?} succeeded");
    stderr(&out)
}

/// A group used four times inside a group used four times …, `depth` groups deep: 4^(depth
/// − 1) noise nodes in a small file.
fn nested_groups(depth: usize) -> String {
    let groups: Vec<String> = (0..depth)
        .map(|d| {
            let nodes = if d + 1 == depth {
                r#""n": (type: "noise_texture")"#.to_owned()
            } else {
                (0..4)
                    .map(|i| format!(r#""c{i}": (type: "group", params: {{ "group": "g{}" }})"#, d + 1))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let out = if d + 1 == depth { "n.color" } else { "c0.out" };
            format!(
                r#""g{d}": (outputs: [(name: "out", type: color)], nodes: {{ {nodes} }}, links: {{ "out": "{out}" }})"#
            )
        })
        .collect();
    format!(
        r#"(version: 1, name: "nested", groups: {{ {} }}, nodes: {{
            "g": (type: "group", params: {{ "group": "g0" }}),
            "surface": (type: "principled_bsdf", inputs: {{ "base_color": "g.out" }}),
            "out": (type: "material_output", inputs: {{ "surface": "surface.bsdf" }}),
        }})"#,
        groups.join(", ")
    )
}

/// Each resource limit is a default a flag moves: lowered, it refuses what the default
/// takes, naming the flag; raised, it takes what the default refuses.
#[test]
fn resource_limit_flags_lower_and_raise_the_limits() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();

    // Graph nodes and group depth: 4^5 noise nodes in 6 nested groups, about 1 400 nodes.
    let kmat = dir.join("nested.kmat");
    std::fs::write(&kmat, nested_groups(6)).unwrap();
    let kmat = kmat.to_str().unwrap();
    let ok = kiln().args(["material", "check", kmat]).output().unwrap();
    assert!(ok.status.success(), "{}", stderr(&ok));
    let e = fails(&["material", "check", kmat, "--max-graph-nodes", "500"]);
    assert!(
        e.contains("more than 500 nodes") && e.contains("--max-graph-nodes"),
        "{e}"
    );
    let e = fails(&["material", "check", kmat, "--max-group-depth", "3"]);
    assert!(
        e.contains("deeper than 3") && e.contains("--max-group-depth"),
        "{e}"
    );
    // 4^7 noise nodes (about 38 000 with the groups): over the default, under a raised one.
    let big = dir.join("big.kmat");
    std::fs::write(&big, nested_groups(8)).unwrap();
    let big = big.to_str().unwrap();
    let e = fails(&["material", "check", big]);
    assert!(e.contains("more than 10000 nodes"), "{e}");
    let ok = kiln()
        .args(["material", "check", big, "--max-graph-nodes", "50000"])
        .output()
        .unwrap();
    assert!(ok.status.success(), "{}", stderr(&ok));

    // Texture size: a scene whose material reads a 16 × 16 image.
    image::RgbaImage::from_pixel(16, 16, image::Rgba([200, 100, 50, 255]))
        .save(dir.join("tex.png"))
        .unwrap();
    let scene = dir.join("textured.kiln");
    std::fs::write(
        &scene,
        r#"(version: 1, camera: (position: (0, 0, 3), look_at: (0, 0, 0), projection: Perspective(fov_y: 40)),
            materials: { "m": (graph: (nodes: {
                "image": (type: "image_texture", params: { "file": "tex.png" }),
                "surface": (type: "principled_bsdf", inputs: { "base_color": "image.color" }),
                "out": (type: "material_output", inputs: { "surface": "surface.bsdf" }),
            })) },
            meshes: { "quad": Quad },
            instances: [(mesh: "quad", material: "m")])"#,
    )
    .unwrap();
    let out = dir.join("out.png");
    let (scene, out) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let e = fails(&["render", scene, "-o", out, "--max-texture-size", "8"]);
    assert!(
        e.contains("tex.png") && e.contains("--max-texture-size"),
        "{e}"
    );

    // Triangles: an OBJ of two triangles through the importer plugin. A mesh over the
    // limit is left out of the import with a warning naming the flag.
    let obj = dir.join("two.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let saved = dir.join("two.kiln");
    let meshes = |args: &[&str]| {
        let out = kiln()
            .args([
                "import",
                obj.to_str().unwrap(),
                "-o",
                saved.to_str().unwrap(),
            ])
            .args(args)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        (
            kiln::scene::load_scene(&saved).unwrap().meshes.len(),
            stderr(&out),
        )
    };
    let (left, warning) = meshes(&["--max-triangles", "1", "--ground", "none"]);
    assert_eq!(left, 0, "{warning}");
    assert!(warning.contains("--max-triangles"), "{warning}");
    assert_eq!(meshes(&["--ground", "none"]).0, 1);
    // The saved scene keeps its mesh as an OBJ file, which the same limit refuses.
    let out = dir.join("two.png");
    let (saved, out) = (saved.to_str().unwrap(), out.to_str().unwrap());
    let e = fails(&["render", saved, "-o", out, "--max-triangles", "1"]);
    assert!(e.contains("--max-triangles") && e.contains("mesh"), "{e}");
    // The glTF importer refuses an accessor past the limit before reading it: the flag
    // reaches the plugin (in an isolated worker too).
    let glb = dir.join("ball.glb");
    kiln::bench::write_glb(&kiln::scene::shapes::uv_sphere(8, 4, true), &glb).unwrap();
    let glb = glb.to_str().unwrap();
    for isolate in [false, true] {
        let mut args = vec!["import", glb, "-o", saved, "--max-triangles", "10"];
        if isolate {
            args.push("--isolate-importers");
        }
        let out = kiln().args(&args).output().unwrap();
        let e = stderr(&out);
        assert!(e.contains("at most 10 are read"), "isolated {isolate}: {e}");
    }
}

/// `--ground catcher` on a model without lights: the EXR's alpha holds the model (1), its
/// shadow (in between) and the transparent background (0, with no colour).
#[test]
fn ground_catcher_writes_the_model_and_its_shadow_as_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("ball.glb");
    kiln::bench::write_glb(&kiln::scene::shapes::uv_sphere(32, 16, true), &glb).unwrap();
    let out = dir.path().join("ball.exr");
    render(
        &out,
        &[
            glb.to_str().unwrap(),
            "--ground",
            "catcher",
            "--size",
            "48x32",
            "--spp",
            "16",
        ],
    );
    let exr = read_exr(&out);
    let alpha = exr.channel("A");
    let centre = (exr.height / 2) * exr.width + exr.width / 2;
    assert!(
        alpha[centre] > 0.99,
        "the ball's alpha is {}",
        alpha[centre]
    );
    // The top-left corner looks above the horizon: transparent, black.
    assert_eq!(alpha[0], 0.0);
    assert_eq!(exr.rgb(0), [0.0; 3]);
    let shadowed = alpha.iter().filter(|a| **a > 0.3 && **a < 0.99).count();
    assert!(
        shadowed > 5,
        "{shadowed} pixels of partial alpha: no shadow"
    );
}
