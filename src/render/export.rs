//! The renderer's film as an image writer receives it ([`ExportFilm`]): read back a band
//! of rows at a time, tonemapped for display, with each pixel's sample count as a layer
//! and the AOVs and the noise estimate when they were rendered; or denoised
//! ([`super::denoise`]), the image as rendered kept as a layer. The CLI and the editor
//! both export through this.

use crate::film::output::{ExportFilm, ExportLayer, ViewSettings};

use super::denoise::denoise_film;
use super::{RenderError, RenderSettings, Renderer};
use crate::scene::Denoiser;

/// Rows of the film read back and converted at a time: large images are never held whole
/// as a film on the host, only in the output's own form.
const BAND_ROWS: u32 = 256;

/// Reads `renderer`'s film into the form exporters take.
pub fn export_film(
    renderer: &Renderer,
    view: ViewSettings,
    denoiser: Denoiser,
) -> Result<ExportFilm, RenderError> {
    if denoiser != Denoiser::None {
        return export_denoised(renderer, view, denoiser);
    }
    let RenderSettings { width, height, .. } = *renderer.settings();
    let mut film = ExportFilm::with_capacity(width, height);
    let mut samples = Vec::with_capacity(width as usize * height as usize);
    for y in (0..height).step_by(BAND_ROWS as usize) {
        let band = renderer.read_film_rows(y..(y + BAND_ROWS).min(height))?;
        film.push_rows(&band, view);
        samples.extend(band.sums.iter().map(|s| s[3] as f32));
    }
    let aovs = renderer.read_aovs()?;
    if renderer.transparent()
        && let Some(aovs) = &aovs
    {
        film.set_alpha(&aovs.alpha, view);
    }
    push_layers(renderer, &mut film, aovs, samples)?;
    Ok(film)
}

/// The film denoised with `denoiser`, the image as rendered kept as the `noisy` layer
/// (Cycles' Noisy Image). Reads the whole film at once: the filter needs the rows around
/// each.
fn export_denoised(
    renderer: &Renderer,
    view: ViewSettings,
    denoiser: Denoiser,
) -> Result<ExportFilm, RenderError> {
    let film = renderer.read_film()?;
    let (Some(aovs), Some(moments)) = (renderer.read_aovs()?, renderer.read_second_moments()?)
    else {
        return Err(RenderError::Denoise(
            "the renderer was built without AOVs (RenderSettings::aovs)".into(),
        ));
    };
    let denoised = denoise_film(&renderer.ctx, &film, &aovs, &moments, denoiser)?;
    let mut export = ExportFilm::from_film(&denoised, view, Vec::new());
    export.layers.push(ExportLayer {
        name: "noisy".into(),
        channels: 3,
        data: film.radiance().iter().flat_map(|c| c.to_array()).collect(),
    });
    let samples = film.sums.iter().map(|s| s[3] as f32).collect();
    if renderer.transparent() {
        export.set_alpha(&aovs.alpha, view);
    }
    push_layers(renderer, &mut export, Some(aovs), samples)?;
    Ok(export)
}

/// Appends `aovs` (the renderer's, read once), the noise estimate and the sample counts
/// as layers.
fn push_layers(
    renderer: &Renderer,
    film: &mut ExportFilm,
    aovs: Option<super::Aovs>,
    samples: Vec<f32>,
) -> Result<(), RenderError> {
    if let Some(aovs) = aovs {
        for (name, channels, data) in [
            ("albedo", 3, aovs.albedo),
            ("normal", 3, aovs.normal),
            ("depth", 1, aovs.depth),
            ("emission", 3, aovs.emission),
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
    Ok(())
}
