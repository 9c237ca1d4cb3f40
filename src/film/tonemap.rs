//! View transforms from scene-linear radiance to display-referred [0, 1] linear RGB, and
//! the sRGB encoding for 8-bit output: the CPU side of [`Tonemap`] (declared in the shader
//! contract, whose display pass implements the same curves).

use glam::{Mat3, Vec3};

pub use crate::shader::view::Tonemap;

impl Tonemap {
    pub fn apply(self, c: Vec3) -> Vec3 {
        let c = c.max(Vec3::ZERO);
        match self {
            Tonemap::None => c.min(Vec3::ONE),
            Tonemap::Agx => agx(c),
            Tonemap::Aces => aces(c),
            Tonemap::PbrNeutral => pbr_neutral(c),
        }
    }
}

fn agx(c: Vec3) -> Vec3 {
    const MIN_EV: f32 = -12.473_93;
    const MAX_EV: f32 = 4.026_069;
    let inset = Mat3::from_cols(
        Vec3::new(0.842_479_06, 0.042_328_242, 0.042_375_655),
        Vec3::new(0.078_433_6, 0.878_468_6, 0.078_433_6),
        Vec3::new(0.079_223_745, 0.079_166_13, 0.879_143),
    );
    let outset = Mat3::from_cols(
        Vec3::new(1.196_879, -0.052_896_85, -0.052_971_635),
        Vec3::new(-0.098_020_88, 1.151_903_1, -0.098_043_45),
        Vec3::new(-0.099_029_74, -0.098_961_18, 1.151_073_7),
    );
    let v = inset * c;
    let v = Vec3::new(
        v.x.max(1e-10).log2(),
        v.y.max(1e-10).log2(),
        v.z.max(1e-10).log2(),
    );
    let x = ((v - Vec3::splat(MIN_EV)) / (MAX_EV - MIN_EV)).clamp(Vec3::ZERO, Vec3::ONE);
    // 6th-order polynomial fit of the AgX base contrast curve.
    let x2 = x * x;
    let x4 = x2 * x2;
    let curve =
        15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
            - Vec3::splat(0.002_32);
    // The curve's output is display-encoded (2.2); return linear for the sRGB encoder.
    let display = (outset * curve).clamp(Vec3::ZERO, Vec3::ONE);
    Vec3::new(
        display.x.powf(2.2),
        display.y.powf(2.2),
        display.z.powf(2.2),
    )
}

fn aces(c: Vec3) -> Vec3 {
    let input = Mat3::from_cols(
        Vec3::new(0.597_19, 0.076_00, 0.028_40),
        Vec3::new(0.354_58, 0.908_34, 0.133_83),
        Vec3::new(0.048_23, 0.015_66, 0.837_77),
    );
    let output = Mat3::from_cols(
        Vec3::new(1.604_75, -0.102_08, -0.003_27),
        Vec3::new(-0.531_08, 1.108_13, -0.072_76),
        Vec3::new(-0.073_67, -0.006_05, 1.076_02),
    );
    let v = input * c;
    let fit = (v * (v + Vec3::splat(0.024_578_6)) - Vec3::splat(0.000_090_537))
        / (v * (0.983_729 * v + Vec3::splat(0.432_951)) + Vec3::splat(0.238_081));
    (output * fit).clamp(Vec3::ZERO, Vec3::ONE)
}

fn pbr_neutral(c: Vec3) -> Vec3 {
    const START_COMPRESSION: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let x = c.min_element();
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let c = c - Vec3::splat(offset);
    let peak = c.max_element();
    if peak < START_COMPRESSION {
        return c;
    }
    let d = 1.0 - START_COMPRESSION;
    let new_peak = 1.0 - d * d / (peak + d - START_COMPRESSION);
    let c = c * (new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    c.lerp(Vec3::splat(new_peak), g)
}

/// The sRGB transfer function (IEC 61966-2-1), linear [0, 1] to encoded [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Scene-linear radiance to an 8-bit sRGB triple: exposure (in stops), view transform,
/// encoding, rounding.
pub fn to_srgb8(c: Vec3, exposure_ev: f32, tonemap: Tonemap) -> [u8; 3] {
    let display = tonemap.apply(c * exposure_ev.exp2());
    // The exporters' quantization, so this matches their 8-bit PNGs.
    display
        .to_array()
        .map(|v| kiln_formats::image::quantize(srgb_encode(v), 255) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Tonemap; 4] = Tonemap::ALL;

    #[test]
    fn every_tonemap_is_monotonic_bounded_and_black_at_zero() {
        for t in ALL {
            let mut prev = -1.0f32;
            for i in 0..=400 {
                let v = 1e-4 * 1.05f32.powi(i);
                let out = t.apply(Vec3::splat(v));
                assert!(out.is_finite() && out.min_element() >= 0.0 && out.max_element() <= 1.0);
                let y = out.x;
                assert!(y >= prev - 1e-6, "{t:?} not monotonic at {v}: {y} < {prev}");
                prev = y;
            }
            assert!(
                t.apply(Vec3::ZERO).max_element() < 1e-3,
                "{t:?} lifts black"
            );
            assert!(
                t.apply(Vec3::splat(f32::MAX)).is_finite(),
                "{t:?} at f32::MAX"
            );
        }
    }

    #[test]
    fn pbr_neutral_leaves_mid_tones_unchanged_up_to_its_offset() {
        let c = Vec3::new(0.5, 0.3, 0.2);
        let out = Tonemap::PbrNeutral.apply(c);
        assert!((out - (c - Vec3::splat(0.04))).length() < 1e-6, "{out}");
    }

    /// The display-encoded (2.2) value AgX gives a grey input.
    fn agx_display(v: f32) -> Vec3 {
        let out = Tonemap::Agx.apply(Vec3::splat(v));
        Vec3::new(
            out.x.powf(1.0 / 2.2),
            out.y.powf(1.0 / 2.2),
            out.z.powf(1.0 / 2.2),
        )
    }

    #[test]
    fn agx_takes_its_published_values_at_middle_grey_and_the_ends_of_its_range() {
        // AgX's log encoding spans middle grey (0.18) -10 to +6.5 stops (Sobotka; Blender's
        // AgX base), so 0.18 sits at 10/16.5 of the curve, where Wrensch's published
        // polynomial (Minimal AgX) gives 0.4967: middle grey lands at half the display range.
        // The top of the range (0.18 · 2^6.5) reaches the curve's end, 0.9984; ten stops
        // under middle grey is black. Greys stay grey (the inset and outset rows sum to 1
        // within 2e-4).
        for (input, want) in [
            (0.18, 0.4967),
            (0.18 * 6.5f32.exp2(), 0.9984),
            (0.18 * (-10.0f32).exp2(), 0.0),
        ] {
            let got = agx_display(input);
            assert!(
                (got - Vec3::splat(want)).abs().max_element() < 2e-3,
                "AgX({input}) = {got}, published {want}"
            );
        }
    }

    #[test]
    fn aces_takes_its_published_values() {
        // Stephen Hill's fit of the ACES 1.0 RRT + sRGB ODT (BakingLab's ACES.hlsl): middle
        // grey 0.18 maps to 0.1056 display-linear (the reference ODT puts it at 4.8 of 48
        // nits, 0.10), 1.0 to 0.6191 and 16 to 0.9899. The input and output matrices keep
        // greys grey.
        for (input, want) in [(0.18, 0.105_59), (1.0, 0.619_12), (16.0, 0.989_93)] {
            let got = Tonemap::Aces.apply(Vec3::splat(input));
            assert!(
                (got - Vec3::splat(want)).abs().max_element() < 1e-3,
                "ACES({input}) = {got}, published {want}"
            );
        }
    }

    #[test]
    fn srgb_encoding_matches_reference_points() {
        assert_eq!(to_srgb8(Vec3::ZERO, 0.0, Tonemap::None), [0, 0, 0]);
        assert_eq!(to_srgb8(Vec3::ONE, 0.0, Tonemap::None), [255, 255, 255]);
        // 18% grey encodes to 118 (0.4613 * 255 = 117.6).
        assert_eq!(
            to_srgb8(Vec3::splat(0.18), 0.0, Tonemap::None),
            [118, 118, 118]
        );
        // One stop of exposure doubles the linear value.
        assert_eq!(
            to_srgb8(Vec3::splat(0.09), 1.0, Tonemap::None),
            [118, 118, 118]
        );
    }
}
