//! Chi-square goodness-of-fit harness for direction-sampling routines.
//!
//! A sampler (a BSDF's `sample`, a light's direction sampling, ...) and the pdf it claims to
//! follow must agree, or every estimator that divides by that pdf is biased. This module tests
//! that agreement statistically, in the manner of Mitsuba 3's `chi2.py`:
//!
//! 1. bin many sampled directions into cells of equal solid angle on the unit sphere
//!    ([`SphereBins`], [`histogram`]);
//! 2. integrate the claimed pdf over every cell numerically ([`SphereBins::all_quadrature`],
//!    [`SphereBins::integrate`]) to get the probability the sampler should put in each cell;
//! 3. run Pearson's chi-square test of the counts against those probabilities ([`chi2_test`]),
//!    pooling cells whose expected count is too small for the chi-square approximation, and
//!    compare the p-value against a significance level corrected for the number of tests in
//!    the suite ([`sidak_alpha`]).
//!
//! Samples that produce no direction (absorbed, or rejected by the sampler) are part of the test:
//! they form one extra category whose expected probability is whatever the integrated pdf leaves
//! over, so a lobe that samples a fraction of the time must report a pdf scaled by that fraction.
//!
//! What this is not: it does not sample anything or evaluate any pdf itself (the caller does that,
//! on the CPU or in a GPU kernel, so the harness is independent of how the code under test runs);
//! it does not check sample *weights* (BSDF value * cos / pdf), only the distribution of
//! directions; and it is a statistical test, so a deliberately tiny significance level is what
//! keeps it from failing by chance, not determinism. The numerical integration uses a midpoint
//! rule, which is exact for pdfs linear in cos(theta) but only approximate for sharply peaked
//! lobes: check [`Chi2Outcome::pdf_integral`] and raise the quadrature order if it drifts.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

use glam::Vec3;

/// Average number of samples the adaptive resolution aims to put in each cell. Mitsuba's default
/// (about 200 per cell for 10^6 samples) is coarser; around 100 keeps the chi-square
/// approximation sound in all but the dimmest cells (which are pooled) while resolving narrow
/// features such as grazing-angle errors.
const TARGET_SAMPLES_PER_CELL: f64 = 100.0;

/// Binning of the unit sphere into cells of equal solid angle: `theta_bins` bands uniform in
/// cos(theta) over [-1, 1] and `phi_bins` sectors uniform in phi over [0, 2*pi). theta is measured
/// from +Z.
///
/// Cell `c` is band `c / phi_bins` (band 0 touches +Z) and sector `c % phi_bins` (sector 0 starts
/// at +X and phi grows towards +Y). Bands are closed on the side towards +Z, so a direction exactly
/// on the equator counts in the upper hemisphere, which is where reflection lobes put grazing
/// samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SphereBins {
    pub theta_bins: usize,
    pub phi_bins: usize,
}

impl SphereBins {
    /// Resolution adapted to the sample count so the average cell expects plenty of samples
    /// (about [`TARGET_SAMPLES_PER_CELL`]); `phi_bins = 2 * theta_bins` keeps cells roughly square
    /// near the equator. `theta_bins` is even so the equator is a band edge: hemispherical lobes
    /// then have no cell straddling their discontinuity, and the midpoint rule stays exact there.
    pub fn for_sample_count(n: usize) -> Self {
        let theta = (n as f64 / (2.0 * TARGET_SAMPLES_PER_CELL)).sqrt().round() as usize;
        // The upper clamp bounds the quadrature work (2 * 256^2 cells) for huge sample counts.
        let theta = (theta + theta % 2).clamp(8, 256);
        Self {
            theta_bins: theta,
            phi_bins: 2 * theta,
        }
    }

    pub fn cell_count(&self) -> usize {
        self.theta_bins * self.phi_bins
    }

    /// Width of a band in cos(theta).
    fn dz(&self) -> f64 {
        2.0 / self.theta_bins as f64
    }

    /// Width of a sector in phi.
    fn dphi(&self) -> f64 {
        TAU / self.phi_bins as f64
    }

    /// Cell of a direction; None for non-finite or zero-length vectors (normalize internally).
    pub fn cell(&self, dir: Vec3) -> Option<usize> {
        // f64 so that directions within an f32 ulp of a cell edge land on a consistent side.
        let d = dir.as_dvec3();
        if !d.is_finite() {
            return None;
        }
        let len = d.length();
        if len <= 0.0 || !len.is_finite() {
            return None;
        }
        let d = d / len;
        let z = d.z.clamp(-1.0, 1.0);
        // ceil - 1 makes each band closed towards +Z (see the type's docs); `as usize` saturates
        // the -1 that z = 1 would give, and min() catches rounding past the last band.
        let band = ((1.0 - z) / self.dz()).ceil() as usize;
        let band = band.saturating_sub(1).min(self.theta_bins - 1);
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let sector = ((phi / self.dphi()).floor() as usize).min(self.phi_bins - 1);
        Some(band * self.phi_bins + sector)
    }

    /// `k*k` quadrature points (midpoint rule in (cos theta, phi)) of a cell, as unit directions,
    /// each with its solid-angle weight; the weights of one cell sum to the cell's solid angle
    /// 4*pi/cell_count.
    pub fn quadrature(&self, cell: usize, k: usize) -> Vec<(Vec3, f64)> {
        assert!(cell < self.cell_count(), "cell {cell} out of range");
        assert!(k > 0, "quadrature order must be positive");
        let (dz, dphi) = (self.dz(), self.dphi());
        let band = cell / self.phi_bins;
        let sector = cell % self.phi_bins;
        let z_top = 1.0 - band as f64 * dz;
        let phi_start = sector as f64 * dphi;
        // Solid angle is dz * dphi in these coordinates, so every point weighs the same.
        let weight = dz * dphi / (k * k) as f64;
        let mut points = Vec::with_capacity(k * k);
        for i in 0..k {
            let z = z_top - (i as f64 + 0.5) * dz / k as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..k {
                let phi = phi_start + (j as f64 + 0.5) * dphi / k as f64;
                let dir = glam::DVec3::new(r * phi.cos(), r * phi.sin(), z);
                points.push((dir.as_vec3(), weight));
            }
        }
        points
    }

    /// All cells' quadrature points concatenated, cell-major (so a GPU kernel can evaluate a pdf
    /// at all of them in one pass).
    pub fn all_quadrature(&self, k: usize) -> Vec<(Vec3, f64)> {
        (0..self.cell_count())
            .flat_map(|cell| self.quadrature(cell, k))
            .collect()
    }

    /// Integrates pdf values given for `all_quadrature(k)` (same order) into expected probability
    /// per cell.
    pub fn integrate(&self, k: usize, pdf_values: &[f64]) -> Vec<f64> {
        assert!(k > 0, "quadrature order must be positive");
        let per_cell = k * k;
        assert_eq!(
            pdf_values.len(),
            self.cell_count() * per_cell,
            "expected one pdf value per point of all_quadrature({k})"
        );
        // The same weight quadrature() gives every point.
        let weight = self.dz() * self.dphi() / per_cell as f64;
        pdf_values
            .chunks_exact(per_cell)
            .map(|values| values.iter().sum::<f64>() * weight)
            .collect()
    }
}

/// Histogram of sampled directions into the bins (None directions = absorbed, not counted).
///
/// Panics on a `Some` direction that has no cell (non-finite or zero length): that is a bug in
/// the sampler, and silently counting it as absorbed would hide it.
pub fn histogram(bins: &SphereBins, dirs: &[Option<Vec3>]) -> Vec<u64> {
    let mut counts = vec![0u64; bins.cell_count()];
    for (i, dir) in dirs.iter().enumerate() {
        if let Some(dir) = *dir {
            let cell = bins.cell(dir).unwrap_or_else(|| {
                panic!("sample {i} is an invalid direction {dir:?} (non-finite or zero length)")
            });
            counts[cell] += 1;
        }
    }
    counts
}

/// The significance level for one of `test_count` tests when the whole suite should have a
/// false-positive rate of `alpha` (Šidák correction): 1 - (1 - alpha)^(1/test_count).
pub fn sidak_alpha(alpha: f64, test_count: usize) -> f64 {
    assert!(test_count > 0, "need at least one test");
    assert!((0.0..=1.0).contains(&alpha), "alpha must be a probability");
    if test_count == 1 {
        // Exactly alpha, which the general expression only approximates in floating point.
        return alpha;
    }
    // -expm1(ln_1p(-alpha) / n) is the same expression without cancellation when alpha is tiny.
    -((-alpha).ln_1p() / test_count as f64).exp_m1()
}

pub struct Chi2Outcome {
    pub statistic: f64,
    pub degrees_of_freedom: usize,
    pub p_value: f64,
    /// Cells pooled because their expected count was below the threshold.
    pub pooled_cells: usize,
    /// Total probability the integrated pdf assigns to the sphere (should be ~1, or the lobe's
    /// sampled fraction when samples can be absorbed).
    pub pdf_integral: f64,
    /// Human-readable summary with the worst cells (observed vs expected), for assertion messages.
    pub report: String,
}

/// Where a chi-square category's counts come from.
#[derive(Clone, Copy, Debug)]
enum Source {
    Cell(usize),
    /// Samples that produced no direction.
    Absorbed,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Source::Cell(c) => write!(f, "cell {c}"),
            Source::Absorbed => write!(f, "absorbed"),
        }
    }
}

/// One term of the statistic: a single category, or several pooled ones.
struct Term {
    sources: Vec<Source>,
    observed: f64,
    expected: f64,
}

impl Term {
    fn empty() -> Self {
        Self {
            sources: Vec::new(),
            observed: 0.0,
            expected: 0.0,
        }
    }

    fn contribution(&self) -> f64 {
        let diff = self.observed - self.expected;
        diff * diff / self.expected
    }

    fn label(&self) -> String {
        match self.sources.as_slice() {
            [one] => one.to_string(),
            many => {
                let shown: Vec<String> = many.iter().take(4).map(Source::to_string).collect();
                let more = if many.len() > 4 { ", ..." } else { "" };
                format!("{} pooled ({}{more})", many.len(), shown.join(", "))
            }
        }
    }
}

/// Pearson's chi-square test of `observed` counts per cell against `expected_probability` per
/// cell times `sample_count`.
///
/// `sample_count` includes samples that produced no direction; those are in no cell, so they form
/// one extra "absorbed" category whose observed count is `sample_count - sum(observed)` and whose
/// expected probability is `1 - sum(expected_probability)`, clamped at 0.
///
/// Categories whose expected count is below `min_expected` (5 is customary) are pooled among
/// themselves: sorted by expected count, consecutive ones are merged until the merged expectation
/// reaches the threshold, and each such group becomes one category. Mitsuba drops the last group
/// if it never reaches the threshold, which ignores its observed counts however large; merging
/// it into a large category would hide them as surely (an excess there is offset by a
/// fluctuation of the large category). Here the leftover joins the *smallest* pooled group, or,
/// when no group formed, stays a category of its own. That keeps an excess visible, provably: a
/// group closes as soon as it reaches the threshold and each member is below it, so a group
/// expects less than 2 * `min_expected`, and a leftover merged into one less than
/// 3 * `min_expected`; observed counts are never negative, so an excess of D samples over the
/// leftover's expectation adds at least (D - 2 * min_expected)^2 / (3 * min_expected) to the
/// statistic (at least D^2 / min_expected when it stands alone). Degrees of freedom =
/// categories kept - 1.
///
/// The test fails loudly (p_value = 0, reason in the report) when a category has observed > 0
/// where expected is exactly 0, when an expected probability is negative or non-finite, when the
/// cells hold more samples than `sample_count`, when the pdf integrates to more than 1.1 (as in
/// Mitsuba), or when fewer than two categories remain.
pub fn chi2_test(
    observed: &[u64],
    expected_probability: &[f64],
    sample_count: u64,
    min_expected: f64,
) -> Chi2Outcome {
    assert_eq!(
        observed.len(),
        expected_probability.len(),
        "observed and expected must have one entry per cell"
    );
    let n = sample_count as f64;
    let in_cells: u64 = observed.iter().sum();
    let pdf_integral: f64 = expected_probability.iter().sum();
    let mut problems: Vec<String> = Vec::new();

    let invalid: Vec<usize> = (0..expected_probability.len())
        .filter(|&i| !(expected_probability[i].is_finite() && expected_probability[i] >= 0.0))
        .collect();
    if !invalid.is_empty() {
        let first: Vec<String> = invalid
            .iter()
            .take(8)
            .map(|&i| format!("cell {i} = {}", expected_probability[i]))
            .collect();
        problems.push(format!(
            "{} cells have a negative or non-finite expected probability: {}",
            invalid.len(),
            first.join(", ")
        ));
    }
    if in_cells > sample_count {
        problems.push(format!(
            "the cells hold {in_cells} samples but only {sample_count} were taken"
        ));
    }
    if pdf_integral > 1.1 {
        problems.push(format!(
            "the pdf integrates to {pdf_integral:.6}, more than 1"
        ));
    }

    let absorbed_observed = sample_count.saturating_sub(in_cells);
    let absorbed_expected = (1.0 - pdf_integral).max(0.0) * n;
    let mut categories: Vec<(Source, f64, f64)> = observed
        .iter()
        .zip(expected_probability)
        .enumerate()
        .map(|(i, (&o, &p))| (Source::Cell(i), o as f64, p * n))
        .collect();
    categories.push((
        Source::Absorbed,
        absorbed_observed as f64,
        absorbed_expected,
    ));

    let impossible: Vec<String> = categories
        .iter()
        .filter(|&&(_, o, e)| e == 0.0 && o > 0.0)
        .map(|(s, o, _)| format!("{s}: {o}"))
        .collect();
    if !impossible.is_empty() {
        let shown: Vec<&str> = impossible.iter().take(8).map(String::as_str).collect();
        problems.push(format!(
            "{} categories received samples where the pdf expects none (observed counts: {}{})",
            impossible.len(),
            shown.join(", "),
            if impossible.len() > 8 { ", ..." } else { "" }
        ));
    }

    // Ascending expectation, so pooling merges the smallest categories first (as Mitsuba does).
    categories.sort_by(|a, b| a.2.total_cmp(&b.2));
    let mut terms: Vec<Term> = Vec::new();
    let mut groups: Vec<Term> = Vec::new();
    let mut pooled_cells = 0;
    let mut pool = Term::empty();
    for (source, o, e) in categories {
        if e == 0.0 && o == 0.0 {
            // An empty category where none is expected carries no information (e.g. the lower
            // hemisphere of a reflection lobe, or the absorbed category of a lossless sampler).
            continue;
        }
        if e < min_expected {
            pool.sources.push(source);
            pool.observed += o;
            pool.expected += e;
            pooled_cells += 1;
            if pool.expected >= min_expected {
                groups.push(std::mem::replace(&mut pool, Term::empty()));
            }
        } else {
            terms.push(Term {
                sources: vec![source],
                observed: o,
                expected: e,
            });
        }
    }
    let pooled_groups = groups.len();
    // Where the leftover pool (below the threshold) went, for the report.
    let mut leftover = String::new();
    if !pool.sources.is_empty() {
        match groups
            .iter_mut()
            .min_by(|a, b| a.expected.total_cmp(&b.expected))
        {
            Some(smallest) => {
                leftover = format!(
                    ", the last {} (expected {:.2}) merged into the smallest group",
                    pool.sources.len(),
                    pool.expected
                );
                smallest.sources.extend(pool.sources);
                smallest.observed += pool.observed;
                smallest.expected += pool.expected;
            }
            None => {
                leftover = format!(
                    ", the last {} (expected {:.2}) kept as a category of its own",
                    pool.sources.len(),
                    pool.expected
                );
                groups.push(pool);
            }
        }
    }
    terms.extend(groups);

    let statistic: f64 = terms.iter().map(Term::contribution).sum();
    let degrees_of_freedom = terms.len().saturating_sub(1);
    if degrees_of_freedom < 1 {
        problems.push(format!(
            "only {} categories have a usable expected count, too few for a test",
            terms.len()
        ));
    }
    let mut p_value = if problems.is_empty() {
        chi2_survival(statistic, degrees_of_freedom)
    } else {
        0.0
    };
    if !p_value.is_finite() {
        problems.push(format!(
            "the p-value of statistic {statistic} with {degrees_of_freedom} dof could not be computed"
        ));
        p_value = 0.0;
    }

    // The report: problems first, then the numbers, then where the statistic comes from.
    let mut report = String::new();
    for problem in &problems {
        let _ = writeln!(report, "FAILED: {problem}");
    }
    let _ = writeln!(
        report,
        "chi-square statistic {statistic:.2} with {degrees_of_freedom} degrees of freedom, \
         p-value {p_value:.3e}"
    );
    let _ = writeln!(
        report,
        "samples: {sample_count} taken, {in_cells} in cells, {absorbed_observed} absorbed \
         (expected {absorbed_expected:.1}); pdf integral {pdf_integral:.6}"
    );
    if pooled_cells > 0 {
        let _ = writeln!(
            report,
            "pooled {pooled_cells} categories with expected count < {min_expected} into \
             {pooled_groups} groups{leftover}"
        );
    }
    let mut worst: Vec<&Term> = terms.iter().collect();
    worst.sort_by(|a, b| b.contribution().total_cmp(&a.contribution()));
    let _ = writeln!(report, "largest contributions (observed vs expected):");
    for term in worst.iter().take(10) {
        let _ = writeln!(
            report,
            "  {}: observed {}, expected {:.1}, {:+.1} sigma, contributes {:.1}",
            term.label(),
            term.observed,
            term.expected,
            (term.observed - term.expected) / term.expected.sqrt(),
            term.contribution()
        );
    }

    Chi2Outcome {
        statistic,
        degrees_of_freedom,
        p_value,
        pooled_cells,
        pdf_integral,
        report,
    }
}

/// Probability that a chi-square variable with `dof` degrees of freedom is at least `statistic`:
/// the regularized upper incomplete gamma function Q(dof/2, statistic/2).
pub fn chi2_survival(statistic: f64, dof: usize) -> f64 {
    assert!(dof > 0, "chi-square needs at least one degree of freedom");
    gamma_q(dof as f64 / 2.0, statistic / 2.0)
}

/// Regularized upper incomplete gamma function Q(a, x), a > 0, by the series for P below the
/// mean and Lentz's continued fraction for Q above it (Numerical Recipes' split): each converges
/// fast on its side, and computing Q directly in the tail keeps tiny p-values accurate instead of
/// rounding 1 - P to 0. NaN if neither converges (not expected for any a a test can produce).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    // Both expansions converge in O(sqrt(a)) steps near x = a; this leaves ample margin for the
    // ~10^5 degrees of freedom the finest binning can produce.
    let max_iterations = 1000 + 100 * a.sqrt() as usize;
    // x^a e^-x / Gamma(a), the common prefactor, in log space to survive large a and x.
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut denominator = a;
        for _ in 0..max_iterations {
            denominator += 1.0;
            term *= x / denominator;
            sum += term;
            if term.abs() < sum.abs() * f64::EPSILON {
                return 1.0 - sum * log_prefactor.exp();
            }
        }
        f64::NAN
    } else {
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..=max_iterations {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < f64::EPSILON {
                return h * log_prefactor.exp();
            }
        }
        f64::NAN
    }
}

/// ln Gamma(x) for x > 0: Stirling's series, which is accurate to ~1e-15 for x >= 10 and gets
/// better as x grows (the regime of many degrees of freedom), after shifting small arguments up
/// with Gamma(x + 1) = x Gamma(x).
fn ln_gamma(x: f64) -> f64 {
    assert!(x > 0.0, "ln_gamma needs a positive argument");
    let mut x = x;
    let mut shift = 0.0;
    while x < 10.0 {
        shift += x.ln();
        x += 1.0;
    }
    let inv = 1.0 / x;
    let inv2 = inv * inv;
    let series = inv
        * (1.0 / 12.0
            - inv2
                * (1.0 / 360.0
                    - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 * (1.0 / 1188.0)))));
    (x - 0.5) * x.ln() - x + 0.5 * (2.0 * PI).ln() + series - shift
}

/// Chi-square of the directions that landed where the pdf is positive against the pdf
/// normalised over those cells: the distribution's shape, separate from how much
/// probability is absorbed (which callers check on their own). Also returns the samples
/// that landed where the integrated pdf is exactly 0 — on the GPU, a few can, from f32
/// rounding at hard edges of the support — for the caller to bound.
///
/// Normalising would make a pdf that integrates to 2 look as good as one that integrates to
/// 1, so the test fails (p_value = 0, reason in the report) when the integrated pdf exceeds
/// `1 + integral_tolerance`: a pdf of a sampler can never exceed 1 in total. The tolerance is
/// the caller's bound on the error of its quadrature (and of its f32 arithmetic); the
/// outcome's `pdf_integral` is the integral before normalising.
pub fn chi2_conditional(
    observed: &[u64],
    expected_probability: &[f64],
    integral_tolerance: f64,
) -> (Chi2Outcome, u64) {
    assert!(
        integral_tolerance >= 0.0,
        "the integral tolerance is a bound on an error, not {integral_tolerance}"
    );
    let stray: u64 = observed
        .iter()
        .zip(expected_probability)
        .filter(|(_, e)| **e == 0.0)
        .map(|(o, _)| *o)
        .sum();
    let integral: f64 = expected_probability.iter().sum();
    let kept: Vec<u64> = observed
        .iter()
        .zip(expected_probability)
        .filter(|(_, e)| **e > 0.0)
        .map(|(o, _)| *o)
        .collect();
    let probability: Vec<f64> = expected_probability
        .iter()
        .filter(|e| **e > 0.0)
        .map(|e| e / integral)
        .collect();
    let mut outcome = chi2_test(&kept, &probability, kept.iter().sum(), 5.0);
    // A NaN integral fails too (chi2_test has already flagged the non-finite cells).
    if integral.is_nan() || integral > 1.0 + integral_tolerance {
        outcome.p_value = 0.0;
        outcome.report = format!(
            "FAILED: the pdf integrates to {integral:.6}, more than 1 + {integral_tolerance:.2e}\n{}",
            outcome.report
        );
    }
    outcome.pdf_integral = integral;
    (outcome, stray)
}
