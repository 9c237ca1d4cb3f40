//! Writing a film to an image file when no exporter plugin handles the format: PNG and
//! JPEG (the tonemapped display image) or OpenEXR (linear 32-bit float radiance and the
//! AOV layers), through the same writers the bundled exporter plugins wrap
//! (`kiln_formats::image`, `kiln_formats::exr`), so the host and a plugin write the same
//! bytes for the same film and options (`tests/import.rs`). Every write goes to a
//! temporary file in the target's folder that is renamed over the target only when
//! complete, so a failed or interrupted write never leaves a truncated image or destroys
//! the previous one.
//!
//! [`ExportFilm`] is the film as both receive it: this module's writers directly, the
//! plugins through the C ABI (`plugin::PluginHost::export`).

use std::path::{Path, PathBuf};

use image::RgbImage;
use kiln_formats::{exr, image as display_image};
use thiserror::Error;

use super::Film;
use super::tonemap::{srgb_encode, to_srgb8};

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

/// The extensions the host's own writers take (what [`OutputFormat::from_path`] knows).
pub const HOST_EXTENSIONS: [&str; 4] = ["png", "jpg", "jpeg", "exr"];

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

pub use crate::shader::view::ViewSettings;

/// The film as 8-bit sRGB, through the one film → tonemap → sRGB path.
pub fn to_srgb_image(film: &Film, view: ViewSettings) -> RgbImage {
    RgbImage::from_fn(film.width, film.height, |x, y| {
        image::Rgb(to_srgb8(film.pixel(x, y), view.exposure_ev, view.tonemap))
    })
}

/// A named AOV layer of an exported film.
pub struct ExportLayer {
    pub name: String,
    pub channels: u32,
    pub data: Vec<f32>,
}

/// The film as image writers receive it, the host's and the exporter plugins'.
pub struct ExportFilm {
    pub width: u32,
    pub height: u32,
    /// Linear RGBA.
    pub radiance: Vec<f32>,
    /// Tonemapped, sRGB-encoded RGBA in [0, 1].
    pub display: Vec<f32>,
    pub layers: Vec<ExportLayer>,
}

impl ExportFilm {
    /// The film's mean radiance, and its display rendering under `view`.
    pub fn from_film(film: &Film, view: ViewSettings, layers: Vec<ExportLayer>) -> Self {
        let mut export = Self::with_capacity(film.width, film.height);
        export.push_rows(film, view);
        export.layers = layers;
        export
    }

    /// An empty `width`×`height` film, to be filled a band of rows at a time with
    /// [`ExportFilm::push_rows`]: a large film is read back and converted a band at a time,
    /// never held whole as sums beside these buffers.
    pub fn with_capacity(width: u32, height: u32) -> Self {
        let floats = width as usize * height as usize * 4;
        Self {
            width,
            height,
            radiance: Vec::with_capacity(floats),
            display: Vec::with_capacity(floats),
            layers: Vec::new(),
        }
    }

    /// Appends the rows of `band` (a film as wide as this one: the next rows down), as
    /// mean radiance and as their display rendering under `view`.
    pub fn push_rows(&mut self, band: &Film, view: ViewSettings) {
        debug_assert_eq!(band.width, self.width, "bands are as wide as the film");
        for y in 0..band.height {
            for x in 0..band.width {
                let c = band.pixel(x, y);
                self.radiance.extend([c.x, c.y, c.z, 1.0]);
                let d = view.tonemap.apply(c * view.exposure_ev.exp2());
                self.display.extend(d.to_array().map(srgb_encode));
                self.display.push(1.0);
            }
        }
    }

    /// Gives the film coverage `alpha` (one value per pixel): the radiance stays
    /// premultiplied (what the renderer averaged, as EXR expects), and the display colour
    /// becomes the radiance over alpha under `view` (straight alpha, as PNG expects).
    pub fn set_alpha(&mut self, alpha: &[f32], view: ViewSettings) {
        for (i, &a) in alpha.iter().enumerate() {
            let a = a.clamp(0.0, 1.0);
            let (rgba, display) = (
                &mut self.radiance[4 * i..4 * i + 4],
                &mut self.display[4 * i..4 * i + 4],
            );
            rgba[3] = a;
            let c = glam::Vec3::new(rgba[0], rgba[1], rgba[2]) / a.max(1e-6);
            let d = if a > 0.0 {
                view.tonemap.apply(c * view.exposure_ev.exp2())
            } else {
                glam::Vec3::ZERO
            };
            display[..3].copy_from_slice(&d.to_array().map(srgb_encode));
            display[3] = a;
        }
    }

    /// The view the shared writers take (the plugin API's safe film).
    pub fn view(&self) -> kiln_plugin_api::Film<'_> {
        kiln_plugin_api::Film {
            width: self.width,
            height: self.height,
            radiance: &self.radiance,
            display: &self.display,
            layers: self
                .layers
                .iter()
                .map(|l| kiln_plugin_api::Layer {
                    name: &l.name,
                    channels: l.channels,
                    data: &l.data,
                })
                .collect(),
        }
    }
}

/// Writes the film atomically in the format of `path`'s extension, with `options` as the
/// exporter plugins take them (`bits=16`, `quality=90`, `compression=piz`): a complete
/// image or none, never a truncated one. EXR files get the film's AOV layers.
pub fn write_image(path: &Path, film: &ExportFilm, options: &str) -> Result<(), OutputError> {
    let format = OutputFormat::from_path(path)?;
    let options = kiln_plugin_api::parse_options(options);
    let result = match format {
        OutputFormat::Png | OutputFormat::Jpeg => display_image::Format::new(path, &options)
            .and_then(|f| display_image::write(path, &film.view(), f)),
        OutputFormat::Exr => exr::compression(&options)
            .map_err(|message| format!("cannot write {}: {message}", path.display()))
            .and_then(|c| exr::write(path, &film.view(), c)),
    };
    result.map_err(|message| OutputError::Write {
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

    fn export(film: &Film, view: ViewSettings) -> ExportFilm {
        ExportFilm::from_film(film, view, Vec::new())
    }

    #[test]
    fn a_film_assembled_from_bands_writes_the_same_bytes_as_the_whole_film() {
        let dir = tempfile::tempdir().unwrap();
        let film = gradient_film();
        let band = |rows: std::ops::Range<usize>| Film {
            width: 8,
            height: rows.len() as u32,
            sums: film.sums[rows.start * 8..rows.end * 8].to_vec(),
        };
        let mut banded = ExportFilm::with_capacity(8, 4);
        banded.push_rows(&band(0..3), ViewSettings::default());
        banded.push_rows(&band(3..4), ViewSettings::default());
        for name in ["a.png", "a.exr"] {
            let whole = dir.path().join(format!("whole_{name}"));
            let parts = dir.path().join(format!("banded_{name}"));
            write_image(&whole, &export(&film, ViewSettings::default()), "").unwrap();
            write_image(&parts, &banded, "").unwrap();
            assert_eq!(
                std::fs::read(&whole).unwrap(),
                std::fs::read(&parts).unwrap(),
                "{name}"
            );
        }
    }

    #[test]
    fn png_holds_the_tonemapped_film() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        let film = gradient_film();
        let view = ViewSettings::default();
        write_image(&path, &export(&film, view), "").unwrap();
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
        write_image(&path, &export(&film, ViewSettings::default()), "").unwrap();
        let read = image::open(&path).unwrap().to_rgb32f();
        for (x, y, p) in read.enumerate_pixels() {
            assert_eq!(p.0, film.pixel(x, y).to_array());
        }
    }

    #[test]
    fn unknown_extension_is_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let film = export(&gradient_film(), ViewSettings::default());
        let err = write_image(&dir.path().join("out.bmpx"), &film, "").unwrap_err();
        assert!(err.to_string().contains(".png"), "{err}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_bad_option_is_refused_naming_the_file_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let film = export(&gradient_film(), ViewSettings::default());
        for (name, options) in [("a.png", "quality=50"), ("b.exr", "compression=dwaa")] {
            let err = write_image(&dir.path().join(name), &film, options).unwrap_err();
            assert!(err.to_string().contains(name), "{err}");
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn write_into_a_missing_folder_fails_with_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no such folder").join("out.png");
        let film = export(&gradient_film(), ViewSettings::default());
        assert!(write_image(&missing, &film, "").is_err());
    }
}
