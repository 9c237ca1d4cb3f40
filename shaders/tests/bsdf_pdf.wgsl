// Test kernel: integrates each lobe configuration's pdf over each cell of the chi-square
// binning (tests/common/chi2.rs SphereBins), one invocation per (configuration, cell).
//
// A k × k midpoint rule in (cos θ, φ), exact for pdfs constant or linear in cos θ, with the
// cell's corners and edges evaluated too so that peaks and the hard edges of a lobe's
// support (refraction folds directions into a boundary where the pdf jumps to 0) are
// noticed even when no midpoint falls on them. Cells whose values vary by more than 2x
// are integrated again with a FINE × FINE midpoint rule in (θ, φ) weighted by sin θ:
// near the poles uniform steps in θ resolve narrow lobes that steps in cos θ cannot.
//
// The fine rule's band edges in θ come from the host (computed in f64): lavapipe's acos errs
// by up to 1.6e-4 rad, which would shift every band by up to half a percent of its width
// and bias the integrals by as much, at every quadrature order alike.
//
// probe_in: [0] = (configs, 0, theta bins, phi bins), [1] = (0, 0, k, fine), then CONFIG_STRIDE
// vec4s per configuration, whose first vec4's z and w, when not 0, set `fine` and `k` for it,
// then the bands' θ edges (theta bins + 1, f32 bits in x). probe_out: configs × cells
// probabilities (f32).

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<f32>;

fn direction_z(z: f32, phi: f32) -> vec3<f32> {
    let r = sqrt(max(0.0, 1.0 - z * z));
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// Returns (integral, spread): spread is max / min of all values seen, 3e38 when some are
// 0 and some not, 0 when all are 0.
fn integrate_coarse(p: LobeParams, z_top: f32, dz: f32, f0: f32, dphi: f32, k: u32) -> vec2<f32> {
    var sum = 0.0;
    var lo = 3.0e38;
    var hi = 0.0;
    // Lattice 0..=2k: odd × odd points are the midpoints, even × even the corners and edges.
    for (var i = 0u; i <= 2u * k; i++) {
        let z = z_top - f32(i) * 0.5 * dz / f32(k);
        for (var j = 0u; j <= 2u * k; j++) {
            let odd = (i & 1u) == 1u && (j & 1u) == 1u;
            let even = (i & 1u) == 0u && (j & 1u) == 0u;
            if (!odd && !even) {
                continue;
            }
            let v = lobe_pdf(p, direction_z(z, f0 + f32(j) * 0.5 * dphi / f32(k)));
            lo = min(lo, v);
            hi = max(hi, v);
            if (odd) {
                sum += v;
            }
        }
    }
    var spread = 0.0;
    if (hi > 0.0) {
        spread = select(3.0e38, hi / lo, lo > 0.0);
    }
    return vec2<f32>(sum * dz * dphi / f32(k * k), spread);
}

fn integrate_fine(p: LobeParams, t0: f32, t1: f32, dz: f32, f0: f32, dphi: f32, k: u32) -> f32 {
    let dt = (t1 - t0) / f32(k);
    var sum = 0.0;
    var weights = 0.0;
    for (var i = 0u; i < k; i++) {
        let theta = t0 + (f32(i) + 0.5) * dt;
        let st = sin(theta);
        let ct = cos(theta);
        var row = 0.0;
        for (var j = 0u; j < k; j++) {
            let phi = f0 + (f32(j) + 0.5) * dphi / f32(k);
            row += lobe_pdf(p, vec3<f32>(st * cos(phi), st * sin(phi), ct));
        }
        sum += row * st;
        weights += st;
    }
    // Normalised by the rule's own weights, so a constant pdf gets the exact solid angle.
    return sum / (weights * f32(k)) * dz * dphi;
}

@compute @workgroup_size(64)
fn bsdf_pdf(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = gid.x + gid.y * groups.x * 64u;
    let header = probe_in[0];
    let cells = header.z * header.w;
    if (index >= header.x * cells) {
        return;
    }
    let config = index / cells;
    let cell = index % cells;
    let p = lobe_params(2u + CONFIG_STRIDE * config);
    let dz = 2.0 / f32(header.z);
    let dphi = 2.0 * PI / f32(header.w);
    let z_top = 1.0 - f32(cell / header.w) * dz;
    let f0 = f32(cell % header.w) * dphi;
    // A configuration may set its own orders (expensive mixtures use lower ones: lavapipe
    // returns wrong results from invocations that run for too long).
    let own = probe_in[2u + CONFIG_STRIDE * config];
    let k = select(probe_in[1].z, own.w, own.w != 0u);
    let fine = select(probe_in[1].w, own.z, own.z != 0u);
    let coarse = integrate_coarse(p, z_top, dz, f0, dphi, k);
    var total = coarse.x;
    if (coarse.y > 2.0) {
        let edges = 2u + CONFIG_STRIDE * header.x;
        let band = cell / header.w;
        let t0 = bitcast<f32>(probe_in[edges + band].x);
        let t1 = bitcast<f32>(probe_in[edges + band + 1u].x);
        total = integrate_fine(p, t0, t1, dz, f0, dphi, fine);
    }
    probe_out[index] = total;
}
