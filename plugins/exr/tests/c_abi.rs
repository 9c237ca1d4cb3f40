//! The OpenEXR exporter driven through its C ABI, with every file read back by the `exr`
//! crate: floats must come back bit for bit, in every channel of every layer.

use std::ffi::{CStr, CString, c_char};
use std::path::Path;

use exr::prelude::{FlatSamples, ReadChannels, ReadLayers};
use kiln_exr::kiln_plugin_descriptor;
use kiln_plugin_api as api;
use kiln_plugin_api::recording::{TestFilm, TestLayer};

/// Awkward floats that lossy paths or careless conversions would change.
const SPECIAL: [f32; 8] = [
    0.0,
    -0.0,
    1.0e-40, // subnormal
    f32::MAX,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1.000_000_1,
    -123.456,
];

/// Value `i` of a channel, seeded so that no two channels agree.
fn sample(seed: u32, i: usize) -> f32 {
    if i % 5 == 3 {
        return SPECIAL[(i + seed as usize) % SPECIAL.len()];
    }
    if i % 11 == 7 {
        // A NaN with a payload: only an exact copy keeps these bits.
        return f32::from_bits(0x7fc0_1234 + seed);
    }
    let x = (i as u32)
        .wrapping_mul(2_654_435_761)
        .wrapping_add(seed.wrapping_mul(97));
    (x % 100_000) as f32 / 7.0 - 3000.0
}

/// A `width`×`height` film whose radiance and albedo, normal and depth layers hold
/// seeded values, awkward floats among them.
fn test_film(width: u32, height: u32) -> TestFilm {
    let n = (width * height) as usize;
    let layer = |name: &str, channels: u32, seed: u32| TestLayer {
        name: CString::new(name).unwrap(),
        channels,
        data: (0..n * channels as usize)
            .map(|i| sample(seed, i))
            .collect(),
    };
    TestFilm {
        width,
        height,
        radiance: (0..n * 4).map(|i| sample(1, i)).collect(),
        // The EXR exporter never reads the display image.
        display: Vec::new(),
        layers: vec![
            layer("albedo", 3, 2),
            layer("normal", 3, 3),
            layer("depth", 1, 4),
        ],
    }
}

fn descriptor() -> &'static api::PluginDescriptor {
    // The descriptor is static data of the library.
    unsafe { &*kiln_plugin_descriptor() }
}

fn export(path: &Path, film: &TestFilm, options: &str) -> Result<(), String> {
    film.export(descriptor(), path, options)
}

fn expect_error(path: &Path, film: &TestFilm, options: &str) -> String {
    let message = export(path, film, options).expect_err("export should fail");
    assert!(!message.is_empty(), "an error comes with a message");
    message
}

/// Every channel of the file: (name, samples), sorted by name, and the part count.
fn read_channels(path: &Path) -> (Vec<(String, Vec<f32>)>, usize) {
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let parts = image.layer_data.len();
    let mut channels = Vec::new();
    for layer in &image.layer_data {
        for channel in &layer.channel_data.list {
            let FlatSamples::F32(samples) = &channel.sample_data else {
                panic!("channel {} is not 32-bit float", channel.name);
            };
            channels.push((channel.name.to_string(), samples.clone()));
        }
    }
    channels.sort_by(|a, b| a.0.cmp(&b.0));
    (channels, parts)
}

/// The channels the film should produce, deinterleaved.
fn expected_channels(film: &TestFilm) -> Vec<(String, Vec<f32>)> {
    let split = |data: &[f32], stride: usize, i: usize| -> Vec<f32> {
        data.iter().skip(i).step_by(stride).copied().collect()
    };
    let mut out: Vec<(String, Vec<f32>)> = ["R", "G", "B", "A"]
        .iter()
        .enumerate()
        .map(|(i, n)| (n.to_string(), split(&film.radiance, 4, i)))
        .collect();
    let names = |layer: &str| -> Vec<&str> {
        match layer {
            "albedo" => vec!["R", "G", "B"],
            "normal" => vec!["X", "Y", "Z"],
            "depth" => vec!["Z"],
            other => panic!("no expected names for {other}"),
        }
    };
    for l in &film.layers {
        let layer = l.name.to_str().unwrap();
        for (i, suffix) in names(layer).into_iter().enumerate() {
            out.push((
                format!("{layer}.{suffix}"),
                split(&l.data, l.channels as usize, i),
            ));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn assert_bit_identical(got: &[(String, Vec<f32>)], want: &[(String, Vec<f32>)]) {
    let names = |c: &[(String, Vec<f32>)]| c.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(got), names(want));
    for ((name, g), (_, w)) in got.iter().zip(want) {
        assert_eq!(g.len(), w.len(), "{name}: sample count");
        for (i, (a, b)) in g.iter().zip(w).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "{name}[{i}]: {a} read back for {b}"
            );
        }
    }
}

#[test]
fn descriptor_declares_an_exr_exporter_of_this_abi() {
    let d = descriptor();
    assert_eq!(d.abi_version, api::ABI_VERSION);
    assert_eq!(d.kind, api::KIND_EXPORTER);
    assert!(d.import.is_none() && d.export.is_some());
    let text = |p| unsafe { CStr::from_ptr(p) }.to_str().unwrap();
    assert_eq!(text(d.name), "OpenEXR");
    assert_eq!(text(d.extensions), "exr");
    assert_eq!(text(d.version), env!("CARGO_PKG_VERSION"));
}

#[test]
fn every_channel_of_every_layer_reads_back_bit_identical_for_each_compression() {
    let dir = tempfile::tempdir().unwrap();
    // Odd sizes and more than 16 rows, so ZIP's and PIZ's blocks end part-way.
    let film = test_film(37, 23);
    let want = expected_channels(&film);
    for compression in [
        "",
        "compression=none",
        "compression=rle",
        "compression=zip",
        "compression=zips",
        "compression=piz",
    ] {
        let path = dir.path().join("film.exr");
        assert_eq!(export(&path, &film, compression), Ok(()), "{compression}");
        let (got, parts) = read_channels(&path);
        assert_eq!(parts, 1, "one part, layers as channel prefixes");
        assert_bit_identical(&got, &want);
    }
}

#[test]
fn default_compression_is_zip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("film.exr");
    let film = test_film(8, 20);
    assert_eq!(export(&path, &film, ""), Ok(()));
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    assert_eq!(
        meta.headers[0].compression,
        exr::prelude::Compression::ZIP16
    );
}

#[test]
fn a_film_without_aovs_is_plain_rgba() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rgba.exr");
    let mut film = test_film(4, 3);
    film.layers.clear();
    assert_eq!(export(&path, &film, ""), Ok(()));
    let (got, _) = read_channels(&path);
    assert_bit_identical(&got, &expected_channels(&film));
    // Readers of plain RGBA files see it too.
    let (w, h, pixels) = {
        let image = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| (res.width(), res.height(), vec![[0f32; 4]; res.area()]),
            |(w, _, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = [r, g, b, a]
            },
        )
        .unwrap();
        image.layer_data.channel_data.pixels
    };
    assert_eq!((w, h), (4, 3));
    // Pixel (x, y) is film pixel y·width + x: rows run from the top.
    for (p, want) in pixels.iter().zip(film.radiance.chunks_exact(4)) {
        assert_eq!(p.map(f32::to_bits), [0, 1, 2, 3].map(|c| want[c].to_bits()));
    }
}

#[test]
fn writes_leave_only_the_image_readable_by_all() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("film.exr");
    assert_eq!(export(&path, &test_film(3, 3), ""), Ok(()));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o644);
    }
}

#[test]
fn bad_options_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("film.exr");
    let film = test_film(2, 2);
    for (options, needle) in [
        ("compression=pxr24", "lossy"),
        ("compression=dwaa", "lossy"),
        ("compression=lzma", "compression=lzma"),
        ("bits=16", "bits"),
    ] {
        let message = expect_error(&path, &film, options);
        assert!(
            message.contains(needle) && message.contains("film.exr"),
            "{options}: {message}"
        );
    }
    assert!(!path.exists());
}

#[test]
fn unwritable_destinations_fail_with_the_path_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let film = test_film(2, 2);
    let missing = dir.path().join("no such folder").join("film.exr");
    let message = expect_error(&missing, &film, "");
    assert!(message.contains("no such folder"), "{message}");
    let file = dir.path().join("file");
    std::fs::write(&file, b"").unwrap();
    let message = expect_error(&file.join("film.exr"), &film, "");
    assert!(message.contains("film.exr"), "{message}");
}

#[test]
fn bad_films_are_refused_with_the_path_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.exr");
    let mut film = test_film(2, 2);
    film.width = 0;
    let message = expect_error(&path, &film, "");
    assert!(
        message.contains("bad.exr") && message.contains("0×2"),
        "{message}"
    );

    let mut film = test_film(2, 2);
    film.radiance.clear();
    let message = expect_error(&path, &film, "");
    assert!(message.contains("radiance"), "{message}");

    let mut film = test_film(2, 2);
    film.layers[1].name = CString::new("albedo").unwrap();
    let message = expect_error(&path, &film, "");
    assert!(
        message.contains("albedo.") && message.contains("unique"),
        "{message}"
    );

    let mut film = test_film(2, 2);
    film.layers[0].channels = 0;
    let message = expect_error(&path, &film, "");
    assert!(message.contains("albedo"), "{message}");

    let mut film = test_film(2, 2);
    film.layers[0].name = CString::new("").unwrap();
    let message = expect_error(&path, &film, "");
    assert!(message.contains("no name"), "{message}");
    assert!(!path.exists());
}

#[test]
fn null_arguments_are_errors_not_crashes() {
    let export = descriptor().export.unwrap();
    let film = test_film(2, 2);
    let mut message = vec![0 as c_char; 256];
    let mut error = api::ErrorBuffer {
        data: message.as_mut_ptr(),
        capacity: message.len(),
    };
    let status = film
        .with_view(|view| unsafe { export(std::ptr::null(), view, std::ptr::null(), &mut error) });
    assert_eq!(status, api::STATUS_ERROR);
    let path = CString::new("/nonexistent-kiln-dir/x.exr").unwrap();
    let status = unsafe {
        export(
            path.as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            &mut error,
        )
    };
    assert_eq!(status, api::STATUS_ERROR);
    let status = film.with_view(|view| unsafe {
        export(path.as_ptr(), view, std::ptr::null(), std::ptr::null_mut())
    });
    assert_eq!(status, api::STATUS_ERROR);
}
