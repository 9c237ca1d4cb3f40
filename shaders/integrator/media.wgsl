// The media a path is inside, for the volumetric path tracer (shaders/integrator/path.wgsl).
//
// Nesting rule: a path starts outside every object (the camera in vacuum). Crossing into
// an object that light passes through — through its surface's transmission or through a
// volume's bare boundary — pushes the medium of that object's inside: its volume
// (shaders/nodes/volume.wgsl), plus the Beer–Lambert absorption of a transmissive
// surface. Crossing out of it removes the innermost entry of that object's material,
// wherever it is in the stack. The medium a segment runs through is the innermost one, so
// a medium inside a glass inside fog sees the medium, then the glass's, then the fog's.
// Objects nested deeper than MEDIA_DEPTH are treated as vacuum inside.
//
// Volumes are homogeneous: their coefficients are the material buffer's, which the
// compiler computes from the volume node's constant inputs.

const MEDIA_DEPTH: u32 = 4u;

struct Media {
    count: u32,
    // The material whose inside each entry is.
    material: array<u32, 4>,
    medium: array<Medium, 4>,
    // Emitted radiance per unit length.
    emission: array<vec3<f32>, 4>,
};

fn media_empty() -> Media {
    var m: Media;
    m.count = 0u;
    return m;
}

// The media after entering the inside of `material`: its volume (the material buffer's)
// with `absorption` more (a transmissive surface's Beer–Lambert extinction).
fn media_entered(media_in: Media, material: u32, absorption: vec3<f32>) -> Media {
    var media = media_in;
    let i = media.count;
    if (i < MEDIA_DEPTH) {
        media.material[i] = material;
        media.medium[i] = material_medium(material, absorption);
        media.emission[i] = materials[material].volume_emission.xyz;
        media.count = i + 1u;
    }
    return media;
}

// The media after leaving the inside of `material`: its innermost entry is removed and
// the entries inside it move out by one. Leaving an object never entered (the camera
// inside it, or one nested too deep) changes nothing.
fn media_left(media_in: Media, material: u32) -> Media {
    var media = media_in;
    let n = media.count;
    var found = false;
    for (var k = 0u; k < n; k++) {
        let i = n - 1u - k;
        if (!found && media.material[i] == material) {
            found = true;
            for (var j = i; j + 1u < n; j++) {
                media.material[j] = media.material[j + 1u];
                media.medium[j] = media.medium[j + 1u];
                media.emission[j] = media.emission[j + 1u];
            }
        }
    }
    if (found) {
        media.count = n - 1u;
    }
    return media;
}

// The medium inside material `id`: its homogeneous volume (the material buffer's), with
// `absorption` more (a transmissive surface's Beer–Lambert extinction).
fn material_medium(id: u32, absorption: vec3<f32>) -> Medium {
    let m = materials[id];
    let sigma_s = max(m.volume_scattering.xyz, vec3<f32>(0.0));
    let sigma_t = max(m.volume_absorption.xyz, vec3<f32>(0.0)) + max(absorption, vec3<f32>(0.0)) + sigma_s;
    let albedo = select(vec3<f32>(0.0), min(sigma_s / sigma_t, vec3<f32>(1.0)), sigma_t > vec3<f32>(0.0));
    return Medium(sigma_t, albedo, m.volume_absorption.w);
}

// ∫₀ᵗ e^(-σt s) Le ds per channel: what an emitting medium adds along a segment.
fn medium_emission(m: Medium, emission: vec3<f32>, t: f32) -> vec3<f32> {
    let thick = m.sigma_t * t > vec3<f32>(1e-4);
    let exact = emission * (vec3<f32>(1.0) - exp(-m.sigma_t * t)) / m.sigma_t;
    // Thin: the series 1 - σt t / 2, which the formula above loses to rounding.
    let thin = emission * t * (vec3<f32>(1.0) - 0.5 * m.sigma_t * t);
    return select(thin, exact, thick);
}
