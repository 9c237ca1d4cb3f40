// Multiple-scattering energy compensation for rough dielectrics (Turquin 2019, "Practical
// multiple scattering compensation for microfacet models", §3): the single-scattering
// rough interface loses the energy of light bouncing between microfacets, and a white
// rough glass would darken with roughness. Scaling the lobe by 1 / E, where E is its
// directional energy albedo (reflection plus transmission, the 1/η² radiance scaling
// undone), restores it; E is tabulated from the shipped lobe for both sides of the
// interface by `cargo run --release --example albedo_tables` (src/render/tables/).
//
// Table layout: [side: outside, inside][IOR: (η-1)/(η+1) from 0 to 0.6, η 1 to 4]
// [roughness 0 to 1][cos θo 0 to 1], 16 entries per axis, trilinear.

const DIELECTRIC_ENERGY_SIZE: u32 = 16u;
const DIELECTRIC_ENERGY_MAX_F: f32 = 0.6;

fn dielectric_energy_at(i: u32) -> f32 {
    return dielectric_energy_table[i / 4u][i % 4u];
}

// E for light leaving toward wo (cos_o > 0: outside) at a material of IOR eta >= 1.
fn dielectric_energy(cos_o: f32, roughness: f32, eta: f32) -> f32 {
    let n = DIELECTRIC_ENERGY_SIZE;
    let last = f32(n - 1u);
    let side = select(1u, 0u, cos_o > 0.0);
    let f = clamp((eta - 1.0) / (eta + 1.0) / DIELECTRIC_ENERGY_MAX_F, 0.0, 1.0) * last;
    let r = clamp(roughness, 0.0, 1.0) * last;
    let m = clamp(abs(cos_o), 0.0, 1.0) * last;
    let f0 = min(u32(f), n - 2u);
    let r0 = min(u32(r), n - 2u);
    let m0 = min(u32(m), n - 2u);
    let tf = f - f32(f0);
    let tr = r - f32(r0);
    let tm = m - f32(m0);
    var e = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let df = k & 1u;
        let dr = (k >> 1u) & 1u;
        let dm = (k >> 2u) & 1u;
        let w = select(1.0 - tf, tf, df == 1u) * select(1.0 - tr, tr, dr == 1u) * select(1.0 - tm, tm, dm == 1u);
        let i = (((side * n + f0 + df) * n + r0 + dr) * n) + m0 + dm;
        e += w * dielectric_energy_at(i);
    }
    return clamp(e, 0.05, 1.0);
}

// The factor a rough (thin or solid) glass lobe is scaled by. A thin wall's two lobes
// together are the white GGX reflection lobe, whose albedo is the conductor table's.
fn dielectric_compensation(cos_o: f32, roughness: f32, eta: f32, thin: bool) -> f32 {
    if (thin) {
        return 1.0 / max(ggx_albedo(abs(cos_o), roughness), 0.05);
    }
    return 1.0 / dielectric_energy(cos_o, roughness, eta);
}
