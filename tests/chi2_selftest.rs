//! Tests of the chi-square harness itself, on the CPU: known-good samplers must pass, known-bad
//! pdfs must fail, and the binning, quadrature and p-value arithmetic must be right.

mod common;

use std::f64::consts::{PI, TAU};

use common::chi2::*;
use glam::Vec3;

const SAMPLE_COUNT: usize = 1_000_000;
const QUADRATURE_ORDER: usize = 4;
const MIN_EXPECTED: f64 = 5.0;
/// Chi-square tests in this file that are expected to pass; the Šidák correction spreads the
/// suite's 1% false-positive budget over them.
const PASSING_TESTS: usize = 3;

/// SplitMix64: tiny, deterministic and good enough to drive samplers in a test.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Cosine-weighted direction about +Z (Malley's method: uniform disk, projected up).
fn sample_cosine(u1: f64, u2: f64) -> Vec3 {
    let r = u1.sqrt();
    let phi = TAU * u2;
    // 1 - u1 >= 2^-53, so z > 0 and no sample lands on the equator.
    Vec3::new(
        (r * phi.cos()) as f32,
        (r * phi.sin()) as f32,
        (1.0 - u1).sqrt() as f32,
    )
}

fn sample_uniform_sphere(u1: f64, u2: f64) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u2;
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}

fn cosine_samples(seed: u64) -> Vec<Option<Vec3>> {
    let mut rng = SplitMix64(seed);
    (0..SAMPLE_COUNT)
        .map(|_| Some(sample_cosine(rng.next_f64(), rng.next_f64())))
        .collect()
}

/// Cosine lobe that absorbs 30% of samples, decided by a third, independent variate.
fn absorbing_cosine_samples(seed: u64) -> Vec<Option<Vec3>> {
    let mut rng = SplitMix64(seed);
    (0..SAMPLE_COUNT)
        .map(|_| {
            let dir = sample_cosine(rng.next_f64(), rng.next_f64());
            (rng.next_f64() >= 0.3).then_some(dir)
        })
        .collect()
}

fn cosine_pdf(dir: Vec3) -> f64 {
    f64::from(dir.z).max(0.0) / PI
}

fn uniform_hemisphere_pdf(dir: Vec3) -> f64 {
    if dir.z > 0.0 { 1.0 / TAU } else { 0.0 }
}

/// Bins the samples, integrates the pdf over the same bins and runs the test.
fn run_chi2(dirs: &[Option<Vec3>], pdf: impl Fn(Vec3) -> f64) -> Chi2Outcome {
    let bins = SphereBins::for_sample_count(dirs.len());
    let observed = histogram(&bins, dirs);
    let pdf_values: Vec<f64> = bins
        .all_quadrature(QUADRATURE_ORDER)
        .into_iter()
        .map(|(dir, _)| pdf(dir))
        .collect();
    let expected = bins.integrate(QUADRATURE_ORDER, &pdf_values);
    chi2_test(&observed, &expected, dirs.len() as u64, MIN_EXPECTED)
}

fn assert_passes(outcome: &Chi2Outcome) {
    let alpha = sidak_alpha(0.01, PASSING_TESTS);
    assert!(
        outcome.p_value > alpha,
        "rejected at significance {alpha:.2e}:\n{}",
        outcome.report
    );
}

#[test]
fn cosine_sampler_passes_against_its_pdf() {
    let outcome = run_chi2(&cosine_samples(1), cosine_pdf);
    assert_passes(&outcome);
    assert!(
        (outcome.pdf_integral - 1.0).abs() < 1e-3,
        "{}",
        outcome.report
    );
    // The resolution must be fine enough for the test to mean something.
    assert!(outcome.degrees_of_freedom > 1000, "{}", outcome.report);
}

#[test]
fn cosine_samples_fail_against_uniform_hemisphere_pdf() {
    let outcome = run_chi2(&cosine_samples(1), uniform_hemisphere_pdf);
    assert!(outcome.p_value < 1e-6, "{}", outcome.report);
}

#[test]
fn absorbing_sampler_passes_against_pdf_scaled_by_survival() {
    let outcome = run_chi2(&absorbing_cosine_samples(2), |d| 0.7 * cosine_pdf(d));
    assert_passes(&outcome);
    assert!(
        (outcome.pdf_integral - 0.7).abs() < 1e-3,
        "{}",
        outcome.report
    );
}

#[test]
fn absorbing_sampler_fails_against_unscaled_pdf() {
    // Per cell the shape still matches; only the absorbed category can tell the difference.
    let outcome = run_chi2(&absorbing_cosine_samples(2), cosine_pdf);
    assert!(outcome.p_value < 1e-6, "{}", outcome.report);
}

#[test]
fn uniform_sphere_sampler_passes_against_constant_pdf() {
    let mut rng = SplitMix64(3);
    let dirs: Vec<Option<Vec3>> = (0..SAMPLE_COUNT)
        .map(|_| Some(sample_uniform_sphere(rng.next_f64(), rng.next_f64())))
        .collect();
    let outcome = run_chi2(&dirs, |_| 1.0 / (4.0 * PI));
    assert_passes(&outcome);
    assert!(
        (outcome.pdf_integral - 1.0).abs() < 1e-3,
        "{}",
        outcome.report
    );
}

#[test]
fn samples_where_pdf_is_zero_fail_loudly() {
    // A lobe that leaks into the lower hemisphere, tested against a pdf that says it cannot.
    let mut rng = SplitMix64(4);
    let dirs: Vec<Option<Vec3>> = (0..SAMPLE_COUNT)
        .map(|_| {
            let d = sample_cosine(rng.next_f64(), rng.next_f64());
            Some(if rng.next_f64() < 1e-3 { -d } else { d })
        })
        .collect();
    let outcome = run_chi2(&dirs, cosine_pdf);
    assert_eq!(outcome.p_value, 0.0, "{}", outcome.report);
    assert!(
        outcome.report.contains("where the pdf expects none"),
        "{}",
        outcome.report
    );
}

#[test]
fn quadrature_weights_sum_to_cell_solid_angle() {
    let bins = SphereBins {
        theta_bins: 10,
        phi_bins: 20,
    };
    let solid_angle = 4.0 * PI / bins.cell_count() as f64;
    for cell in 0..bins.cell_count() {
        let points = bins.quadrature(cell, 3);
        assert_eq!(points.len(), 9);
        let total: f64 = points.iter().map(|&(_, w)| w).sum();
        assert!(
            (total - solid_angle).abs() < 1e-9,
            "cell {cell}: {total} vs {solid_angle}"
        );
    }
}

#[test]
fn quadrature_points_are_unit_directions_inside_their_cell() {
    let bins = SphereBins {
        theta_bins: 12,
        phi_bins: 24,
    };
    for cell in 0..bins.cell_count() {
        for (dir, _) in bins.quadrature(cell, 4) {
            assert!((dir.length() - 1.0).abs() < 1e-6, "{dir:?}");
            assert_eq!(bins.cell(dir), Some(cell), "{dir:?}");
        }
    }
}

#[test]
fn constant_pdf_integrates_to_equal_cell_probabilities() {
    let bins = SphereBins::for_sample_count(SAMPLE_COUNT);
    let k = 3;
    let points = bins.all_quadrature(k);
    assert_eq!(points.len(), bins.cell_count() * k * k);
    let pdf_values = vec![1.0 / (4.0 * PI); points.len()];
    let probabilities = bins.integrate(k, &pdf_values);
    assert_eq!(probabilities.len(), bins.cell_count());
    let expected = 1.0 / bins.cell_count() as f64;
    for (cell, &p) in probabilities.iter().enumerate() {
        assert!(
            (p - expected).abs() < 1e-12,
            "cell {cell}: {p} vs {expected}"
        );
    }
}

#[test]
fn cell_lookup_handles_poles_equator_and_invalid_directions() {
    let bins = SphereBins {
        theta_bins: 8,
        phi_bins: 16,
    };
    assert_eq!(bins.cell(Vec3::Z), Some(0));
    assert_eq!(bins.cell(Vec3::NEG_Z), Some(7 * 16));
    // The equator belongs to the upper hemisphere; phi = 0 starts sector 0.
    assert_eq!(bins.cell(Vec3::X), Some(3 * 16));
    // Not normalized: only the direction matters.
    assert_eq!(bins.cell(Vec3::new(0.0, 5.0, 0.0)), Some(3 * 16 + 4));
    assert_eq!(bins.cell(Vec3::new(0.0, -1.0, -1e-3)), Some(4 * 16 + 12));
    assert_eq!(bins.cell(Vec3::ZERO), None);
    assert_eq!(bins.cell(Vec3::new(f32::NAN, 0.0, 1.0)), None);
    assert_eq!(bins.cell(Vec3::new(f32::INFINITY, 0.0, 1.0)), None);
}

#[test]
fn adaptive_resolution_has_even_bands_and_plenty_of_samples_per_cell() {
    for n in [1_000, 100_000, 1_000_000, 10_000_000, 10_000_000_000] {
        let bins = SphereBins::for_sample_count(n);
        assert_eq!(bins.theta_bins % 2, 0, "{bins:?}");
        assert_eq!(bins.phi_bins, 2 * bins.theta_bins, "{bins:?}");
        assert!(bins.theta_bins >= 8, "{bins:?}");
        let per_cell = n as f64 / bins.cell_count() as f64;
        if n >= 100_000 {
            assert!(per_cell >= 50.0, "{n}: {bins:?}");
        }
        // Below the resolution cap, cells should not be needlessly coarse either.
        if bins.theta_bins < 256 {
            assert!(per_cell < 400.0, "{n}: {bins:?}");
        }
    }
}

#[test]
fn exact_counts_give_zero_statistic_and_pool_small_cells() {
    // Expected counts 1, 2, 3 are pooled into one category of 6; 506 and 512 stand alone.
    // Dyadic probabilities sum to exactly 1, so the absorbed category is exactly empty.
    let probabilities = [1.0, 2.0, 3.0, 506.0, 512.0].map(|c| c / 1024.0);
    let observed = [1, 2, 3, 506, 512];
    let outcome = chi2_test(&observed, &probabilities, 1024, MIN_EXPECTED);
    assert_eq!(outcome.pooled_cells, 3, "{}", outcome.report);
    assert_eq!(outcome.degrees_of_freedom, 2, "{}", outcome.report);
    assert!(outcome.statistic.abs() < 1e-9, "{}", outcome.report);
    assert!((outcome.p_value - 1.0).abs() < 1e-9, "{}", outcome.report);
}

#[test]
fn leftover_pool_below_threshold_is_merged_not_dropped() {
    // 1 + 2 pooled reach only 3 < 5: the leftover joins the smallest regular category, so the
    // samples in those cells still count against the fit.
    let probabilities = [1.0, 2.0, 509.0, 512.0].map(|c| c / 1024.0);
    let observed = [20, 20, 472, 512];
    let outcome = chi2_test(&observed, &probabilities, 1024, MIN_EXPECTED);
    assert_eq!(outcome.pooled_cells, 2, "{}", outcome.report);
    assert_eq!(outcome.degrees_of_freedom, 1, "{}", outcome.report);
    // Categories (20 + 20 + 472 vs 1 + 2 + 509) and (512 vs 512): statistic 0.
    assert!(outcome.statistic.abs() < 1e-9, "{}", outcome.report);
    // 60 samples where 3 are expected: dropping the leftover (as Mitsuba does) would ignore
    // them and leave weak evidence (statistic ~10 on 1 dof from the other cells); merged into
    // the absorbed category (4 observed, 12 expected) they dominate the statistic.
    let probabilities = [1.0, 2.0, 509.0, 500.0].map(|c| c / 1024.0);
    let observed = [30, 30, 460, 500];
    let outcome = chi2_test(&observed, &probabilities, 1024, MIN_EXPECTED);
    assert!(outcome.statistic > 150.0, "{}", outcome.report);
    assert!(outcome.p_value < 1e-6, "{}", outcome.report);
}

#[test]
fn absorbed_category_counts_missing_samples() {
    // Half the samples are missing from the cells, and the pdf accounts for exactly that.
    let probabilities = [0.25, 0.25];
    let outcome = chi2_test(&[250, 250], &probabilities, 1000, MIN_EXPECTED);
    assert_eq!(outcome.degrees_of_freedom, 2, "{}", outcome.report);
    assert!(outcome.statistic.abs() < 1e-9, "{}", outcome.report);
    assert!((outcome.pdf_integral - 0.5).abs() < 1e-12);
    // The same counts against a pdf that claims no absorption: samples in a zero category.
    let outcome = chi2_test(&[250, 250], &[0.5, 0.5], 1000, MIN_EXPECTED);
    assert_eq!(outcome.p_value, 0.0, "{}", outcome.report);
}

#[test]
fn invalid_pdf_values_fail_loudly() {
    let outcome = chi2_test(&[500, 500], &[0.5, f64::NAN], 1000, MIN_EXPECTED);
    assert_eq!(outcome.p_value, 0.0, "{}", outcome.report);
    assert!(outcome.report.contains("non-finite"), "{}", outcome.report);
    let outcome = chi2_test(&[500, 500], &[0.9, 0.9], 1000, MIN_EXPECTED);
    assert_eq!(outcome.p_value, 0.0, "{}", outcome.report);
    assert!(
        outcome.report.contains("integrates to"),
        "{}",
        outcome.report
    );
}

/// Q(k/2, x/2) for even k in closed form: e^(-x/2) * sum_{i < k/2} (x/2)^i / i!, summed in log
/// space so it stays finite for thousands of degrees of freedom.
fn chi2_survival_even_dof(x: f64, dof: usize) -> f64 {
    let y = x / 2.0;
    let mut log_factorial = 0.0;
    let mut total = 0.0;
    for i in 0..dof / 2 {
        if i > 0 {
            log_factorial += (i as f64).ln();
        }
        total += (i as f64 * y.ln() - y - log_factorial).exp();
    }
    total
}

#[test]
fn chi2_survival_matches_closed_form_for_even_dof() {
    for (dof, x) in [
        (2, 0.5),
        (2, 30.0),
        (4, 3.0),
        (10, 5.0),
        (10, 40.0),
        (200, 180.0),
        (200, 260.0),
        (10_000, 9_800.0),
        (10_000, 10_300.0),
        (10_000, 12_000.0),
    ] {
        let got = chi2_survival(x, dof);
        let want = chi2_survival_even_dof(x, dof);
        assert!(
            (got - want).abs() <= 1e-9 * want.max(1e-300) + 1e-14,
            "dof {dof}, x {x}: {got} vs {want}"
        );
    }
    // Odd dof: Q(1/2, x/2) = erfc(sqrt(x/2)); erfc(1) = 0.157299207050285...
    let got = chi2_survival(2.0, 1);
    assert!((got - 0.157_299_207_050_285_1).abs() < 1e-12, "{got}");
}

#[test]
fn sidak_alpha_is_alpha_for_one_test_and_shrinks_with_more() {
    assert_eq!(sidak_alpha(0.01, 1), 0.01);
    let mut previous = 0.01;
    for count in [2, 10, 100, 10_000] {
        let alpha = sidak_alpha(0.01, count);
        assert!(alpha < previous, "{count}: {alpha} !< {previous}");
        // Šidák is slightly less conservative than Bonferroni's alpha / count.
        assert!(alpha > 0.01 / count as f64, "{count}: {alpha}");
        // And the corrected level really gives the suite its false-positive rate.
        let suite = 1.0 - (1.0 - alpha).powi(count as i32);
        assert!((suite - 0.01).abs() < 1e-12, "{count}: {suite}");
        previous = alpha;
    }
}
