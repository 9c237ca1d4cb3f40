// Node library: the Sky Texture, a clear sky by single scattering in a spherical
// atmosphere (Nishita, Sirai, Tadamura and Nakamae 1993, "Display of the Earth taking
// into account atmospheric scattering"; Cycles' Nishita sky is the same model): Rayleigh
// scattering by air, Mie scattering and absorption by aerosols ("dust") and absorption by
// ozone, integrated along the view ray with the sunlight that reaches each point, at 16
// wavelengths from 380 to 755 nm, then turned into linear Rec. 709 RGB through the CIE
// 1931 colour-matching functions.
//
// Units: spectral radiance in W/(m²·sr·nm) averaged under the CIE ȳ curve, so a colour's
// luminance Y is the ȳ-weighted mean of its spectrum: the sun above the atmosphere gives
// an irradiance of Y ≈ 1.7 (1361 W/m² in all).
//
// The sun's disc is not part of `color`: `sun` is its irradiance on a surface facing it
// (after the atmosphere), and the renderer adds the disc as a distant light of that
// irradiance and the node's sun size (src/render/world_bake.rs), sampled analytically.
// Directions are world space with +Y up; below the horizon the view ray ends at a matte
// ground of albedo `ground_albedo` that the sun lights (the sky's light on it is left
// out), seen through the haze in front of it.

struct NdSky {
    color: vec3<f32>,
    sun: vec3<f32>,
}

const SKY_EARTH_RADIUS: f32 = 6360000.0;
const SKY_ATMOSPHERE_RADIUS: f32 = 6420000.0;
// Scale heights of air and aerosols (m).
const SKY_RAYLEIGH_HEIGHT: f32 = 8000.0;
const SKY_MIE_HEIGHT: f32 = 1200.0;
// Rayleigh scattering of air at sea level: 8π³(n² − 1)² F / (3 N λ⁴) with n − 1 =
// 2.793e-4, N = 2.545e25 molecules/m³ and the King factor F = (6 + 3δ)/(6 − 7δ), δ =
// 0.035; this constant is the numerator over 3N, per metre for λ in micrometres.
const SKY_RAYLEIGH_K: f32 = 1.0757e-6;
// Aerosol scattering at sea level (per m, dust = 1), its extinction (a tenth more:
// single-scattering albedo 0.9) and its phase function's mean cosine.
const SKY_MIE_SCATTERING: f32 = 2e-5;
const SKY_MIE_EXTINCTION: f32 = 2.222e-5;
const SKY_MIE_G: f32 = 0.76;
// Ozone: a layer from 10 to 40 km whose density peaks at 25 km, holding a column of 300
// Dobson units (8.07e22 molecules/m²) at ozone = 1.
const SKY_OZONE_PEAK: f32 = 5.38e18;
// Ozone's absorption cross-section (m²) at the 16 wavelengths, the Chappuis band
// (after Serdyuchenko et al. 2014, room temperature; to about 20%).
const SKY_OZONE_CROSS_SECTION: array<vec4<f32>, 4> = array<vec4<f32>, 4>(
    vec4<f32>(0.0, 0.01e-25, 0.1e-25, 0.35e-25),
    vec4<f32>(0.9e-25, 1.9e-25, 3.0e-25, 3.9e-25),
    vec4<f32>(4.7e-25, 5.1e-25, 4.2e-25, 2.7e-25),
    vec4<f32>(1.7e-25, 1.0e-25, 0.65e-25, 0.45e-25),
);
// The sun above the atmosphere: a black body at 5778 K whose spectrum integrates to the
// solar constant, 1361 W/m².
const SKY_SUN_TEMPERATURE: f32 = 5778.0;
const SKY_SOLAR_CONSTANT: f32 = 1361.0;
const SKY_VIEW_STEPS: u32 = 16u;
const SKY_LIGHT_STEPS: u32 = 8u;

// Wavelengths (nm) of lanes 4k .. 4k + 3.
fn sky_wavelengths(k: u32) -> vec4<f32> {
    return 380.0 + 25.0 * (4.0 * f32(k) + vec4<f32>(0.0, 1.0, 2.0, 3.0));
}

// Rayleigh scattering coefficient at sea level (per m) at wavelengths `nm`.
fn sky_rayleigh(nm: vec4<f32>) -> vec4<f32> {
    let um = nm * 0.001;
    return SKY_RAYLEIGH_K / (um * um * um * um);
}

// The sun's spectral irradiance above the atmosphere (W/m²/nm): Planck's law at
// SKY_SUN_TEMPERATURE, scaled to the solar constant (π B(λ) / σT⁴ per nm).
fn sky_sun_spectrum(nm: vec4<f32>) -> vec4<f32> {
    let m = nm * 1e-9;
    let planck = 1.191042e-16 / (m * m * m * m * m) / (exp(0.01438777 / (m * SKY_SUN_TEMPERATURE)) - 1.0);
    let sigma_t4 = 5.670374e-8 * pow(SKY_SUN_TEMPERATURE, 4.0);
    return SKY_SOLAR_CONSTANT * 3.14159265 * planck / sigma_t4 * 1e-9;
}

// The CIE 1931 2° colour-matching functions at `nm`, by the multi-lobe fit of Wyman,
// Sloan and Shirley 2013 ("Simple analytic approximations to the CIE XYZ color matching
// functions").
fn sky_cmf(nm: f32) -> vec3<f32> {
    let x = 1.056 * sky_lobe(nm, 599.8, 37.9, 31.0) + 0.362 * sky_lobe(nm, 442.0, 16.0, 26.7)
        - 0.065 * sky_lobe(nm, 501.1, 20.4, 26.2);
    let y = 0.821 * sky_lobe(nm, 568.8, 46.9, 40.5) + 0.286 * sky_lobe(nm, 530.9, 16.3, 31.1);
    let z = 1.217 * sky_lobe(nm, 437.0, 11.8, 36.0) + 0.681 * sky_lobe(nm, 459.0, 26.0, 13.8);
    return vec3<f32>(x, y, z);
}

fn sky_lobe(nm: f32, mean: f32, below: f32, above: f32) -> f32 {
    let t = (nm - mean) / select(above, below, nm < mean);
    return exp(-0.5 * t * t);
}

// A spectrum (16 lanes) as linear Rec. 709 RGB whose Y is its ȳ-weighted mean.
fn sky_to_rgb(s: array<vec4<f32>, 4>) -> vec3<f32> {
    var xyz = vec3<f32>(0.0);
    var y_sum = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let nm = sky_wavelengths(k);
        for (var j = 0u; j < 4u; j++) {
            let w = sky_cmf(nm[j]);
            xyz += s[k][j] * w;
            y_sum += w.y;
        }
    }
    xyz /= y_sum;
    return vec3<f32>(
        3.2404542 * xyz.x - 1.5371385 * xyz.y - 0.4985314 * xyz.z,
        -0.9692660 * xyz.x + 1.8760108 * xyz.y + 0.0415560 * xyz.z,
        0.0556434 * xyz.x - 0.2040259 * xyz.y + 1.0572252 * xyz.z,
    );
}

// Densities relative to sea level at height `h` (m): air, aerosols, ozone (relative to
// its peak).
fn sky_density(h: f32) -> vec3<f32> {
    return vec3<f32>(
        exp(-h / SKY_RAYLEIGH_HEIGHT),
        exp(-h / SKY_MIE_HEIGHT),
        max(0.0, 1.0 - abs(h - 25000.0) / 15000.0),
    );
}

// Distance from `o` (inside the sphere of radius `r` about the Earth's centre) along unit
// `d` to where the ray leaves it.
fn sky_exit(o: vec3<f32>, d: vec3<f32>, r: f32) -> f32 {
    let b = dot(o, d);
    let c = dot(o, o) - r * r;
    return -b + sqrt(max(b * b - c, 0.0));
}

// Distance from `o` along unit `d` to the ground, or -1 where the ray misses it.
fn sky_ground(o: vec3<f32>, d: vec3<f32>) -> f32 {
    let b = dot(o, d);
    let c = dot(o, o) - SKY_EARTH_RADIUS * SKY_EARTH_RADIUS;
    let disc = b * b - c;
    if (b > 0.0 || disc < 0.0) {
        return -1.0;
    }
    return -b - sqrt(disc);
}

// Density integrals (m at sea-level density: air, aerosols, ozone) from `o` along unit
// `d` to the top of the atmosphere; w = 0 where the ground is in the way.
fn sky_column(o: vec3<f32>, d: vec3<f32>, steps: u32) -> vec4<f32> {
    if (sky_ground(o, d) > 0.0) {
        return vec4<f32>(0.0);
    }
    let dt = sky_exit(o, d, SKY_ATMOSPHERE_RADIUS) / f32(steps);
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < steps; i++) {
        let p = o + d * ((f32(i) + 0.5) * dt);
        depth += sky_density(length(p) - SKY_EARTH_RADIUS) * dt;
    }
    return vec4<f32>(depth, 1.0);
}

// Optical depth of density integrals `column` (air, aerosols, ozone) for lanes 4k..4k+3,
// with the densities scaled by `amounts` (the node's air, dust and ozone).
fn sky_optical_depth(column: vec3<f32>, amounts: vec3<f32>, k: u32) -> vec4<f32> {
    let c = column * amounts;
    return sky_rayleigh(sky_wavelengths(k)) * c.x + SKY_MIE_EXTINCTION * c.y
        + SKY_OZONE_CROSS_SECTION[k] * (SKY_OZONE_PEAK * c.z);
}

// Unit direction toward the sun for an elevation and a rotation (degrees): rotation 0
// puts the sun toward -Z, 90 toward +X.
fn sky_sun_direction(elevation: f32, rotation: f32) -> vec3<f32> {
    let e = radians(elevation);
    let r = radians(rotation);
    return vec3<f32>(cos(e) * sin(r), sin(e), -cos(e) * cos(r));
}

// Sky Texture: the sky's radiance along `direction` (`color`, without the sun's disc)
// and the sun's irradiance (`sun`, 0 with the disc off or the sun below the horizon).
fn nd_sky(
    direction: vec3<f32>,
    elevation: f32,
    rotation: f32,
    altitude: f32,
    air: f32,
    dust: f32,
    ozone: f32,
    ground_albedo: f32,
    sun_intensity: f32,
    disc: bool,
) -> NdSky {
    let amounts = max(vec3<f32>(air, dust, ozone), vec3<f32>(0.0));
    let o = vec3<f32>(0.0, SKY_EARTH_RADIUS + clamp(altitude, 1.0, 59000.0), 0.0);
    let d = select(vec3<f32>(0.0, 1.0, 0.0), normalize(direction), dot(direction, direction) > 0.0);
    let s = sky_sun_direction(elevation, rotation);
    let ground = sky_ground(o, d);
    let far = select(sky_exit(o, d, SKY_ATMOSPHERE_RADIUS), ground, ground > 0.0);
    let dt = far / f32(SKY_VIEW_STEPS);
    var view = vec3<f32>(0.0);
    var air_sum: array<vec4<f32>, 4>;
    var dust_sum: array<vec4<f32>, 4>;
    for (var i = 0u; i < SKY_VIEW_STEPS; i++) {
        let p = o + d * ((f32(i) + 0.5) * dt);
        let segment = sky_density(length(p) - SKY_EARTH_RADIUS) * dt;
        let to_point = view + 0.5 * segment;
        view += segment;
        let light = sky_column(p, s, SKY_LIGHT_STEPS);
        if (light.w == 0.0) {
            continue;
        }
        for (var k = 0u; k < 4u; k++) {
            let kept = exp(-sky_optical_depth(to_point + light.xyz, amounts, k));
            air_sum[k] += kept * segment.x;
            dust_sum[k] += kept * segment.y;
        }
    }
    let mu = dot(d, s);
    let rayleigh_phase = 3.0 / (16.0 * 3.14159265) * (1.0 + mu * mu);
    let g = SKY_MIE_G;
    let mie_phase = 3.0 / (8.0 * 3.14159265) * (1.0 - g * g) * (1.0 + mu * mu)
        / ((2.0 + g * g) * pow(1.0 + g * g - 2.0 * g * mu, 1.5));
    var radiance: array<vec4<f32>, 4>;
    var sun: array<vec4<f32>, 4>;
    let sun_column = sky_column(o, s, SKY_VIEW_STEPS);
    // Where the view ray ends at the ground: a Lambertian surface of `ground_albedo` lit
    // by the sun through the atmosphere (not by the sky), seen through the air between.
    var ground_light = vec4<f32>(0.0);
    if (ground > 0.0) {
        let g = o + d * ground;
        ground_light = sky_column(g, s, SKY_LIGHT_STEPS);
        ground_light.w *= max(dot(normalize(g), s), 0.0) * clamp(ground_albedo, 0.0, 1.0) / 3.14159265;
    }
    for (var k = 0u; k < 4u; k++) {
        let nm = sky_wavelengths(k);
        let e = sky_sun_spectrum(nm);
        radiance[k] = e * (sky_rayleigh(nm) * amounts.x * rayleigh_phase * air_sum[k]
            + SKY_MIE_SCATTERING * amounts.y * mie_phase * dust_sum[k]);
        if (ground_light.w > 0.0) {
            radiance[k] += e * ground_light.w
                * exp(-sky_optical_depth(view + ground_light.xyz, amounts, k));
        }
        sun[k] = e * exp(-sky_optical_depth(sun_column.xyz, amounts, k)) * sun_column.w
            * select(0.0, max(sun_intensity, 0.0), disc);
    }
    return NdSky(max(sky_to_rgb(radiance), vec3<f32>(0.0)), max(sky_to_rgb(sun), vec3<f32>(0.0)));
}

// World Output: the radiance arriving from the direction the world is evaluated toward.
fn nd_world_output(color: vec3<f32>, strength: f32) -> vec3<f32> {
    return max(color, vec3<f32>(0.0)) * max(strength, 0.0);
}
