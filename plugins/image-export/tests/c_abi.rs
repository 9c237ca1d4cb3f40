//! The PNG/JPEG exporter driven through its C ABI, as the host drives it: the
//! descriptor, then `export` with a hand-built `FilmView`.

use std::ffi::{CStr, CString, c_char};
use std::path::Path;

use kiln_image_export::kiln_plugin_descriptor;
use kiln_plugin_api as api;
use kiln_plugin_api::recording::{TestFilm, export_view};

/// A `width`×`height` film showing `display`, with radiance 1.
fn test_film(width: u32, height: u32, display: Vec<f32>) -> TestFilm {
    TestFilm {
        width,
        height,
        radiance: vec![1.0; display.len()],
        display,
        layers: Vec::new(),
    }
}

/// `n` pixels whose display values run through [0, 1] with alpha varying too.
fn gradient(width: u32, height: u32) -> TestFilm {
    let n = (width * height) as usize;
    let display = (0..n)
        .flat_map(|i| {
            let t = i as f32 / (n - 1).max(1) as f32;
            [t, 1.0 - t, (t * 7.0).fract(), 0.25 + 0.75 * t]
        })
        .collect();
    test_film(width, height, display)
}

fn descriptor() -> &'static api::PluginDescriptor {
    // The descriptor is static data of the library.
    unsafe { &*kiln_plugin_descriptor() }
}

fn expect_ok(path: &Path, film: &TestFilm, options: &str) {
    let result = film.export(descriptor(), path, options);
    assert_eq!(result, Ok(()), "export failed");
}

fn expect_error(path: &Path, film: &TestFilm, options: &str) -> String {
    let result = film.export(descriptor(), path, options);
    let message = result.expect_err("export should fail");
    assert!(!message.is_empty(), "an error comes with a message");
    message
}

fn quantize8(v: f32) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    }
}

#[test]
fn descriptor_declares_a_png_jpeg_exporter_of_this_abi() {
    let d = descriptor();
    assert_eq!(d.abi_version, api::ABI_VERSION);
    assert_eq!(d.kind, api::KIND_EXPORTER);
    assert!(d.import.is_none() && d.export.is_some());
    let text = |p| unsafe { CStr::from_ptr(p) }.to_str().unwrap();
    assert_eq!(text(d.name), "PNG/JPEG");
    assert_eq!(text(d.extensions), "png,jpg,jpeg");
    assert_eq!(text(d.version), env!("CARGO_PKG_VERSION"));
}

#[test]
fn png_8_bit_holds_the_display_rgba_rounded_to_nearest() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    let film = gradient(7, 5);
    expect_ok(&path, &film, "");
    let read = image::open(&path).unwrap();
    assert_eq!(
        read.color(),
        image::ColorType::Rgba8,
        "PNG keeps alpha, 8-bit by default"
    );
    let expected: Vec<u8> = film.display.iter().map(|&v| quantize8(v)).collect();
    assert_eq!(read.to_rgba8().into_raw(), expected);
}

#[test]
fn png_16_bit_holds_the_display_to_one_part_in_65535() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    let film = gradient(6, 4);
    expect_ok(&path, &film, "bits=16");
    let read = image::open(&path).unwrap();
    assert_eq!(read.color(), image::ColorType::Rgba16);
    let pixels = read.to_rgba16().into_raw();
    for (&stored, &v) in pixels.iter().zip(&film.display) {
        let back = f32::from(stored) / 65535.0;
        assert!(
            (back - v).abs() <= 0.5 / 65535.0 + 1e-7,
            "{v} stored as {stored}"
        );
    }
}

#[test]
fn out_of_range_and_nan_values_are_clamped_and_zeroed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("edge.png");
    let display = vec![
        -0.5,
        1.5,
        f32::NAN,
        f32::INFINITY, //
        0.5 / 255.0,
        0.499 / 255.0,
        f32::NEG_INFINITY,
        1.0,
    ];
    expect_ok(&path, &test_film(2, 1, display), "");
    let pixels = image::open(&path).unwrap().to_rgba8().into_raw();
    assert_eq!(pixels, [0, 255, 0, 255, 1, 0, 0, 255]);
}

#[test]
fn jpeg_drops_alpha_and_keeps_colour_within_compression_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.jpg");
    // A flat colour: JPEG's error on it is a few levels at most.
    let display = [0.8f32, 0.4, 0.2, 0.3].repeat(16 * 16);
    expect_ok(&path, &test_film(16, 16, display), "");
    let read = image::open(&path).unwrap();
    assert_eq!(read.color(), image::ColorType::Rgb8, "JPEG has no alpha");
    for p in read.to_rgb8().pixels() {
        for (got, want) in p.0.iter().zip([204u8, 102, 51]) {
            assert!(got.abs_diff(want) <= 3, "{:?} far from (204, 102, 51)", p.0);
        }
    }
}

#[test]
fn jpeg_quality_option_trades_size_for_fidelity() {
    let dir = tempfile::tempdir().unwrap();
    let film = gradient(64, 64);
    let low = dir.path().join("low.jpeg");
    let high = dir.path().join("high.jpeg");
    expect_ok(&low, &film, "quality=10");
    expect_ok(&high, &film, "quality=100");
    let size = |p: &Path| std::fs::metadata(p).unwrap().len();
    assert!(
        size(&low) < size(&high),
        "{} !< {}",
        size(&low),
        size(&high)
    );
}

#[test]
fn writes_leave_only_the_image_readable_by_all() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    expect_ok(&path, &gradient(3, 3), "");
    let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(entries.len(), 1, "no temporary file is left behind");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o644);
    }
}

#[cfg(unix)]
#[test]
fn replacing_an_image_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    std::fs::write(&path, b"old").unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
    expect_ok(&path, &gradient(3, 3), "");
    let mode = std::fs::metadata(&path).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, 0o600);
    assert!(image::open(&path).is_ok());
}

#[test]
fn a_failed_export_leaves_the_previous_file_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    std::fs::write(&path, b"previous").unwrap();
    expect_error(&path, &test_film(0, 0, Vec::new()), "");
    expect_error(&path, &gradient(2, 2), "bits=12");
    assert_eq!(std::fs::read(&path).unwrap(), b"previous");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn unwritable_destinations_fail_with_the_path_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let film = gradient(2, 2);
    let missing = dir.path().join("no such folder").join("out.png");
    let message = expect_error(&missing, &film, "");
    assert!(message.contains("no such folder"), "{message}");
    // A regular file where the folder should be (root ignores permission bits, so this
    // is the unwritable folder that holds for every user).
    let file = dir.path().join("file");
    std::fs::write(&file, b"").unwrap();
    let message = expect_error(&file.join("out.jpg"), &film, "");
    assert!(message.contains("out.jpg"), "{message}");
    // A folder where the file should be.
    let folder = dir.path().join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    let message = expect_error(&folder, &film, "");
    assert!(message.contains("folder.png"), "{message}");
}

#[test]
fn bad_films_are_refused_with_the_path_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.png");
    let message = expect_error(&path, &test_film(0, 4, Vec::new()), "");
    assert!(
        message.contains("bad.png") && message.contains("0×4"),
        "{message}"
    );
    // No display buffer: the view has a null pointer, so the film holds no floats.
    let mut film = gradient(2, 2);
    film.display.clear();
    let message = expect_error(&path, &film, "");
    assert!(
        message.contains("bad.png") && message.contains("16"),
        "{message}"
    );
    // Sizes whose pixel count overflows are an error, not a crash.
    let view = api::FilmView {
        width: u32::MAX,
        height: u32::MAX,
        radiance: std::ptr::null(),
        display: std::ptr::null(),
        layer_count: 0,
        layers: std::ptr::null(),
    };
    let message = export_view(descriptor(), &path, &view, "").expect_err("export should fail");
    assert!(!message.is_empty());
    assert!(!path.exists());
}

#[test]
fn bad_options_are_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let film = gradient(2, 2);
    let png = dir.path().join("o.png");
    let jpg = dir.path().join("o.jpg");
    for (path, options, needle) in [
        (&png, "bits=12", "bits=12"),
        (&png, "quality=80", "quality"),
        (&png, "gamma=2", "gamma"),
        (&jpg, "quality=0", "quality=0"),
        (&jpg, "quality=101", "quality=101"),
        (&jpg, "quality=high", "quality=high"),
        (&jpg, "bits=16", "bits"),
    ] {
        let message = expect_error(path, &film, options);
        assert!(message.contains(needle), "{options}: {message}");
    }
    expect_ok(&jpg, &film, " quality = 75 ; ");
}

#[test]
fn null_arguments_and_short_error_buffers_are_handled() {
    let export = descriptor().export.unwrap();
    let film = gradient(2, 2);
    film.with_view(|view| {
        let mut message = vec![0x55 as c_char; 8];
        let mut error = api::ErrorBuffer {
            data: message.as_mut_ptr(),
            capacity: message.len(),
        };
        let status = unsafe { export(std::ptr::null(), view, std::ptr::null(), &mut error) };
        assert_eq!(status, api::STATUS_ERROR);
        // Truncated to the buffer, NUL-terminated.
        assert_eq!(message[7], 0);
        let path = CString::new("/nonexistent-kiln-dir/x.png").unwrap();
        let status = unsafe {
            export(
                path.as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                &mut error,
            )
        };
        assert_eq!(status, api::STATUS_ERROR);
        // A null error buffer: the status alone reports the failure.
        let status = unsafe { export(path.as_ptr(), view, std::ptr::null(), std::ptr::null_mut()) };
        assert_eq!(status, api::STATUS_ERROR);
    });
}
