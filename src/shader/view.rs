//! View settings: how scene-linear radiance becomes display values. The types live in the
//! shader contract because the viewport's display pass (`shaders/editor/display.wgsl`)
//! selects its view transform by [`Tonemap::gpu_id`]; the CPU implementation that images
//! written by `kiln render` go through is `crate::film::tonemap`, which the display pass
//! matches (`tests/display.rs`).

/// A view transform from scene-linear radiance to display-referred [0, 1] linear RGB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// Clip to [0, 1] (Blender's "Standard").
    None,
    /// AgX (Troy Sobotka), Blender's default since 4.0, as the analytic fit of
    /// Benjamin Wrensch's "Minimal AgX".
    #[default]
    Agx,
    /// ACES RRT + ODT, Stephen Hill's fit.
    Aces,
    /// Khronos PBR Neutral: colours under the knee are left unchanged.
    PbrNeutral,
}

impl Tonemap {
    pub const ALL: [Tonemap; 4] = [
        Tonemap::None,
        Tonemap::Agx,
        Tonemap::Aces,
        Tonemap::PbrNeutral,
    ];

    /// The name in scene files and on the command line (`--tonemap`).
    pub fn key(self) -> &'static str {
        match self {
            Tonemap::None => "none",
            Tonemap::Agx => "agx",
            Tonemap::Aces => "aces",
            Tonemap::PbrNeutral => "pbr-neutral",
        }
    }

    /// The view transform named `key` ([`Tonemap::key`]).
    pub fn from_key(key: &str) -> Option<Tonemap> {
        Tonemap::ALL.into_iter().find(|t| t.key() == key)
    }

    /// The name the editor shows (Blender's, where Blender has it).
    pub fn label(self) -> &'static str {
        match self {
            Tonemap::None => "Standard",
            Tonemap::Agx => "AgX",
            Tonemap::Aces => "ACES",
            Tonemap::PbrNeutral => "Khronos PBR Neutral",
        }
    }

    /// The value of `DisplayParams::tonemap` in `shaders/editor/display.wgsl`.
    pub fn gpu_id(self) -> u32 {
        match self {
            Tonemap::None => 0,
            Tonemap::Agx => 1,
            Tonemap::Aces => 2,
            Tonemap::PbrNeutral => 3,
        }
    }
}

/// How the film becomes display values (ignored for EXR, which keeps scene-linear data).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewSettings {
    /// Stops (EV) applied before the view transform.
    pub exposure_ev: f32,
    pub tonemap: Tonemap,
}

impl ViewSettings {
    pub fn validate(&self) -> Result<(), String> {
        if self.exposure_ev.is_finite() && self.exposure_ev.abs() <= 64.0 {
            Ok(())
        } else {
            Err(format!(
                "exposure {} must be a finite number of stops within ±64",
                self.exposure_ev
            ))
        }
    }
}
