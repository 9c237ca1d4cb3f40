//! The renderer's film as an image writer receives it ([`ExportFilm`]): read back a band
//! of rows at a time, tonemapped for display, with each pixel's sample count as a layer
//! and the AOVs when they were rendered. The CLI and the editor both export through this.

use crate::film::output::{ExportFilm, ExportLayer, ViewSettings};

use super::{RenderError, RenderSettings, Renderer};

/// Rows of the film read back and converted at a time: large images are never held whole
/// as a film on the host, only in the output's own form.
const BAND_ROWS: u32 = 256;

/// Reads `renderer`'s film into the form exporters take.
pub fn export_film(renderer: &Renderer, view: ViewSettings) -> Result<ExportFilm, RenderError> {
    let RenderSettings { width, height, .. } = *renderer.settings();
    let mut film = ExportFilm::with_capacity(width, height);
    let mut samples = Vec::with_capacity(width as usize * height as usize);
    for y in (0..height).step_by(BAND_ROWS as usize) {
        let band = renderer.read_film_rows(y..(y + BAND_ROWS).min(height))?;
        film.push_rows(&band, view);
        samples.extend(band.sums.iter().map(|s| s[3] as f32));
    }
    if let Some(aovs) = renderer.read_aovs()? {
        for (name, channels, data) in [
            ("albedo", 3, aovs.albedo),
            ("normal", 3, aovs.normal),
            ("depth", 1, aovs.depth),
        ] {
            film.layers.push(ExportLayer {
                name: name.into(),
                channels,
                data,
            });
        }
    }
    if let Some(noise) = renderer.read_noise()? {
        film.layers.push(ExportLayer {
            name: "noise".into(),
            channels: 1,
            data: noise,
        });
    }
    film.layers.push(ExportLayer {
        name: "samples".into(),
        channels: 1,
        data: samples,
    });
    Ok(film)
}
