//! Interval bounds of node outputs, for the majorant of a heterogeneous volume: the
//! integrator's delta and ratio tracking need an extinction that no point of the volume
//! exceeds, and the compiler proves one by interval arithmetic over the graph that feeds
//! the volume node. A node declares how bounds of its inputs bound its outputs
//! ([`super::nodes::NodeDef::range`]); a node without a declaration, or an operation
//! whose result interval arithmetic cannot bound (a division by an interval containing
//! zero), gives [`Bounds::UNBOUNDED`], and the compiler names it.

use super::graph::Value;
use super::nodes::Params;

/// Lower and upper bounds per component (a float in x, repeated).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
}

/// How a node's output bounds follow from its inputs' (one per declared input, in the
/// input's type): one per output.
pub type RangeFn = fn(&[Bounds], Params) -> Vec<Bounds>;

impl Bounds {
    pub const UNBOUNDED: Bounds = Bounds {
        lo: [f32::NEG_INFINITY; 3],
        hi: [f32::INFINITY; 3],
    };
    pub const UNIT: Bounds = Bounds::scalar(0.0, 1.0);

    pub const fn scalar(lo: f32, hi: f32) -> Bounds {
        Bounds {
            lo: [lo; 3],
            hi: [hi; 3],
        }
    }

    /// A constant's bounds: the value itself.
    pub fn exact(v: &Value) -> Bounds {
        let c = match v {
            Value::Float(x) => [*x; 3],
            _ => v.as_vec3(),
        };
        Bounds { lo: c, hi: c }
    }

    /// Both bounds finite in every component.
    pub fn is_finite(&self) -> bool {
        self.lo.iter().chain(&self.hi).all(|x| x.is_finite())
    }

    /// The smallest bounds holding both.
    pub fn hull(self, other: Bounds) -> Bounds {
        Bounds {
            lo: std::array::from_fn(|i| self.lo[i].min(other.lo[i])),
            hi: std::array::from_fn(|i| self.hi[i].max(other.hi[i])),
        }
    }

    /// Bounds of `f` applied per component, for `f` non-decreasing in its argument.
    fn monotone(self, f: impl Fn(f32) -> f32) -> Bounds {
        Bounds {
            lo: self.lo.map(&f),
            hi: self.hi.map(&f),
        }
    }

    /// Bounds of `f(a, b)` per component, from the four corners: exact for functions
    /// monotone in each argument (sums, products, minima, maxima).
    fn corners(self, other: Bounds, f: impl Fn(f32, f32) -> f32) -> Bounds {
        let mut out = Bounds {
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
        };
        for i in 0..3 {
            for a in [self.lo[i], self.hi[i]] {
                for b in [other.lo[i], other.hi[i]] {
                    let v = f(a, b);
                    // NaN (∞ · 0) means the corner cannot be bounded.
                    let (lo, hi) = if v.is_nan() {
                        (f32::NEG_INFINITY, f32::INFINITY)
                    } else {
                        (v, v)
                    };
                    out.lo[i] = out.lo[i].min(lo);
                    out.hi[i] = out.hi[i].max(hi);
                }
            }
        }
        out
    }

    /// Within [lo, hi] (both bounds clamped).
    pub fn clamped(self, lo: f32, hi: f32) -> Bounds {
        self.monotone(|x| x.clamp(lo, hi))
    }

    /// The bounds of a component mean (a colour read as a float).
    pub fn average(self) -> Bounds {
        let mean = |c: [f32; 3]| (c[0] + c[1] + c[2]) / 3.0;
        Bounds::scalar(mean(self.lo), mean(self.hi))
    }

    /// The bounds of Rec. 709 luminance (a colour read as a float by luminance).
    pub fn luminance(self) -> Bounds {
        let y = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        Bounds::scalar(y(self.lo), y(self.hi))
    }

    /// The bounds of x, y or z alone.
    pub fn component(self, i: usize) -> Bounds {
        Bounds::scalar(self.lo[i], self.hi[i])
    }

    /// Three floats' bounds as one vector's.
    pub fn combine(x: Bounds, y: Bounds, z: Bounds) -> Bounds {
        Bounds {
            lo: [x.lo[0], y.lo[0], z.lo[0]],
            hi: [x.hi[0], y.hi[0], z.hi[0]],
        }
    }

    fn add(self, o: Bounds) -> Bounds {
        self.corners(o, |a, b| a + b)
    }

    fn mul(self, o: Bounds) -> Bounds {
        self.corners(o, |a, b| a * b)
    }

    fn within(self, lo: f32, hi: f32) -> bool {
        self.lo.iter().all(|&x| x >= lo) && self.hi.iter().all(|&x| x <= hi)
    }

    /// `a + t (b - a)` for t within [0, 1]: between a and b.
    fn mix(t: Bounds, a: Bounds, b: Bounds) -> Bounds {
        if t.within(0.0, 1.0) {
            a.hull(b)
        } else {
            Bounds::UNBOUNDED
        }
    }
}

// -------------------------------------------------------------------- node ranges

/// Texture nodes whose every output lies in [0, 1].
pub fn unit(_: &[Bounds], _: Params) -> Vec<Bounds> {
    vec![Bounds::UNIT; 2]
}

/// Texture Coordinate: inside a volume, Generated is the position within the object's
/// bounding box, in [0, 1]; the other outputs are not bounded.
pub fn texture_coordinate(_: &[Bounds], _: Params) -> Vec<Bounds> {
    // The order of the node's outputs: generated first.
    let mut out = vec![Bounds::UNBOUNDED; 9];
    out[0] = Bounds::UNIT;
    out
}

pub fn math(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    let (a, b, c) = (inputs[0], inputs[1], inputs[2]);
    let op = super::nodes::MATH_OPERATIONS[params.choice("operation")];
    let value = match op {
        "add" => a.add(b),
        "subtract" => a.add(b.monotone(|x| -x)).monotone(|x| x),
        "multiply" => a.mul(b),
        "multiply_add" => a.mul(b).add(c),
        // Blender's safe division gives 0 for a zero divisor: only a divisor interval
        // that excludes 0 is bounded.
        "divide" if b.lo[0] > 0.0 || b.hi[0] < 0.0 => a.corners(b, |x, y| x / y),
        "minimum" => a.corners(b, f32::min),
        "maximum" => a.corners(b, f32::max),
        "absolute" => {
            let m = a.lo[0].abs().max(a.hi[0].abs());
            let lo = if a.lo[0] <= 0.0 && a.hi[0] >= 0.0 {
                0.0
            } else {
                a.lo[0].abs().min(a.hi[0].abs())
            };
            Bounds::scalar(lo, m)
        }
        // Safe square root: 0 for negative arguments.
        "sqrt" => a.monotone(|x| x.max(0.0).sqrt()),
        "exponent" => a.monotone(f32::exp),
        // A non-negative base to a constant exponent: monotone in the base.
        "power" if a.lo[0] >= 0.0 && b.lo[0] == b.hi[0] => {
            let e = b.lo[0];
            let (p, q) = (a.lo[0].powf(e), a.hi[0].powf(e));
            Bounds::scalar(p.min(q), p.max(q))
        }
        "sine" | "cosine" => Bounds::scalar(-1.0, 1.0),
        _ => Bounds::UNBOUNDED,
    };
    let value = if params.flag("clamp") {
        // Unbounded (or NaN) bounds clamp to the whole unit interval.
        if value.is_finite() {
            value.clamped(0.0, 1.0)
        } else {
            Bounds::UNIT
        }
    } else {
        value
    };
    vec![value]
}

/// Clamp: min(max(value, min), max), monotone in all three.
pub fn clamp(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    let (v, lo, hi) = (inputs[0], inputs[1], inputs[2]);
    if params.choice("clamp_type") == 1 {
        // "range" swaps min and max: the result is between the two.
        return vec![lo.hull(hi)];
    }
    let lower = v.corners(lo, f32::max);
    vec![lower.corners(hi, f32::min)]
}

/// Map Range, clamped: within the output range, whatever the input.
pub fn map_range(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    if params.flag("clamp") {
        vec![inputs[3].hull(inputs[4])]
    } else {
        vec![Bounds::UNBOUNDED]
    }
}

/// Mix (float or vector): between a and b when the factor is within [0, 1].
pub fn mix(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    let t = if params.flag("clamp_factor") {
        inputs[0].clamped(0.0, 1.0)
    } else {
        inputs[0]
    };
    vec![Bounds::mix(t, inputs[1], inputs[2])]
}

/// Mix Color in its plain "mix" mode: between a and b, clamped if asked.
pub fn mix_color(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    let mixed = if params.choice("blend") == 0 {
        // The factor is clamped to [0, 1] by the node.
        Bounds::mix(inputs[0].clamped(0.0, 1.0), inputs[1], inputs[2])
    } else {
        Bounds::UNBOUNDED
    };
    if params.flag("clamp_result") {
        return vec![if mixed.is_finite() {
            mixed.clamped(0.0, 1.0)
        } else {
            Bounds::UNIT
        }];
    }
    vec![mixed]
}

/// Colour Ramp: within the hull of its stops' colours and alphas.
pub fn color_ramp(_: &[Bounds], params: Params) -> Vec<Bounds> {
    let Some(super::graph::Param::Ramp(stops)) = params.get("stops") else {
        // The default ramp, black to white.
        return vec![Bounds::UNIT, Bounds::UNIT];
    };
    let mut color: Option<Bounds> = None;
    let mut alpha: Option<Bounds> = None;
    for s in stops {
        let c = Bounds {
            lo: [s.color[0], s.color[1], s.color[2]],
            hi: [s.color[0], s.color[1], s.color[2]],
        };
        let a = Bounds::scalar(s.color[3], s.color[3]);
        color = Some(color.map_or(c, |b| b.hull(c)));
        alpha = Some(alpha.map_or(a, |b| b.hull(a)));
    }
    vec![
        color.unwrap_or(Bounds::scalar(0.0, 0.0)),
        alpha.unwrap_or(Bounds::scalar(0.0, 0.0)),
    ]
}

/// Invert: between the colour and 1 − colour.
pub fn invert(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    let (fac, c) = (inputs[0], inputs[1]);
    let inverted = Bounds {
        lo: c.hi.map(|x| 1.0 - x),
        hi: c.lo.map(|x| 1.0 - x),
    };
    vec![Bounds::mix(fac, c, inverted)]
}

pub fn rgb_to_bw(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    vec![inputs[0].luminance()]
}

pub fn separate(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    if params.get("mode").is_some() && params.choice("mode") != 0 {
        // HSV components of any colour lie in [0, 1] except the value.
        return vec![Bounds::UNIT, Bounds::UNIT, Bounds::UNBOUNDED];
    }
    (0..3).map(|i| inputs[0].component(i)).collect()
}

pub fn combine(inputs: &[Bounds], params: Params) -> Vec<Bounds> {
    if params.get("mode").is_some() && params.choice("mode") != 0 {
        return vec![Bounds::UNBOUNDED];
    }
    vec![Bounds::combine(inputs[0], inputs[1], inputs[2])]
}

/// A value's bounds passed through (Value, RGB, Vector, and the identity probes).
pub fn identity(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    vec![inputs[0]]
}

// ------------------------------------------------------------------ volume nodes
//
// A volume output's bounds are those of its extinction σt = σa + σs per channel, from
// the formulas of shaders/nodes/volume.wgsl, each non-decreasing in density and monotone
// in each colour.

/// Volume Absorption: σt = (1 − clamp(colour)) × density.
pub fn volume_absorption(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    let (c, d) = (inputs[0], inputs[1]);
    let keep = |x: f32| 1.0 - x.clamp(0.0, 1.0);
    vec![Bounds {
        lo: std::array::from_fn(|i| keep(c.hi[i]) * d.lo[0].max(0.0)),
        hi: std::array::from_fn(|i| keep(c.lo[i]) * d.hi[0].max(0.0)),
    }]
}

/// Volume Scatter: σt = max(colour, 0) × density.
pub fn volume_scatter(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    let (c, d) = (inputs[0], inputs[1]);
    vec![Bounds {
        lo: std::array::from_fn(|i| c.lo[i].max(0.0) * d.lo[0].max(0.0)),
        hi: std::array::from_fn(|i| c.hi[i].max(0.0) * d.hi[0].max(0.0)),
    }]
}

/// Principled Volume: σt = (c + (1 − c) t) × density with c = max(colour, 0), the
/// absorbed part (1 − c) clamped to ≥ 0 and t = 1 − √absorption colour; non-decreasing
/// in c and in t, so in the colour and against the absorption colour.
pub fn principled_volume(inputs: &[Bounds], _: Params) -> Vec<Bounds> {
    let (c, d, a) = (inputs[0], inputs[1], inputs[3]);
    let per_density = |c: f32, a: f32| {
        let c = c.max(0.0);
        let tint = (1.0 - a.max(0.0).sqrt()).max(0.0);
        c + (1.0 - c).max(0.0) * tint
    };
    vec![Bounds {
        lo: std::array::from_fn(|i| per_density(c.lo[i], a.hi[i]) * d.lo[0].max(0.0)),
        hi: std::array::from_fn(|i| per_density(c.hi[i], a.lo[i]) * d.hi[0].max(0.0)),
    }]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_bound_products_of_signed_intervals() {
        let a = Bounds::scalar(-2.0, 3.0);
        let b = Bounds::scalar(-1.0, 4.0);
        let p = a.mul(b);
        assert_eq!((p.lo[0], p.hi[0]), (-8.0, 12.0));
        // ∞ · 0 cannot be bounded.
        let q = Bounds::UNBOUNDED.mul(Bounds::scalar(0.0, 1.0));
        assert!(!q.is_finite());
    }

    #[test]
    fn a_volume_node_bounds_its_extinction_as_its_traits_compute_it() {
        // For constant inputs the bounds are a point: the extinction the node's traits
        // compute for the material buffer (σa + σs), so the two formulas cannot drift.
        let cases = [
            ([0.8, 0.5, 0.1], 2.0, [0.0; 3]),
            ([0.0, 1.0, 1.5], 0.5, [0.3, 0.6, 1.0]),
            ([1.0; 3], 10.0, [1.0; 3]),
        ];
        for kind in ["volume_absorption", "volume_scatter", "principled_volume"] {
            let def = super::super::nodes::find(kind).expect("a volume node");
            let values = std::collections::BTreeMap::new();
            let params = Params::new(def, &values);
            for (color, density, absorption_color) in cases {
                let value = |name: &str| {
                    Some(match name {
                        "color" => Value::Vec3(color),
                        "density" => Value::Float(density),
                        "absorption_color" => Value::Vec3(absorption_color),
                        "emission_color" => Value::Vec3([1.0; 3]),
                        _ => Value::Float(0.2),
                    })
                };
                let traits = (def.traits.expect("volume traits"))(&value, params);
                let v = traits
                    .volume
                    .expect("constant inputs make a homogeneous volume");
                let inputs: Vec<Bounds> = def
                    .inputs
                    .iter()
                    .map(|i| Bounds::exact(&value(i.name).expect("every input")))
                    .collect();
                let b = (def.range.expect("a volume node declares its range"))(&inputs, params)[0];
                for c in 0..3 {
                    let sigma_t = v.absorption[c] + v.scattering[c];
                    assert!(
                        (b.lo[c] - sigma_t).abs() < 1e-6 && (b.hi[c] - sigma_t).abs() < 1e-6,
                        "{kind} {color:?} {density} {absorption_color:?}: bounds {b:?}, σt {sigma_t}"
                    );
                }
            }
        }
    }

    #[test]
    fn mixing_with_an_unclamped_factor_is_unbounded_outside_the_unit_interval() {
        let a = Bounds::scalar(0.0, 1.0);
        let b = Bounds::scalar(2.0, 3.0);
        assert_eq!(Bounds::mix(Bounds::UNIT, a, b), Bounds::scalar(0.0, 3.0));
        assert!(!Bounds::mix(Bounds::scalar(0.0, 2.0), a, b).is_finite());
    }
}
