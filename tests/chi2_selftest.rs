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
const PASSING_TESTS: usize = 6;
/// The integral tolerance given to `chi2_conditional` here: the pdfs below are linear in
/// cos(theta) (or constant) over each cell, which the midpoint rule integrates exactly, so the
/// only error is rounding the quadrature directions to f32 (relative 2^-24 per value) and the
/// f64 sums; 1e-6 bounds both with a wide margin.
const EXACT_QUADRATURE_TOLERANCE: f64 = 1e-6;

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

/// The same, through `chi2_conditional`: the shape of the directions that landed where the
/// pdf is positive, and the samples that landed where it is 0.
fn run_chi2_conditional(dirs: &[Option<Vec3>], pdf: impl Fn(Vec3) -> f64) -> (Chi2Outcome, u64) {
    let bins = SphereBins::for_sample_count(dirs.len());
    let observed = histogram(&bins, dirs);
    let pdf_values: Vec<f64> = bins
        .all_quadrature(QUADRATURE_ORDER)
        .into_iter()
        .map(|(dir, _)| pdf(dir))
        .collect();
    let expected = bins.integrate(QUADRATURE_ORDER, &pdf_values);
    chi2_conditional(&observed, &expected, EXACT_QUADRATURE_TOLERANCE)
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
fn conditional_chi2_passes_correct_samplers_and_reports_the_raw_integral() {
    let (outcome, stray) = run_chi2_conditional(&cosine_samples(5), cosine_pdf);
    assert_passes(&outcome);
    assert_eq!(stray, 0, "{}", outcome.report);
    assert!(
        (outcome.pdf_integral - 1.0).abs() < EXACT_QUADRATURE_TOLERANCE,
        "{}",
        outcome.report
    );
    assert!(outcome.degrees_of_freedom > 1000, "{}", outcome.report);
    // Absorption is the caller's to check: the shape alone passes, and the integral (0.7, not
    // the normalised 1) is there for the caller to compare with the absorbed fraction.
    let (outcome, stray) =
        run_chi2_conditional(&absorbing_cosine_samples(6), |d| 0.7 * cosine_pdf(d));
    assert_passes(&outcome);
    assert_eq!(stray, 0, "{}", outcome.report);
    assert!(
        (outcome.pdf_integral - 0.7).abs() < EXACT_QUADRATURE_TOLERANCE,
        "{}",
        outcome.report
    );
}

#[test]
fn conditional_chi2_rejects_a_pdf_that_integrates_above_one() {
    // Normalised, these pdfs have exactly the samples' shape; only the integral check can
    // tell that they claim more than every sample there is.
    let dirs = cosine_samples(7);
    for scale in [1.03, 2.0] {
        let (outcome, _) = run_chi2_conditional(&dirs, |d| scale * cosine_pdf(d));
        assert_eq!(outcome.p_value, 0.0, "scale {scale}: {}", outcome.report);
        assert!(
            outcome.report.contains("integrates to"),
            "scale {scale}: {}",
            outcome.report
        );
        assert!(
            (outcome.pdf_integral - scale).abs() < EXACT_QUADRATURE_TOLERANCE * scale,
            "scale {scale}: {}",
            outcome.report
        );
    }
    // Just inside the tolerance it is the shape that decides, and the shape is right.
    let scale = 1.0 + EXACT_QUADRATURE_TOLERANCE / 2.0;
    let (outcome, _) = run_chi2_conditional(&dirs, |d| scale * cosine_pdf(d));
    assert_passes(&outcome);
}

#[test]
fn conditional_chi2_rejects_a_sampler_three_percent_off() {
    // 3% of the samples come from the uniform hemisphere instead of the cosine lobe the pdf
    // claims. The expected excess of the statistic over its degrees of freedom is n times the
    // chi-square divergence of the binned distributions, 0.03^2 * (sum_cells u^2 / c - 1): per
    // band of width dz = 1/36 that sum is dz / (2 z_mid), 2.77 over the 36 bands (it grows
    // like ln(bands) / 2 from the horizon), so the excess is ~1600 on ~5200 degrees of freedom
    // whose standard deviation is ~100: 16 sigma (this seed gives 7094, 19 sigma, p 4e-64).
    // The seed is fixed, so the outcome is deterministic; the margin makes it no accident.
    let mut rng = SplitMix64(8);
    let dirs: Vec<Option<Vec3>> = (0..SAMPLE_COUNT)
        .map(|_| {
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            Some(if rng.next_f64() < 0.03 {
                // Uniform over the upper hemisphere: z = 1 - u1 in (0, 1].
                sample_uniform_sphere(u1 / 2.0, u2)
            } else {
                sample_cosine(u1, u2)
            })
        })
        .collect();
    let (outcome, stray) = run_chi2_conditional(&dirs, cosine_pdf);
    assert_eq!(stray, 0, "{}", outcome.report);
    let dof = outcome.degrees_of_freedom as f64;
    let sigmas = (outcome.statistic - dof) / (2.0 * dof).sqrt();
    assert!(
        outcome.p_value < 1e-12 && sigmas > 5.0,
        "{sigmas:.1} sigma: {}",
        outcome.report
    );
}

#[test]
fn conditional_chi2_counts_samples_where_the_pdf_is_zero() {
    // One sample in a thousand leaks into the lower hemisphere, where the pdf is 0: the
    // conditional test leaves them out of the shape and returns their count.
    let mut rng = SplitMix64(4);
    let mut leaked = 0;
    let dirs: Vec<Option<Vec3>> = (0..SAMPLE_COUNT)
        .map(|_| {
            let d = sample_cosine(rng.next_f64(), rng.next_f64());
            let leak = rng.next_f64() < 1e-3;
            leaked += leak as u64;
            Some(if leak { -d } else { d })
        })
        .collect();
    assert!(leaked > 0);
    let (_, stray) = run_chi2_conditional(&dirs, cosine_pdf);
    assert_eq!(stray, leaked);
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
fn leftover_pool_without_a_group_stands_alone_and_shows_its_excess() {
    // 1 + 2 pooled reach only 3 < 5 and no group forms: the leftover is a category of its
    // own. With exact counts the statistic is 0 and there are three categories.
    let probabilities = [1.0, 2.0, 509.0, 512.0].map(|c| c / 1024.0);
    let outcome = chi2_test(&[1, 2, 509, 512], &probabilities, 1024, MIN_EXPECTED);
    assert_eq!(outcome.pooled_cells, 2, "{}", outcome.report);
    assert_eq!(outcome.degrees_of_freedom, 2, "{}", outcome.report);
    assert!(outcome.statistic.abs() < 1e-9, "{}", outcome.report);
    // 40 samples where 3 are expected, offset by a 1.6 sigma deficit in the 509 cell: merged
    // into that large cell (512 vs 512) the excess would vanish. Alone it contributes
    // (40 - 3)^2 / 3 = 456.3, and the 509 cell (472 - 509)^2 / 509 = 2.7.
    let observed = [20, 20, 472, 512];
    let outcome = chi2_test(&observed, &probabilities, 1024, MIN_EXPECTED);
    let want = 37.0f64.powi(2) / 3.0 + 37.0f64.powi(2) / 509.0;
    assert!(
        (outcome.statistic - want).abs() < 1e-9,
        "statistic {} instead of {want}:\n{}",
        outcome.statistic,
        outcome.report
    );
    assert!(outcome.p_value < 1e-6, "{}", outcome.report);
}

#[test]
fn leftover_pool_joins_the_smallest_group_and_shows_its_excess() {
    // Sorted expectations 1, 2, 3 | 4, 4 | 4 | 1006: 1 + 2 + 3 = 6 closes group A, 4 + 4 = 8
    // group B, and the last 4 (below the threshold) is left over. It joins the smallest group,
    // A (6 + 4 = 10), not B nor the large category.
    let probabilities = [1.0, 2.0, 3.0, 4.0, 4.0, 4.0, 1006.0].map(|c| c / 1024.0);
    let exact = [1, 2, 3, 4, 4, 4, 1006];
    let outcome = chi2_test(&exact, &probabilities, 1024, MIN_EXPECTED);
    assert_eq!(outcome.pooled_cells, 6, "{}", outcome.report);
    // Categories: A with the leftover, B, and the large cell.
    assert_eq!(outcome.degrees_of_freedom, 2, "{}", outcome.report);
    assert!(outcome.statistic.abs() < 1e-9, "{}", outcome.report);
    assert!(
        outcome.report.contains("merged into the smallest group"),
        "{}",
        outcome.report
    );
    // 40 samples where 4 are expected (the leftover is the last cell of expectation 4, sorting
    // being stable), the surplus taken from the large cell: A holds 46 against 10, so the
    // statistic is 36^2 / 10 + 36^2 / 1006 = 130.9 (merged into B it would be 36^2 / 12 + ...,
    // into the large cell 0).
    let mut observed = exact;
    observed[5] = 40;
    observed[6] = 1006 - 36;
    let outcome = chi2_test(&observed, &probabilities, 1024, MIN_EXPECTED);
    let want = 36.0f64.powi(2) / 10.0 + 36.0f64.powi(2) / 1006.0;
    assert!(
        (outcome.statistic - want).abs() < 1e-9,
        "statistic {} instead of {want}:\n{}",
        outcome.statistic,
        outcome.report
    );
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
