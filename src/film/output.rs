//! Writing a film to an image file: PNG and JPEG (tonemapped, 8-bit sRGB) or OpenEXR
//! (linear 32-bit float radiance). Every write goes to a temporary file in the target's
//! folder that is renamed over the target only when complete, so a failed or interrupted
//! write never leaves a truncated image or destroys the previous one.

use std::path::{Path, PathBuf};

use image::{ImageFormat, Rgb32FImage, RgbImage};
use thiserror::Error;

use super::Film;
use super::tonemap::{Tonemap, to_srgb8};

#[derive(Debug, Error)]
pub enum OutputError {
    #[error(
        "cannot tell the image format of {path}: use one of the extensions .png, .jpg, .jpeg, .exr"
    )]
    UnknownFormat { path: PathBuf },
    /// `message` names the path.
    #[error("{message}")]
    Write { path: PathBuf, message: String },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    Jpeg,
    Exr,
}

impl OutputFormat {
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("jpg" | "jpeg") => Ok(Self::Jpeg),
            Some("exr") => Ok(Self::Exr),
            _ => Err(OutputError::UnknownFormat {
                path: path.to_owned(),
            }),
        }
    }
}

/// How the film becomes display values (ignored for EXR, which keeps scene-linear data).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewSettings {
    pub exposure_ev: f32,
    pub tonemap: Tonemap,
}

/// The film as 8-bit sRGB, through the one film → tonemap → sRGB path.
pub fn to_srgb_image(film: &Film, view: ViewSettings) -> RgbImage {
    RgbImage::from_fn(film.width, film.height, |x, y| {
        image::Rgb(to_srgb8(film.pixel(x, y), view.exposure_ev, view.tonemap))
    })
}

/// Writes the film atomically (`kiln_plugin_api::atomic`, shared with the exporter
/// plugins): a complete image or none, never a truncated one.
pub fn write_image(path: &Path, film: &Film, view: ViewSettings) -> Result<(), OutputError> {
    let format = OutputFormat::from_path(path)?;
    kiln_plugin_api::atomic::write_atomically(path, |writer| {
        let result = match format {
            OutputFormat::Png => to_srgb_image(film, view).write_to(writer, ImageFormat::Png),
            OutputFormat::Jpeg => to_srgb_image(film, view).write_to(writer, ImageFormat::Jpeg),
            OutputFormat::Exr => {
                let pixels: Vec<f32> = film.radiance().iter().flat_map(|c| c.to_array()).collect();
                Rgb32FImage::from_raw(film.width, film.height, pixels)
                    .expect("one rgb triple per pixel")
                    .write_to(writer, ImageFormat::OpenExr)
            }
        };
        result.map_err(|e| e.to_string())
    })
    .map_err(|message| OutputError::Write {
        path: path.to_owned(),
        message,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient_film() -> Film {
        let mut film = Film::new(8, 4);
        for (i, s) in film.sums.iter_mut().enumerate() {
            let v = i as f64 / 32.0;
            *s = [v * 2.0, v, 0.25 * 2.0, 2.0];
        }
        film
    }

    #[test]
    fn png_holds_the_tonemapped_film() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        let film = gradient_film();
        let view = ViewSettings::default();
        write_image(&path, &film, view).unwrap();
        let read = image::open(&path).unwrap().to_rgb8();
        assert_eq!(read, to_srgb_image(&film, view));
        // Only the image is left behind: no temporary files.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode();
            assert_eq!(
                mode & 0o777,
                0o644,
                "a new image is readable like other files"
            );
        }
    }

    #[test]
    fn exr_holds_linear_radiance_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.exr");
        let film = gradient_film();
        write_image(&path, &film, ViewSettings::default()).unwrap();
        let read = image::open(&path).unwrap().to_rgb32f();
        for (x, y, p) in read.enumerate_pixels() {
            assert_eq!(p.0, film.pixel(x, y).to_array());
        }
    }

    #[test]
    fn unknown_extension_is_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let err = write_image(
            &dir.path().join("out.bmpx"),
            &gradient_film(),
            ViewSettings::default(),
        )
        .unwrap_err();
        assert!(err.to_string().contains(".png"), "{err}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn write_into_a_missing_folder_fails_with_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no such folder").join("out.png");
        assert!(write_image(&missing, &gradient_film(), ViewSettings::default()).is_err());
    }
}
