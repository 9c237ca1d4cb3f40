// Conservative floating-point error bounds and ray-origin offsets, after pbrt-v4
// (Pharr, Jakob, Humphreys, 4th ed., §6.8). Errors are bounded relative to the magnitudes
// of the values involved, so the offsets scale with the scene: a scene at 1e-3 or 1e4
// units self-intersects no more than one at 1.

const MACHINE_EPSILON: f32 = 5.9604645e-8; // 2^-24, half an ulp of 1

fn gamma(n: f32) -> f32 {
    return (n * MACHINE_EPSILON) / (1.0 - n * MACHINE_EPSILON);
}

fn next_float_up(v: f32) -> f32 {
    if (v == 0.0) {
        return 1.4e-45;
    }
    let bits = bitcast<u32>(v);
    if (v > 0.0) {
        return bitcast<f32>(bits + 1u);
    }
    return bitcast<f32>(bits - 1u);
}

fn next_float_down(v: f32) -> f32 {
    if (v == 0.0) {
        return -1.4e-45;
    }
    let bits = bitcast<u32>(v);
    if (v > 0.0) {
        return bitcast<f32>(bits - 1u);
    }
    return bitcast<f32>(bits + 1u);
}

// A point with a per-component absolute error bound.
struct PointError {
    p: vec3<f32>,
    err: vec3<f32>,
};

// Applies an affine 3x4 transform (rows) to a point, growing its error bound
// (pbrt-v4 Transform::operator()(Point3fi)).
fn transform_point_error(m: array<vec4<f32>, 3>, pe: PointError) -> PointError {
    let p = vec4<f32>(pe.p, 1.0);
    let out = vec3<f32>(dot(m[0], p), dot(m[1], p), dot(m[2], p));
    let ap = abs(p);
    let g3 = gamma(3.0);
    var err = g3 * vec3<f32>(dot(abs(m[0]), ap), dot(abs(m[1]), ap), dot(abs(m[2]), ap));
    err += (1.0 + g3) * vec3<f32>(
        dot(abs(m[0].xyz), pe.err),
        dot(abs(m[1].xyz), pe.err),
        dot(abs(m[2].xyz), pe.err)
    );
    return PointError(out, err);
}

// Moves a ray origin off a surface along the geometric normal, far enough that the
// spawned ray cannot re-hit the surface it leaves, then rounds away from it.
fn offset_ray_origin(pe: PointError, n: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let d = dot(abs(n), pe.err);
    var offset = d * n;
    if (dot(w, n) < 0.0) {
        offset = -offset;
    }
    var po = pe.p + offset;
    for (var i = 0; i < 3; i++) {
        if (offset[i] > 0.0) {
            po[i] = next_float_up(po[i]);
        } else if (offset[i] < 0.0) {
            po[i] = next_float_down(po[i]);
        }
    }
    return po;
}
