//! Writing a film to an image file: PNG and JPEG (tonemapped, 8-bit sRGB) or OpenEXR
//! (linear 32-bit float radiance, and each pixel's sample count as the `samples` layer,
//! named as the EXR plugin names layers). Every write goes to a temporary file in the target's
//! folder that is renamed over the target only when complete, so a failed or interrupted
//! write never leaves a truncated image or destroys the previous one.

use std::path::{Path, PathBuf};

use image::{ImageFormat, RgbImage};
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

/// An image file's pixels, assembled from bands of a film's rows before it is written:
/// a large film is read back and converted a band at a time, so that only the image's own
/// buffer (3 bytes a pixel for PNG and JPEG, 16 for EXR) is held whole, never the film.
pub struct OutputImage {
    path: PathBuf,
    format: OutputFormat,
    view: ViewSettings,
    pixels: Pixels,
}

enum Pixels {
    Srgb(RgbImage),
    /// Planar channels, as OpenEXR stores them: R, G, B and the sample counts.
    Linear {
        width: u32,
        channels: [Vec<f32>; 4],
    },
}

/// The EXR channel names of [`Pixels::Linear`]'s planes.
const EXR_CHANNELS: [&str; 4] = ["R", "G", "B", "samples.Y"];

impl OutputImage {
    /// A black `width`×`height` image for `path`, in the format its extension names.
    pub fn new(
        path: &Path,
        width: u32,
        height: u32,
        view: ViewSettings,
    ) -> Result<Self, OutputError> {
        let format = OutputFormat::from_path(path)?;
        let pixels = match format {
            OutputFormat::Png | OutputFormat::Jpeg => Pixels::Srgb(RgbImage::new(width, height)),
            OutputFormat::Exr => Pixels::Linear {
                width,
                channels: std::array::from_fn(|_| vec![0.0; width as usize * height as usize]),
            },
        };
        Ok(Self {
            path: path.to_owned(),
            format,
            view,
            pixels,
        })
    }

    /// Converts `band`, the film's rows from `first_row` down (as wide as the image), into
    /// the image's pixels. Rows past the image's bottom are ignored.
    pub fn put_rows(&mut self, first_row: u32, band: &Film) {
        let view = self.view;
        for y in 0..band.height {
            let row = first_row + y;
            for x in 0..band.width {
                let c = band.pixel(x, y);
                match &mut self.pixels {
                    Pixels::Srgb(img) if row < img.height() && x < img.width() => {
                        img.put_pixel(
                            x,
                            row,
                            image::Rgb(to_srgb8(c, view.exposure_ev, view.tonemap)),
                        );
                    }
                    Pixels::Linear { width, channels } if x < *width => {
                        let i = row as usize * *width as usize + x as usize;
                        if i < channels[0].len() {
                            let samples = band.sample_count(x, y) as f32;
                            for (plane, v) in channels.iter_mut().zip([c.x, c.y, c.z, samples]) {
                                plane[i] = v;
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
    }

    /// Writes the image atomically (`kiln_plugin_api::atomic`, shared with the exporter
    /// plugins): a complete image or none, never a truncated one.
    pub fn write(self) -> Result<(), OutputError> {
        let Self {
            path,
            format,
            pixels,
            ..
        } = self;
        kiln_plugin_api::atomic::write_atomically(&path, |writer| {
            let result = match (pixels, format) {
                (Pixels::Srgb(img), OutputFormat::Jpeg) => img.write_to(writer, ImageFormat::Jpeg),
                (Pixels::Srgb(img), _) => img.write_to(writer, ImageFormat::Png),
                (Pixels::Linear { width, channels }, _) => {
                    return write_exr(writer, width, channels);
                }
            };
            result.map_err(|e| e.to_string())
        })
        .map_err(|message| OutputError::Write {
            path: path.clone(),
            message,
        })
    }
}

/// An OpenEXR file of `width`-wide planes named [`EXR_CHANNELS`], 32-bit float, ZIP
/// compressed in blocks of 16 scan lines (the EXR plugin's default).
fn write_exr<W: std::io::Write + std::io::Seek>(
    writer: W,
    width: u32,
    channels: [Vec<f32>; 4],
) -> Result<(), String> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image, Layer,
        LayerAttributes, LineOrder, SmallVec, Text, Vec2, WritableImage,
    };
    let height = channels[0].len() / width.max(1) as usize;
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = EXR_CHANNELS
        .iter()
        .zip(channels)
        .map(|(name, plane)| {
            // The names are ASCII constants.
            let name = Text::new_or_none(*name).expect("ASCII channel name");
            AnyChannel::new(name, FlatSamples::F32(plane))
        })
        .collect();
    let layer = Layer::new(
        Vec2(width as usize, height),
        LayerAttributes::default(),
        Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(list),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(writer)
        .map_err(|e| e.to_string())
}

/// Writes the film atomically: a complete image or none, never a truncated one.
pub fn write_image(path: &Path, film: &Film, view: ViewSettings) -> Result<(), OutputError> {
    let mut image = OutputImage::new(path, film.width, film.height, view)?;
    image.put_rows(0, film);
    image.write()
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
        // Each pixel's sample count, as the `samples` layer.
        let layers = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
        let samples = layers.layer_data[0]
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == "samples.Y")
            .expect("a samples layer");
        let counts: Vec<f32> = samples.sample_data.values_as_f32().collect();
        assert_eq!(counts, vec![2.0; 32]);
    }

    #[test]
    fn an_image_assembled_from_bands_equals_the_whole_film_written_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let film = gradient_film();
        for name in ["whole.png", "whole.exr"] {
            let whole = dir.path().join(name);
            write_image(&whole, &film, ViewSettings::default()).unwrap();
            let banded = dir.path().join(format!("banded.{}", &name[6..]));
            let mut image = OutputImage::new(&banded, 8, 4, ViewSettings::default()).unwrap();
            // Bands of 3 and 1 rows, the second put first: order does not matter.
            let band = |rows: std::ops::Range<usize>| Film {
                width: 8,
                height: rows.len() as u32,
                sums: film.sums[rows.start * 8..rows.end * 8].to_vec(),
            };
            image.put_rows(3, &band(3..4));
            image.put_rows(0, &band(0..3));
            image.write().unwrap();
            assert_eq!(
                std::fs::read(&whole).unwrap(),
                std::fs::read(&banded).unwrap(),
                "{name}"
            );
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
