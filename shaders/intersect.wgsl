// Ray–primitive tests: the watertight ray–triangle test (Woop, Benthin & Wald 2013, in
// pbrt-v4's form with its conservative t bound) and a slab test whose far distance is
// widened by the rounding error, so boxes never cull a triangle the triangle test hits.

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
};

// Per-ray constants of the watertight test: the permutation making z the dominant
// direction axis and the shear that maps the ray onto +z.
struct RayShear {
    kx: i32,
    ky: i32,
    kz: i32,
    shear: vec3<f32>,
};

fn ray_shear(dir: vec3<f32>) -> RayShear {
    let a = abs(dir);
    var kz = 0;
    if (a.y > a.x && a.y >= a.z) {
        kz = 1;
    } else if (a.z > a.x && a.z > a.y) {
        kz = 2;
    }
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    let dz = dir[kz];
    return RayShear(kx, ky, kz, vec3<f32>(-dir[kx] / dz, -dir[ky] / dz, 1.0 / dz));
}

struct TriangleHit {
    hit: bool,
    t: f32,
    b1: f32,
    b2: f32,
};

fn difference_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let cd = c * d;
    let err = fma(-c, d, cd);
    let dop = fma(a, b, -cd);
    return dop + err;
}

fn intersect_triangle(
    ray: Ray,
    rs: RayShear,
    t_max: f32,
    p0: vec3<f32>,
    p1: vec3<f32>,
    p2: vec3<f32>,
) -> TriangleHit {
    let miss = TriangleHit(false, 0.0, 0.0, 0.0);
    let a = p0 - ray.origin;
    let b = p1 - ray.origin;
    let c = p2 - ray.origin;
    var p0t = vec3<f32>(a[rs.kx], a[rs.ky], a[rs.kz]);
    var p1t = vec3<f32>(b[rs.kx], b[rs.ky], b[rs.kz]);
    var p2t = vec3<f32>(c[rs.kx], c[rs.ky], c[rs.kz]);
    p0t = vec3<f32>(p0t.x + rs.shear.x * p0t.z, p0t.y + rs.shear.y * p0t.z, p0t.z);
    p1t = vec3<f32>(p1t.x + rs.shear.x * p1t.z, p1t.y + rs.shear.y * p1t.z, p1t.z);
    p2t = vec3<f32>(p2t.x + rs.shear.x * p2t.z, p2t.y + rs.shear.y * p2t.z, p2t.z);

    let e0 = difference_of_products(p1t.x, p2t.y, p1t.y, p2t.x);
    let e1 = difference_of_products(p2t.x, p0t.y, p2t.y, p0t.x);
    let e2 = difference_of_products(p0t.x, p1t.y, p0t.y, p1t.x);
    if ((e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0)) {
        return miss;
    }
    let det = e0 + e1 + e2;
    if (det == 0.0) {
        return miss;
    }
    // The largest |z| in object units, before z is scaled into t units below.
    let max_z_object = max(abs(p0t.z), max(abs(p1t.z), abs(p2t.z)));
    p0t.z *= rs.shear.z;
    p1t.z *= rs.shear.z;
    p2t.z *= rs.shear.z;
    let t_scaled = e0 * p0t.z + e1 * p1t.z + e2 * p2t.z;
    if (det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det)) {
        return miss;
    }
    if (det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det)) {
        return miss;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // The t_max test above compares rounded scaled values; repeat it on t itself so a hit
    // never replaces a nearer one (the closest hit must not depend on the visiting order).
    if (t >= t_max) {
        return miss;
    }

    // Reject hits whose t is not certainly positive given the rounding error (pbrt-v4 §6.8.4).
    // pbrt bounds the error of the sheared x and y with the z magnitude after scaling by
    // 1/d.z, which is only commensurate for unit-length directions; instance rays are not
    // renormalised (a mesh scaled by 10^6 has |d| ~ 10^-6 in object space), so x and y use
    // z in object units and only t uses the scaled z.
    let max_zt = max(abs(p0t.z), max(abs(p1t.z), abs(p2t.z)));
    let delta_z = gamma(3.0) * max_zt;
    let max_xt = max(abs(p0t.x), max(abs(p1t.x), abs(p2t.x)));
    let max_yt = max(abs(p0t.y), max(abs(p1t.y), abs(p2t.y)));
    let delta_x = gamma(5.0) * (max_xt + max_z_object);
    let delta_y = gamma(5.0) * (max_yt + max_z_object);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = max(abs(e0), max(abs(e1), abs(e2)));
    let delta_t = 3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * abs(inv_det);
    if (t <= delta_t) {
        return miss;
    }
    return TriangleHit(true, t, e1 * inv_det, e2 * inv_det);
}

// 1 + 2 gamma(3): the relative error bound of a slab distance.
const BOX_T_SLACK: f32 = 1.0000004;

// Entry distance of the ray into the box, or a negative value when it misses within
// [0, t_max]. `inv_dir` may hold infinities for axis-parallel rays.
fn intersect_aabb(origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let t_near = min(t0, t1);
    // Widened by the rounding error of the slab computations (pbrt-v4 Bounds3::IntersectP).
    let t_far = max(t0, t1) * BOX_T_SLACK;
    let enter = max(max(t_near.x, t_near.y), max(t_near.z, 0.0));
    // The entry distance carries the same rounding error, so it is compared with a widened
    // t_max too: otherwise a box holding a triangle hit an ulp nearer than the current
    // best can be culled.
    let leave = min(min(t_far.x, t_far.y), min(t_far.z, t_max * BOX_T_SLACK));
    if (enter <= leave) {
        return enter;
    }
    return -1.0;
}
