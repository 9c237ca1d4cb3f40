//! The principled surface's parameters, declared once: the table in
//! [`principled_parameters!`]'s one invocation below. From it come the Rust
//! [`Principled`] struct a scene material holds, its defaults (Blender's) and valid ranges,
//! the scene file's material fields (by [`PARAMETERS`]), the packed form the material
//! buffer carries ([`Principled::pack`]), the WGSL `Principled` struct with its unpacking
//! and default ([`wgsl`]), and the sockets of the Principled BSDF node with the clamping of
//! what a graph feeds them.
//!
//! Adding a parameter is one row here and its use in `shaders/bsdf/principled.wgsl`.

use glam::Vec3;

/// What a parameter's values may be. Scene files and importers are checked against it
/// ([`Principled::validate`]); values a graph computes are clamped to it on the GPU
/// ([`Range::clamp_wgsl`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    /// In [0, 1] (each channel of a colour).
    Unit,
    /// Finite and at least 0.
    NonNegative,
    /// An index of refraction: finite and at least 1 (a graph's values are clamped to
    /// [1, 100]).
    Ior,
    /// Any finite number.
    Finite,
    /// On or off.
    Flag,
}

/// A parameter's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Float,
    Color,
    Bool,
}

/// A parameter's value, for code that handles parameters by name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamValue {
    Float(f32),
    Color(Vec3),
    Bool(bool),
}

/// The Rust types a parameter can have, with how each is packed for the GPU.
pub trait ParameterType: Copy {
    const KIND: Kind;
    /// How many f32 of the packed form it takes.
    const FLOATS: usize;
    fn value(self) -> ParamValue;
    fn from_value(value: ParamValue) -> Option<Self>;
    fn push_floats(self, out: &mut Vec<f32>);
}

impl ParameterType for f32 {
    const KIND: Kind = Kind::Float;
    const FLOATS: usize = 1;
    fn value(self) -> ParamValue {
        ParamValue::Float(self)
    }
    fn from_value(value: ParamValue) -> Option<Self> {
        match value {
            ParamValue::Float(x) => Some(x),
            _ => None,
        }
    }
    fn push_floats(self, out: &mut Vec<f32>) {
        out.push(self);
    }
}

impl ParameterType for Vec3 {
    const KIND: Kind = Kind::Color;
    const FLOATS: usize = 3;
    fn value(self) -> ParamValue {
        ParamValue::Color(self)
    }
    fn from_value(value: ParamValue) -> Option<Self> {
        match value {
            ParamValue::Color(c) => Some(c),
            _ => None,
        }
    }
    fn push_floats(self, out: &mut Vec<f32>) {
        out.extend(self.to_array());
    }
}

impl ParameterType for bool {
    const KIND: Kind = Kind::Bool;
    const FLOATS: usize = 1;
    fn value(self) -> ParamValue {
        ParamValue::Bool(self)
    }
    fn from_value(value: ParamValue) -> Option<Self> {
        match value {
            ParamValue::Bool(b) => Some(b),
            _ => None,
        }
    }
    fn push_floats(self, out: &mut Vec<f32>) {
        out.push(if self { 1.0 } else { 0.0 });
    }
}

/// One row of the table.
#[derive(Clone, Copy, Debug)]
pub struct Parameter {
    pub name: &'static str,
    pub kind: Kind,
    pub range: Range,
    pub doc: &'static str,
}

impl Parameter {
    /// Its value in [`Principled::default`].
    pub fn default_value(&self) -> ParamValue {
        Principled::default()
            .get(self.name)
            .expect("every parameter is a field")
    }
}

macro_rules! principled_parameters {
    ($($name:ident: $ty:ty = $default:expr, $range:ident, $doc:literal;)*) => {
        /// The principled surface: the parameters of Blender's Principled BSDF / OpenPBR
        /// Surface that `shaders/bsdf/principled.wgsl` evaluates. Defaults are Blender's.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Principled {
            $(#[doc = $doc] pub $name: $ty,)*
        }

        impl Default for Principled {
            fn default() -> Self {
                Self { $($name: $default,)* }
            }
        }

        /// Every parameter in the packed (and the WGSL struct's) order.
        pub const PARAMETERS: [Parameter; [$(stringify!($name)),*].len()] = [$(Parameter {
            name: stringify!($name),
            kind: <$ty as ParameterType>::KIND,
            range: Range::$range,
            doc: $doc,
        },)*];

        /// The f32s of the packed form.
        const PACKED_FLOATS: usize = 0 $(+ <$ty as ParameterType>::FLOATS)*;

        impl Principled {
            /// The parameter `name`, or `None` if there is none of that name.
            pub fn get(&self, name: &str) -> Option<ParamValue> {
                match name {
                    $(stringify!($name) => Some(self.$name.value()),)*
                    _ => None,
                }
            }

            /// Sets the parameter `name`; an error names an unknown parameter or a value
            /// of the wrong type (ranges are [`Principled::validate`]'s).
            pub fn set(&mut self, name: &str, value: ParamValue) -> Result<(), String> {
                match name {
                    $(stringify!($name) => {
                        self.$name = ParameterType::from_value(value).ok_or_else(|| {
                            format!("{name} takes {:?}, not {value:?}", <$ty as ParameterType>::KIND)
                        })?;
                    })*
                    _ => return Err(format!("no principled parameter is named {name}")),
                }
                Ok(())
            }

            /// The packed form `principled_unpack` reads: the parameters' f32s in table
            /// order (a flag as 0 or 1), zero-padded to whole vec4s.
            pub fn pack(&self) -> [[f32; 4]; PACKED_VEC4S] {
                let mut floats = Vec::with_capacity(PACKED_VEC4S * 4);
                $(self.$name.push_floats(&mut floats);)*
                floats.resize(PACKED_VEC4S * 4, 0.0);
                std::array::from_fn(|i| std::array::from_fn(|j| floats[4 * i + j]))
            }
        }
    };
}

principled_parameters! {
    base_color: Vec3 = Vec3::splat(0.8), Unit,
        "Diffuse albedo, or metal reflectance at normal incidence (linear RGB).";
    base_weight: f32 = 1.0, Unit, "Scales the base colour.";
    diffuse_roughness: f32 = 0.0, Unit, "Oren–Nayar roughness of the diffuse base; 0 is Lambertian.";
    metallic: f32 = 0.0, Unit, "0 dielectric, 1 metal.";
    roughness: f32 = 0.5, Unit, "Perceptual roughness (GGX alpha = roughness²).";
    anisotropy: f32 = 0.0, Unit, "Stretches highlights along the tangent.";
    anisotropy_rotation: f32 = 0.0, Finite,
        "Turns the tangent about the normal, in turns (0.25 is 90°); the tangent follows the texture's u direction where the mesh has UVs.";
    ior: f32 = 1.5, Ior, "Index of refraction.";
    specular_weight: f32 = 1.0, NonNegative, "Scales dielectric reflection.";
    specular_color: Vec3 = Vec3::ONE, Unit,
        "Tints dielectric reflection; for metals, the edge tint at 82° (F82).";
    transmission_weight: f32 = 0.0, Unit, "0 opaque, 1 glass.";
    transmission_color: Vec3 = Vec3::ONE, Unit,
        "Glass tint; in a thin wall, the tint of everything that passes through it (glass and diffuse transmission).";
    transmission_depth: f32 = 0.0, NonNegative,
        "Depth at which light inside reaches the transmission colour (Beer–Lambert); 0 tints the surface instead.";
    subsurface_weight: f32 = 0.0, Unit,
        "Share of the diffuse base that enters the object and scatters inside it (a random walk) before leaving; in a thin wall, that passes through it diffusely (translucency).";
    subsurface_radius: Vec3 = Vec3::new(1.0, 0.2, 0.1), NonNegative,
        "Mean free path per channel, times the subsurface scale: how far each colour travels under the surface.";
    subsurface_scale: f32 = 0.05, NonNegative, "Scales the subsurface radius, in scene units.";
    subsurface_anisotropy: f32 = 0.0, Unit,
        "Forward scattering inside the object (Henyey–Greenstein g); 0 is isotropic.";
    subsurface_ior: f32 = 1.4, Ior,
        "Index of refraction of the surface light enters the walk through (clamped to [1.01, 3.8], as in Cycles): higher bends entering light further toward the normal.";
    coat_weight: f32 = 0.0, Unit, "Clear coat amount.";
    coat_roughness: f32 = 0.03, Unit, "Coat roughness.";
    coat_ior: f32 = 1.5, Ior, "Coat index of refraction.";
    coat_color: Vec3 = Vec3::ONE, Unit, "Tints what lies under the coat.";
    sheen_weight: f32 = 0.0, Unit, "Microfibre sheen amount.";
    sheen_color: Vec3 = Vec3::ONE, Unit, "Sheen colour.";
    sheen_roughness: f32 = 0.3, Unit, "Sheen roughness.";
    emission_color: Vec3 = Vec3::ONE, NonNegative, "Emitted colour, from the front side.";
    emission_strength: f32 = 0.0, NonNegative, "Emitted radiance per unit of colour.";
    alpha: f32 = 1.0, Unit, "Opacity: 1 opaque, 0 invisible (alpha cut-out); shadows let 1 − alpha of the light through.";
    thin_walled: bool = false, Flag,
        "A surface with no inside (leaves, paper, soap film): light passes without bending, and subsurface becomes diffuse transmission.";
}

/// The vec4s of the packed form (`PRINCIPLED_VEC4S` in WGSL).
pub const PACKED_VEC4S: usize = PACKED_FLOATS.div_ceil(4);

impl Principled {
    /// The parameter of `name` in the table, if any.
    pub fn parameter(name: &str) -> Option<&'static Parameter> {
        PARAMETERS.iter().find(|p| p.name == name)
    }

    /// Emitted radiance: the emission colour times its strength.
    pub fn emission(&self) -> Vec3 {
        self.emission_color * self.emission_strength
    }

    /// Every parameter within its [`Range`]; the error names the first that is not.
    pub fn validate(&self) -> Result<(), String> {
        for p in &PARAMETERS {
            let value = self.get(p.name).expect("every parameter is a field");
            let channels = match value {
                ParamValue::Float(x) => vec![x],
                ParamValue::Color(c) => c.to_array().to_vec(),
                ParamValue::Bool(_) => continue,
            };
            let shown = match value {
                ParamValue::Color(c) => format!("{c}"),
                ParamValue::Float(x) => format!("{x}"),
                ParamValue::Bool(b) => format!("{b}"),
            };
            let (ok, must): (fn(f32) -> bool, &str) = match p.range {
                Range::Unit => (|x| (0.0..=1.0).contains(&x), "must lie in [0, 1]"),
                Range::NonNegative => (
                    |x| x.is_finite() && x >= 0.0,
                    "must be finite and non-negative",
                ),
                Range::Ior => (|x| x.is_finite() && x >= 1.0, "must be at least 1"),
                Range::Finite => (f32::is_finite, "must be finite"),
                Range::Flag => continue,
            };
            if !channels.into_iter().all(ok) {
                return Err(format!("{} {shown} {must}", p.name));
            }
        }
        Ok(())
    }
}

impl Range {
    /// WGSL bringing `value` (of `kind`, default `default`) into the range, for values a
    /// graph computes: non-finite values become the default (0 for colours).
    pub fn clamp_wgsl(self, kind: Kind, value: &str, default: f32) -> String {
        let d = wgsl_float(default);
        match (self, kind) {
            (Range::Unit, Kind::Color) => format!("nd_unit3({value})"),
            (Range::Unit, _) => format!("nd_unit({value})"),
            (Range::NonNegative, Kind::Color) => {
                format!("max(nd_finite3({value}), vec3<f32>(0.0))")
            }
            (Range::NonNegative, _) => format!("max(nd_finite({value}, {d}), 0.0)"),
            (Range::Ior, _) => format!("clamp(nd_finite({value}, {d}), 1.0, 100.0)"),
            (Range::Finite, Kind::Color) => format!("nd_finite3({value})"),
            (Range::Finite, _) => format!("nd_finite({value}, {d})"),
            (Range::Flag, _) => value.to_owned(),
        }
    }
}

/// An f32 as a WGSL abstract float literal.
fn wgsl_float(x: f32) -> String {
    format!("{x:?}")
}

/// A value as a WGSL expression.
pub fn wgsl_value(value: ParamValue) -> String {
    match value {
        ParamValue::Float(x) => wgsl_float(x),
        ParamValue::Color(c) => format!(
            "vec3<f32>({}, {}, {})",
            wgsl_float(c.x),
            wgsl_float(c.y),
            wgsl_float(c.z)
        ),
        ParamValue::Bool(b) => format!("{b}"),
    }
}

/// The WGSL of the table: `PRINCIPLED_VEC4S`, `struct Principled`, `principled_unpack`
/// (the packed form back to the struct) and `principled_default` (Blender's defaults).
/// Kernel assembly puts it before the shader files that use it.
pub fn wgsl() -> String {
    let mut text =
        format!("const PRINCIPLED_VEC4S: u32 = {PACKED_VEC4S}u;\n\nstruct Principled {{\n");
    for p in &PARAMETERS {
        let ty = match p.kind {
            Kind::Float => "f32",
            Kind::Color => "vec3<f32>",
            Kind::Bool => "bool",
        };
        text.push_str(&format!("    // {}\n    {}: {ty},\n", p.doc, p.name));
    }
    text.push_str("};\n\n");
    text.push_str(&format!(
        "// The packed form of the material buffer (src/shader/principled.rs).\n\
         fn principled_unpack(m: array<vec4<f32>, {PACKED_VEC4S}>) -> Principled {{\n    return Principled(\n"
    ));
    let at = |i: usize| format!("m[{}].{}", i / 4, ["x", "y", "z", "w"][i % 4]);
    let mut next = 0;
    for p in &PARAMETERS {
        let expr = match p.kind {
            Kind::Float => at(next),
            Kind::Color => format!(
                "vec3<f32>({}, {}, {})",
                at(next),
                at(next + 1),
                at(next + 2)
            ),
            Kind::Bool => format!("{} != 0.0", at(next)),
        };
        next += if p.kind == Kind::Color { 3 } else { 1 };
        text.push_str(&format!("        {expr},\n"));
    }
    text.push_str("    );\n}\n\n");
    text.push_str(
        "// Blender's defaults.\nfn principled_default() -> Principled {\n    return Principled(\n",
    );
    for p in &PARAMETERS {
        text.push_str(&format!("        {},\n", wgsl_value(p.default_value())));
    }
    text.push_str("    );\n}\n");
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_get_and_set_cover_every_row() {
        let mut names: Vec<&str> = PARAMETERS.iter().map(|p| p.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), PARAMETERS.len());
        let mut p = Principled::default();
        for row in &PARAMETERS {
            let changed = match row.default_value() {
                ParamValue::Float(x) => ParamValue::Float(x + 0.25),
                ParamValue::Color(c) => ParamValue::Color(c * 0.5),
                ParamValue::Bool(b) => ParamValue::Bool(!b),
            };
            p.set(row.name, changed).unwrap();
            assert_eq!(p.get(row.name), Some(changed), "{}", row.name);
        }
        assert!(p.set("roughness", ParamValue::Bool(true)).is_err());
        assert!(p.set("no_such", ParamValue::Float(0.0)).is_err());
    }

    #[test]
    fn packing_puts_each_parameter_at_its_place_in_table_order() {
        let p = Principled {
            base_color: Vec3::new(0.1, 0.2, 0.3),
            base_weight: 0.4,
            thin_walled: true,
            ..Principled::default()
        };
        let packed = p.pack();
        let floats: Vec<f32> = packed.iter().flatten().copied().collect();
        assert_eq!(&floats[..4], &[0.1, 0.2, 0.3, 0.4]);
        assert_eq!(floats[PACKED_FLOATS - 1], 1.0, "the flag is last");
        assert!(floats[PACKED_FLOATS..].iter().all(|&x| x == 0.0));
    }

    #[test]
    fn validation_names_the_parameter_and_its_range() {
        assert_eq!(Principled::default().validate(), Ok(()));
        let cases = [
            (
                "roughness",
                ParamValue::Float(1.5),
                "roughness 1.5 must lie in [0, 1]",
            ),
            ("ior", ParamValue::Float(0.5), "ior 0.5 must be at least 1"),
            (
                "emission_color",
                ParamValue::Color(Vec3::new(1.0, -1.0, 0.0)),
                "emission_color [1, -1, 0] must be finite and non-negative",
            ),
            (
                "anisotropy_rotation",
                ParamValue::Float(f32::NAN),
                "anisotropy_rotation NaN must be finite",
            ),
        ];
        for (name, value, message) in cases {
            let mut p = Principled::default();
            p.set(name, value).unwrap();
            assert_eq!(p.validate(), Err(message.to_owned()));
        }
    }
}
