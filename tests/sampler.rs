//! The samplers of `shaders/rng.wgsl`, run on the GPU as a path draws from them
//! (`shaders/tests/sampler_probe.wgsl`): Sobol' draws are stratified over a pixel's first
//! 2^k samples (elementary intervals of every 2D draw, the 2^k intervals of every 1D one),
//! a smooth integrand converges at a rate clearly steeper than Monte Carlo's N^-1/2,
//! and neither neighbouring pixels nor a path's draws are correlated.

mod common;

use common::run_test_kernel;
use kiln::shader::sampling::Sampler;

/// One sample's draws: the camera's rand2(), the rand() after it, bounce 3's first rand2(),
/// and the probe's integrand at the camera's rand2().
#[derive(Clone, Copy, Debug)]
struct Draws {
    film: [f32; 2],
    pick: f32,
    bounce: [f32; 2],
    integrand: f32,
}

/// `spp` samples of each of `pixels` pixels, pixel-major.
fn draws(pixels: u32, spp: u32, sampler: Sampler, seed: u32) -> Vec<Draws> {
    let input = [[pixels, spp, sampler.gpu_id(), seed]];
    let total = pixels * spp;
    let out = run_test_kernel(
        (
            "shaders/tests/sampler_probe.wgsl",
            include_str!("../shaders/tests/sampler_probe.wgsl"),
        ),
        "sampler_probe",
        bytemuck::cast_slice(&input),
        32 * total as u64,
        total,
    );
    let v: &[[f32; 8]] = bytemuck::cast_slice(&out);
    v.iter()
        .map(|d| Draws {
            film: [d[0], d[1]],
            pick: d[2],
            bounce: [d[4], d[5]],
            integrand: d[6],
        })
        .collect()
}

/// Whether the 2^m points form a (0, m, 2)-net: every elementary box of area 2^-m
/// (2^a by 2^b cells, a + b = m) holds exactly one of them.
fn is_net(points: &[[f32; 2]], m: u32) -> bool {
    assert_eq!(points.len(), 1 << m);
    (0..=m).all(|a| {
        let b = m - a;
        let mut seen = vec![false; 1 << m];
        points.iter().all(|p| {
            let x = (p[0] * (1u32 << a) as f32) as usize;
            let y = (p[1] * (1u32 << b) as f32) as usize;
            !std::mem::replace(&mut seen[(y << a) | x], true)
        })
    })
}

/// Whether the 2^m values fall one in each of 2^m equal intervals.
fn is_stratified(mut values: impl Iterator<Item = f32>, m: u32) -> bool {
    let mut seen = vec![false; 1 << m];
    values.all(|v| !std::mem::replace(&mut seen[(v * (1u32 << m) as f32) as usize], true))
}

#[test]
fn sobol_draws_are_stratified_over_every_power_of_two_of_a_pixels_samples() {
    const M: u32 = 8;
    let pixels = 64;
    let spp = 1 << M;
    let sobol = draws(pixels, spp, Sampler::Sobol, 5);
    for (p, pixel) in sobol.chunks(spp as usize).enumerate() {
        // Every prefix of 2^k samples, as a progressive render has them.
        for k in [2, 5, M] {
            let first = &pixel[..1 << k];
            let film: Vec<[f32; 2]> = first.iter().map(|d| d.film).collect();
            let bounce: Vec<[f32; 2]> = first.iter().map(|d| d.bounce).collect();
            assert!(
                is_net(&film, k),
                "pixel {p}: the film draw of {} samples",
                1 << k
            );
            assert!(
                is_net(&bounce, k),
                "pixel {p}: bounce 3's draw, {} samples",
                1 << k
            );
            assert!(
                is_stratified(first.iter().map(|d| d.pick), k),
                "pixel {p}: the 1D draw of {} samples",
                1 << k
            );
        }
    }
    // The check can fail: independent numbers are almost never stratified.
    let independent = draws(pixels, spp, Sampler::Independent, 5);
    let stratified = independent
        .chunks(spp as usize)
        .filter(|pixel| is_stratified(pixel.iter().map(|d| d.pick), M))
        .count();
    assert_eq!(
        stratified, 0,
        "independent draws stratified in {stratified} pixels"
    );
}

/// The RMSE over pixels of the mean of each pixel's first n samples of the integrand
/// exp(x) cos(y) over the unit square, against its integral (e - 1) sin 1, for each n.
fn rmse_by_sample_count(draws: &[Draws], spp: usize, counts: &[usize]) -> Vec<f64> {
    let exact = (std::f64::consts::E - 1.0) * 1f64.sin();
    counts
        .iter()
        .map(|&n| {
            let pixels = draws.len() / spp;
            let squares: f64 = draws
                .chunks(spp)
                .map(|pixel| {
                    let mean =
                        pixel[..n].iter().map(|d| d.integrand as f64).sum::<f64>() / n as f64;
                    (mean - exact).powi(2)
                })
                .sum();
            (squares / pixels as f64).sqrt()
        })
        .collect()
}

/// The least-squares slope of ln y against ln x.
fn log_slope(x: &[usize], y: &[f64]) -> f64 {
    let points: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .map(|(&x, &y)| ((x as f64).ln(), y.ln()))
        .collect();
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn a_smooth_integrand_converges_clearly_faster_than_monte_carlo() {
    // 256 pixels are 256 independent estimates (their scrambles differ).
    let (pixels, spp) = (256, 4096);
    let counts = [16, 64, 256, 1024, 4096];
    let slopes: Vec<(Sampler, f64, Vec<f64>)> = Sampler::ALL
        .into_iter()
        .map(|sampler| {
            let rmse = rmse_by_sample_count(&draws(pixels, spp, sampler, 9), spp as usize, &counts);
            (sampler, log_slope(&counts, &rmse), rmse)
        })
        .collect();
    for (sampler, slope, rmse) in &slopes {
        // Monte Carlo's -1/2 with room for the noise of 256 estimates (the RMSE of each
        // count is known to about 1/sqrt(2 * 256) = 4%); Owen-scrambled Sobol' reaches
        // -3/2 on smooth integrands (Owen 1997), so -1 is far from both.
        let ok = match sampler {
            Sampler::Independent => (-0.6..=-0.4).contains(slope),
            Sampler::Sobol => *slope < -1.0,
        };
        let rmse: Vec<String> = rmse.iter().map(|e| format!("{e:.2e}")).collect();
        println!("{}: RMSE ∝ N^{slope:.2}", sampler.key());
        assert!(
            ok,
            "{}: RMSE ∝ N^{slope:.2} (RMSE at {counts:?} samples: {})",
            sampler.key(),
            rmse.join(", ")
        );
    }
}

/// Pearson's correlation of the pairs.
fn correlation(pairs: &[(f64, f64)]) -> f64 {
    let n = pairs.len() as f64;
    let (ma, mb) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (a, b) in pairs {
        sab += (a - ma) * (b - mb);
        saa += (a - ma).powi(2);
        sbb += (b - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

#[test]
fn neighbouring_pixels_and_a_paths_draws_are_uncorrelated() {
    let (pixels, spp) = (4096u32, 16usize);
    let sobol = draws(pixels, spp as u32, Sampler::Sobol, 3);
    let at = |pixel: usize, sample: usize| &sobol[pixel * spp + sample];
    // The same sample index and draw in horizontally adjacent pixels (of a 64-wide film),
    // and different draws of the same sample.
    let mut checks: Vec<(&str, Vec<(f64, f64)>)> = Vec::new();
    let neighbours = |f: &dyn Fn(&Draws) -> f32| -> Vec<(f64, f64)> {
        (0..pixels as usize)
            .filter(|p| p % 64 != 63)
            .flat_map(|p| (0..spp).map(move |s| (p, s)))
            .map(|(p, s)| (f(at(p, s)) as f64, f(at(p + 1, s)) as f64))
            .collect()
    };
    checks.push(("film x, neighbours", neighbours(&|d| d.film[0])));
    checks.push(("film y, neighbours", neighbours(&|d| d.film[1])));
    checks.push(("1D draw, neighbours", neighbours(&|d| d.pick)));
    checks.push(("bounce 3, neighbours", neighbours(&|d| d.bounce[0])));
    let within = |f: &dyn Fn(&Draws) -> (f32, f32)| -> Vec<(f64, f64)> {
        sobol
            .iter()
            .map(|d| {
                let (a, b) = f(d);
                (a as f64, b as f64)
            })
            .collect()
    };
    checks.push(("film x and film y", within(&|d| (d.film[0], d.film[1]))));
    checks.push(("film x and the 1D draw", within(&|d| (d.film[0], d.pick))));
    checks.push((
        "film x and bounce 3's x",
        within(&|d| (d.film[0], d.bounce[0])),
    ));
    checks.push((
        "the 1D draw and bounce 3's y",
        within(&|d| (d.pick, d.bounce[1])),
    ));
    for (what, pairs) in checks {
        // Uncorrelated pairs give r with standard deviation 1 / sqrt(n): 5 sigma.
        let r = correlation(&pairs);
        let bound = 5.0 / (pairs.len() as f64).sqrt();
        assert!(
            r.abs() < bound,
            "{what}: correlation {r:.4} over {} pairs (bound {bound:.4})",
            pairs.len()
        );
    }
}
