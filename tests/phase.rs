//! The Henyey–Greenstein phase function of `shaders/media/phase.wgsl`, run on the GPU:
//! its samples follow its density (chi-square against the exact probability of each cell),
//! the density it reports is the closed form, its mean cosine is g, and it stays finite
//! from g = -0.999 to 0.999.

mod common;

use std::f64::consts::PI;

use common::chi2::{SphereBins, chi2_test, histogram, sidak_alpha};
use common::run_test_kernel;
use glam::{DVec3, Vec3};

const SAMPLES: u32 = 1 << 18;
/// The whole suite's false-alarm rate.
const ALPHA: f64 = 0.01;
const G: [f32; 9] = [-0.99, -0.9, -0.5, -0.1, 0.0, 0.1, 0.5, 0.9, 0.99];

/// The density per steradian at cos θ, in f64.
fn hg(cos_theta: f64, g: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// The probability that cos θ ≤ x: the integral of 2π hg over [-1, x].
fn hg_cdf(x: f64, g: f64) -> f64 {
    if g.abs() < 1e-9 {
        return (x + 1.0) / 2.0;
    }
    (1.0 - g * g) / (2.0 * g) * (1.0 / (1.0 + g * g - 2.0 * g * x).sqrt() - 1.0 / (1.0 + g))
}

/// `SAMPLES` samples of each (g, direction): the sampled direction and the density the
/// shader reports for it.
fn sample(configs: &[(f32, Vec3)], seed: u32) -> Vec<Vec<(Vec3, f32)>> {
    let mut input = vec![[SAMPLES, seed, configs.len() as u32, 0]];
    for (g, d) in configs {
        input.push([g.to_bits(), d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]);
    }
    let total = SAMPLES * configs.len() as u32;
    let out = run_test_kernel(
        (
            "shaders/tests/phase_sample.wgsl",
            include_str!("../shaders/tests/phase_sample.wgsl"),
        ),
        "phase_sample",
        bytemuck::cast_slice(&input),
        16 * total as u64,
        total,
    );
    let v: &[[f32; 4]] = bytemuck::cast_slice(&out);
    v.chunks(SAMPLES as usize)
        .map(|c| {
            c.iter()
                .map(|s| (Vec3::new(s[0], s[1], s[2]), s[3]))
                .collect()
        })
        .collect()
}

#[test]
fn samples_follow_the_density_for_g_from_minus_to_plus_0_99() {
    // Propagation along +z: the cells' bands are bands of cos θ, whose exact probability
    // is the closed-form CDF's difference; sectors share it evenly (φ is uniform).
    let configs: Vec<(f32, Vec3)> = G.iter().map(|&g| (g, Vec3::Z)).collect();
    let bins = SphereBins::for_sample_count(SAMPLES as usize);
    let dz = 2.0 / bins.theta_bins as f64;
    let alpha = sidak_alpha(ALPHA, configs.len());
    for ((g, _), samples) in configs.iter().zip(sample(&configs, 7)) {
        let g = *g as f64;
        let dirs: Vec<Option<Vec3>> = samples.iter().map(|(w, _)| Some(*w)).collect();
        let observed = histogram(&bins, &dirs);
        let expected: Vec<f64> = (0..bins.cell_count())
            .map(|cell| {
                let band = cell / bins.phi_bins;
                let hi = 1.0 - band as f64 * dz;
                let lo = hi - dz;
                (hg_cdf(hi, g) - hg_cdf(lo, g)) / bins.phi_bins as f64
            })
            .collect();
        let outcome = chi2_test(&observed, &expected, SAMPLES as u64, 5.0);
        assert!(
            outcome.p_value >= alpha,
            "g = {g}: p = {} < {alpha}\n{}",
            outcome.p_value,
            outcome.report
        );
    }
}

#[test]
fn reported_density_is_the_closed_form_and_the_mean_cosine_is_g() {
    // Tilted directions check the frame the samples are turned into.
    let dirs = [
        Vec3::new(0.3, -0.5, 0.81).normalize(),
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let mut configs = Vec::new();
    for g in [-0.999, -0.5, 0.0, 0.7, 0.999] {
        for d in dirs {
            configs.push((g, d));
        }
    }
    for ((g, d), samples) in configs.iter().zip(sample(&configs, 11)) {
        let (g, d) = (*g as f64, d.as_dvec3());
        let mut sum = 0.0;
        for (wi, pdf) in &samples {
            let wi: DVec3 = wi.as_dvec3();
            assert!(
                wi.is_finite() && (wi.length() - 1.0).abs() < 1e-4,
                "g = {g}: sampled {wi}"
            );
            assert!(pdf.is_finite() && *pdf > 0.0, "g = {g}: density {pdf}");
            let cos = d.dot(wi).clamp(-1.0, 1.0);
            let exact = hg(cos, g);
            // The shader's cos θ is an f32 dot product, off by up to a few 1e-7: near the
            // peak of g → ±1 the density changes steeply with it (d ln p / d cos θ =
            // 3g / (1 + g² - 2g cos θ)), so the tolerance grows with that slope.
            let denom = 1.0 + g * g - 2.0 * g * cos;
            let slack = 1e-3 + 3.0 * g.abs() / denom * 5e-7;
            assert!(
                ((*pdf as f64) - exact).abs() <= slack * exact,
                "g = {g}, cos θ = {cos}: density {pdf}, closed form {exact}"
            );
            sum += cos;
        }
        let n = samples.len() as f64;
        let mean = sum / n;
        // The variance of cos θ is at most 1: five standard errors.
        assert!(
            (mean - g).abs() < 5.0 / n.sqrt(),
            "g = {g}, direction {d}: mean cosine {mean}"
        );
    }
}
