//! The environment map's importance distribution: the map's texels followed by the
//! two-level CDF that `shaders/lights/environment.wgsl` samples (`env_data`), and the
//! map's mean radiance, which next-event estimation weighs against the other lights
//! (`light_distribution`).
//!
//! Texels are weighted by luminance × sin θ: rows near the poles of an equirectangular
//! map cover less solid angle. Not here: the sampling itself (WGSL) and the upload
//! (`gpu_scene`).

use glam::Vec3;

use crate::scene::EnvironmentMap;

/// Rec. 709 luminance, the weights of `luminance` in `shaders/sampling.wgsl`.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Polar angle of the centre of row `y` of an equirectangular map `height` rows tall.
fn row_theta(y: usize, height: usize) -> f64 {
    (y as f64 + 0.5) / height as f64 * std::f64::consts::PI
}

/// Luminance averaged over the sphere, strength included (the uniform sky of the same
/// power).
pub fn mean_environment_luminance(map: &EnvironmentMap) -> f64 {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut sum = 0.0;
    for y in 0..h {
        let s = row_theta(y, h).sin();
        for x in 0..w {
            sum += luminance(map.texels[y * w + x]) as f64 * s;
        }
    }
    // Each texel spans (2π / w) (π / h) sin θ steradians; the sphere has 4π.
    sum * map.strength as f64 * 2.0 * std::f64::consts::PI * std::f64::consts::PI
        / (w * h) as f64
        / (4.0 * std::f64::consts::PI)
}

/// The map and its sampling distribution, proportional to luminance × sin θ: a header
/// (width, height, strength, rotation in radians), then per row an inclusive conditional
/// CDF over columns (in each texel's w), then an inclusive marginal CDF over rows (in x).
/// Each CDF ends at exactly 1.
pub fn environment_data(map: &EnvironmentMap) -> Vec<[f32; 4]> {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut data = Vec::with_capacity(1 + w * h + h);
    data.push([
        map.width as f32,
        map.height as f32,
        map.strength,
        map.rotation_degrees.to_radians(),
    ]);
    let mut row_sums = Vec::with_capacity(h);
    for y in 0..h {
        let s = row_theta(y, h).sin();
        let weights: Vec<f64> = (0..w)
            .map(|x| luminance(map.texels[y * w + x]) as f64 * s)
            .collect();
        let row: f64 = weights.iter().sum();
        let mut acc = 0.0;
        for (x, weight) in weights.iter().enumerate() {
            acc += weight;
            // A black row is sampled uniformly (it is then never chosen anyway).
            let cdf = if row > 0.0 {
                acc / row
            } else {
                (x + 1) as f64 / w as f64
            };
            let t = map.texels[y * w + x];
            data.push([t.x, t.y, t.z, if x + 1 == w { 1.0 } else { cdf as f32 }]);
        }
        row_sums.push(row);
    }
    let total: f64 = row_sums.iter().sum();
    let mut acc = 0.0;
    for (y, row) in row_sums.iter().enumerate() {
        acc += row;
        let cdf = if total > 0.0 {
            acc / total
        } else {
            (y + 1) as f64 / h as f64
        };
        data.push([if y + 1 == h { 1.0 } else { cdf as f32 }, 0.0, 0.0, 0.0]);
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, texel: impl Fn(u32, u32) -> Vec3) -> EnvironmentMap {
        EnvironmentMap {
            width,
            height,
            texels: (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| texel(x, y))
                .collect(),
            strength: 2.0,
            rotation_degrees: 90.0,
        }
    }

    #[test]
    fn a_uniform_map_has_its_own_luminance_as_mean_within_a_percent() {
        // The midpoint rule over sin θ converges as 1/h²: 64 rows are within 0.1 %.
        let sky = map(128, 64, |_, _| Vec3::new(0.5, 1.0, 0.25));
        let expected = luminance(Vec3::new(0.5, 1.0, 0.25)) as f64 * 2.0;
        let mean = mean_environment_luminance(&sky);
        assert!(
            (mean - expected).abs() < 0.01 * expected,
            "mean {mean}, expected {expected}"
        );
    }

    #[test]
    fn every_cdf_rises_to_exactly_one_and_follows_the_texel_weights() {
        // One bright column in the middle row, black elsewhere, and one all-black row.
        let (w, h) = (8usize, 5usize);
        let sky = map(w as u32, h as u32, |x, y| match (x, y) {
            (3, 2) => Vec3::splat(4.0),
            (_, 4) => Vec3::ZERO,
            _ => Vec3::splat(0.1),
        });
        let data = environment_data(&sky);
        assert_eq!(data.len(), 1 + w * h + h);
        assert_eq!(data[0], [8.0, 5.0, 2.0, 90f32.to_radians()]);
        for y in 0..h {
            let row: Vec<f32> = (0..w).map(|x| data[1 + y * w + x][3]).collect();
            assert!(row.windows(2).all(|p| p[0] <= p[1]), "row {y}: {row:?}");
            assert_eq!(row[w - 1], 1.0, "row {y}");
        }
        // The bright texel takes 4 of the middle row's 4.7 luminance.
        let bright = data[1 + 2 * w + 3][3] - data[1 + 2 * w + 2][3];
        assert!((bright - 4.0 / 4.7).abs() < 1e-5, "{bright}");
        // The black row is spread uniformly and is never picked by the marginal.
        assert_eq!(data[1 + 4 * w][3], 1.0 / w as f32);
        let marginal: Vec<f32> = (0..h).map(|y| data[1 + w * h + y][0]).collect();
        assert!(marginal.windows(2).all(|p| p[0] <= p[1]), "{marginal:?}");
        assert_eq!(marginal[3], 1.0);
        assert_eq!(marginal[h - 1], 1.0);
    }
}
