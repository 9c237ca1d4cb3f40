// Volume shaders, as Blender's: what fills the inside of a closed mesh. Coefficients are
// per scene unit; the integrator (shaders/integrator/path.wgsl) samples free flights
// through them and scatters by Henyey–Greenstein (shaders/media/phase.wgsl).

// A volume at a point: absorption σa and scattering σs per channel and unit length, the
// emitted radiance per unit length, and the phase function's anisotropy g.
struct VolumeEval {
    absorption: vec3<f32>,
    scattering: vec3<f32>,
    emission: vec3<f32>,
    g: f32,
};

// The phase function's |g| is kept below 0.999 (HG_MAX_G of shaders/media/phase.wgsl):
// at ±1 it is a delta.

// An empty inside: no absorption, scattering or emission.
fn nd_no_volume() -> VolumeEval {
    return VolumeEval(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
}

// The material output: the surface with the volume inside it.
fn nd_material_output(surface: MaterialEval, volume: VolumeEval) -> MaterialEval {
    var m = surface;
    m.volume = volume;
    return m;
}

// Volume Absorption: light passing through loses 1 - colour per unit of density.
fn nd_volume_absorption(color: vec3<f32>, density: f32) -> VolumeEval {
    let d = max(density, 0.0);
    let a = (vec3<f32>(1.0) - clamp(color, vec3<f32>(0.0), vec3<f32>(1.0))) * d;
    return VolumeEval(a, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
}

// Volume Scatter: light is scattered by colour × density per unit length, without
// absorption.
fn nd_volume_scatter(color: vec3<f32>, density: f32, anisotropy: f32) -> VolumeEval {
    let d = max(density, 0.0);
    let s = max(color, vec3<f32>(0.0)) * d;
    return VolumeEval(vec3<f32>(0.0), s, vec3<f32>(0.0), clamp(anisotropy, -0.999, 0.999));
}

// Principled Volume, as Cycles' (svm_node_principled_volume): scattering colour × density,
// absorption (1 - colour)(1 - √absorption colour) × density, emission strength × colour.
fn nd_principled_volume(
    color: vec3<f32>,
    density: f32,
    anisotropy: f32,
    absorption_color: vec3<f32>,
    emission_strength: f32,
    emission_color: vec3<f32>,
) -> VolumeEval {
    let d = max(density, 0.0);
    let c = max(color, vec3<f32>(0.0));
    let tint = max(vec3<f32>(1.0) - sqrt(max(absorption_color, vec3<f32>(0.0))), vec3<f32>(0.0));
    let absorption = max(vec3<f32>(1.0) - c, vec3<f32>(0.0)) * tint * d;
    let emission = max(emission_color, vec3<f32>(0.0)) * max(emission_strength, 0.0);
    return VolumeEval(absorption, c * d, emission, clamp(anisotropy, -0.999, 0.999));
}
