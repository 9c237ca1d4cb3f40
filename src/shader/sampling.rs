//! How a pixel's samples are placed: the sampler that draws every random number of a path
//! (`shaders/rng.wgsl`) and the pixel filter the film position is drawn from
//! (`shaders/sampling.wgsl`, filter importance sampling: each sample weighs 1, and a pixel
//! is the mean of its own samples, so pixels stay independent and any sample range merges).

use super::gpu_types::{FILTER_TABLE_SIZE, SAMPLER_INDEPENDENT, SAMPLER_SOBOL};

/// Where a path's random numbers come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sampler {
    /// A hash per number: white noise, the error of Monte Carlo at N^-1/2.
    Independent,
    /// Owen-scrambled Sobol' points (Burley 2020), padded per draw: every draw is
    /// stratified over a pixel's samples, decorrelated between pixels (Cycles' default).
    #[default]
    Sobol,
}

impl Sampler {
    pub const ALL: [Sampler; 2] = [Sampler::Independent, Sampler::Sobol];

    /// The name in scene files and on the command line (`--sampler`).
    pub fn key(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Sobol => "sobol",
        }
    }

    /// The sampler named `key` ([`Sampler::key`]).
    pub fn from_key(key: &str) -> Option<Sampler> {
        Sampler::ALL.into_iter().find(|s| s.key() == key)
    }

    /// The name the editor shows.
    pub fn label(self) -> &'static str {
        match self {
            Sampler::Independent => "Independent",
            Sampler::Sobol => "Sobol (Owen-scrambled)",
        }
    }

    /// `Params.sampler`.
    pub fn gpu_id(self) -> u32 {
        match self {
            Sampler::Independent => SAMPLER_INDEPENDENT,
            Sampler::Sobol => SAMPLER_SOBOL,
        }
    }
}

/// The shape of a pixel filter, as Cycles defines them (Film ▸ Pixel Filter), over a
/// support of `width` pixels centred on the pixel. Separable: the 2D filter is f(x) f(y).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterKind {
    /// Constant over the support.
    Box,
    /// A triangle falling to 0 at the support's ends.
    Tent,
    /// exp(-2 (6x / width)^2): a Gaussian of standard deviation width / 12 (Cycles').
    Gaussian,
    /// The four-term Blackman–Harris window over the support (Cycles' default).
    BlackmanHarris,
}

impl FilterKind {
    pub const ALL: [FilterKind; 4] = [
        FilterKind::Box,
        FilterKind::Tent,
        FilterKind::Gaussian,
        FilterKind::BlackmanHarris,
    ];

    /// The name in scene files and on the command line (`--filter`).
    pub fn key(self) -> &'static str {
        match self {
            FilterKind::Box => "box",
            FilterKind::Tent => "tent",
            FilterKind::Gaussian => "gaussian",
            FilterKind::BlackmanHarris => "blackman-harris",
        }
    }

    /// The filter named `key` ([`FilterKind::key`]).
    pub fn from_key(key: &str) -> Option<FilterKind> {
        FilterKind::ALL.into_iter().find(|f| f.key() == key)
    }

    /// The name the editor shows (Blender's).
    pub fn label(self) -> &'static str {
        match self {
            FilterKind::Box => "Box",
            FilterKind::Tent => "Tent",
            FilterKind::Gaussian => "Gaussian",
            FilterKind::BlackmanHarris => "Blackman-Harris",
        }
    }
}

/// A pixel filter: a shape and the width of its support in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFilter {
    pub kind: FilterKind,
    pub width: f32,
}

/// Cycles' default: Blackman–Harris over 1.5 pixels, sharper than a tent of 2 pixels and
/// with less aliasing than a box of 1.
impl Default for PixelFilter {
    fn default() -> Self {
        Self {
            kind: FilterKind::BlackmanHarris,
            width: 1.5,
        }
    }
}

/// The widest filter accepted, in pixels (Cycles allows 10).
pub const MAX_FILTER_WIDTH: f32 = 16.0;

/// Subintervals of the quadrature that tabulates a filter's distribution.
const CDF_STEPS: usize = 1 << 14;

impl PixelFilter {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.width > 0.0 && self.width <= MAX_FILTER_WIDTH) {
            return Err(format!(
                "the pixel filter's width must be in (0, {MAX_FILTER_WIDTH}] pixels, not {}",
                self.width
            ));
        }
        Ok(())
    }

    /// The filter's value at `x` pixels from the pixel's centre, unnormalised (the shape's
    /// peak is about 1); 0 outside the support.
    pub fn shape(&self, x: f64) -> f64 {
        let w = self.width as f64;
        if x.abs() > w / 2.0 {
            return 0.0;
        }
        match self.kind {
            FilterKind::Box => 1.0,
            FilterKind::Tent => 1.0 - (2.0 * x / w).abs(),
            FilterKind::Gaussian => {
                let v = 6.0 * x / w;
                (-2.0 * v * v).exp()
            }
            FilterKind::BlackmanHarris => {
                let v = std::f64::consts::TAU * (x / w + 0.5);
                0.35875 - 0.48829 * v.cos() + 0.14128 * (2.0 * v).cos() - 0.01168 * (3.0 * v).cos()
            }
        }
    }

    /// The filter's cumulative distribution at the edges of `CDF_STEPS` equal steps over
    /// its support (Simpson's rule per step), normalised to end at 1.
    fn cdf(&self) -> Vec<f64> {
        let w = self.width as f64;
        let h = w / CDF_STEPS as f64;
        let mut cdf = Vec::with_capacity(CDF_STEPS + 1);
        let mut sum = 0.0;
        cdf.push(0.0);
        for i in 0..CDF_STEPS {
            let a = -w / 2.0 + i as f64 * h;
            sum += h / 6.0 * (self.shape(a) + 4.0 * self.shape(a + h / 2.0) + self.shape(a + h));
            cdf.push(sum);
        }
        cdf.iter_mut().for_each(|c| *c /= sum);
        cdf
    }

    /// The quantile function in pixels from the pixel's centre at the probabilities
    /// [`table_probability`] of [`FILTER_TABLE_SIZE`] evenly spaced t: `Params.filter_quantiles`.
    /// The kernel finds t for its random number and interpolates linearly in t. Spaced so,
    /// the entries are dense in the tails, where a filter's distribution curves most
    /// (a tent's rises quadratically, a Gaussian's faster): with even spacing of the
    /// probabilities, 128 entries misplace up to 5e-3 of a Gaussian's mass; spaced so,
    /// under 1e-4.
    pub fn quantiles(&self) -> [[f32; 4]; FILTER_TABLE_SIZE as usize / 4] {
        let n = FILTER_TABLE_SIZE as usize;
        let w = self.width as f64;
        let cdf = self.cdf();
        let h = w / CDF_STEPS as f64;
        let mut table = [[0.0; 4]; FILTER_TABLE_SIZE as usize / 4];
        let mut step = 0;
        for i in 0..n {
            let u = table_probability(i as f64 / (n - 1) as f64);
            while step + 1 < CDF_STEPS && cdf[step + 1] < u {
                step += 1;
            }
            // Linear within the step: its density is close to constant.
            let (c0, c1) = (cdf[step], cdf[step + 1]);
            let t = if c1 > c0 {
                ((u - c0) / (c1 - c0)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let x = if i == 0 {
                -w / 2.0
            } else if i == n - 1 {
                w / 2.0
            } else {
                -w / 2.0 + (step as f64 + t) * h
            };
            table[i / 4][i % 4] = x as f32;
        }
        table
    }
}

/// The probability at which the filter table holds the quantile for t in [0, 1]
/// (`filter_quantile` in `shaders/sampling.wgsl` inverts it).
pub fn table_probability(t: f64) -> f64 {
    (1.0 - (std::f64::consts::PI * t).cos()) / 2.0
}

/// What places a pixel's samples: the sampler and the pixel filter (Cycles' Sampling and
/// Film ▸ Pixel Filter panels).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sampling {
    pub sampler: Sampler,
    pub filter: PixelFilter,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probability that an offset is below `x`, from the table as the kernel reads it:
    /// linear in t between entries.
    fn table_cdf(table: &[f32], x: f64) -> f64 {
        let intervals = (table.len() - 1) as f64;
        if x <= table[0] as f64 {
            return 0.0;
        }
        for (i, pair) in table.windows(2).enumerate() {
            let (a, b) = (pair[0] as f64, pair[1] as f64);
            if x <= b {
                let f = if b > a { (x - a) / (b - a) } else { 1.0 };
                return table_probability((i as f64 + f) / intervals);
            }
        }
        1.0
    }

    /// The filter's own distribution at the increasing `xs`, by a midpoint rule unrelated
    /// to the table's quadrature.
    fn reference_cdf(filter: &PixelFilter, xs: &[f64]) -> Vec<f64> {
        let w = filter.width as f64;
        let n = 100_000;
        let h = w / n as f64;
        let mut at = Vec::with_capacity(xs.len());
        let mut mass = 0.0;
        let mut next = xs.iter().peekable();
        for i in 0..n {
            let t = -w / 2.0 + (i as f64 + 0.5) * h;
            while let Some(&&x) = next.peek()
                && x <= t
            {
                at.push(mass);
                next.next();
            }
            mass += filter.shape(t) * h;
        }
        at.resize(xs.len(), mass);
        at.iter().map(|m| m / mass).collect()
    }

    #[test]
    fn every_filter_integrates_to_one_and_its_table_follows_its_distribution() {
        for kind in FilterKind::ALL {
            for width in [0.5, 1.0, 1.5, 2.0, 4.0] {
                let filter = PixelFilter { kind, width };
                let table: Vec<f32> = filter.quantiles().into_iter().flatten().collect();
                assert_eq!(table[0], -width / 2.0, "{kind:?} {width}");
                assert_eq!(*table.last().unwrap(), width / 2.0, "{kind:?} {width}");
                assert!(
                    table.windows(2).all(|p| p[0] <= p[1]),
                    "{kind:?} {width}: the quantiles decrease somewhere"
                );
                // The table's distribution is the filter's, normalised (so it integrates to
                // one), to within what 127 intervals resolve; it reaches 0 and 1 at the
                // support's ends.
                let xs: Vec<f64> = (0..=40)
                    .map(|i| -(width as f64) / 2.0 + width as f64 * i as f64 / 40.0)
                    .collect();
                for (&x, p) in xs.iter().zip(reference_cdf(&filter, &xs)) {
                    let table_p = table_cdf(&table, x);
                    assert!(
                        (table_p - p).abs() < 2e-4,
                        "{kind:?} width {width}: P(offset < {x:.3}) is {table_p:.5}, the \
                         filter's is {p:.5}"
                    );
                }
                // Symmetric, as every shape is.
                for i in 0..table.len() {
                    let mirror = table[table.len() - 1 - i];
                    assert!(
                        (table[i] + mirror).abs() < 1e-4 * width,
                        "{kind:?} {width}: quantiles {i} and its mirror"
                    );
                }
            }
        }
    }

    #[test]
    fn keys_round_trip() {
        for kind in FilterKind::ALL {
            assert_eq!(FilterKind::from_key(kind.key()), Some(kind));
        }
        for sampler in Sampler::ALL {
            assert_eq!(Sampler::from_key(sampler.key()), Some(sampler));
        }
        assert_eq!(FilterKind::from_key("mitchell"), None);
    }

    #[test]
    fn widths_outside_the_range_are_refused() {
        for width in [0.0, -1.0, f32::NAN, MAX_FILTER_WIDTH * 2.0] {
            let filter = PixelFilter {
                kind: FilterKind::Box,
                width,
            };
            assert!(filter.validate().is_err(), "{width}");
        }
    }
}
