// The local geometry at a ray hit: position with its error bound, geometric and shading
// normals, texture coordinates and material, all in world space.

struct Surface {
    pe: PointError,
    // Geometric normal from the triangle's winding (front side), unit length.
    ng: vec3<f32>,
    // Interpolated vertex normal, or `ng` for meshes without normals; same side as `ng`.
    ns: vec3<f32>,
    uv: vec2<f32>,
    // dp/du from the triangle's texture coordinates (world space, not unit, not
    // orthogonal to the normals); zero where the mesh has no UVs or they are degenerate.
    dpdu: vec3<f32>,
    dpdv: vec3<f32>,
    // Interpolated vertex colour (white where the mesh has none).
    color: vec4<f32>,
    // The second UV set (zero where the mesh has none).
    uv1: vec2<f32>,
    material: u32,
};

// Octahedral normal decoding (Cigolle et al. 2014, "A Survey of Efficient Representations
// for Independent Unit Vectors").
fn decode_octahedral(packed: u32) -> vec3<f32> {
    let e = unpack2x16snorm(packed);
    var v = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0) {
        let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), v.xy >= vec2<f32>(0.0));
        v = vec3<f32>((1.0 - abs(v.yx)) * s, v.z);
    }
    return normalize(v);
}

fn surface_at(hit: SceneHit) -> Surface {
    let inst = fetch_instance(hit.instance);
    let tri = fetch_triangle(hit.triangle);
    let b0 = 1.0 - hit.b1 - hit.b2;
    let p0 = tri.p0.xyz;
    let p1 = tri.p1.xyz;
    let p2 = tri.p2.xyz;
    // Barycentric interpolation is exact up to gamma(7) of the terms (pbrt-v4 §6.8.5),
    // which keeps the error bound relative to the geometry's own magnitude.
    let p_object = b0 * p0 + hit.b1 * p1 + hit.b2 * p2;
    let err_object = gamma(7.0) * (abs(b0 * p0) + abs(hit.b1 * p1) + abs(hit.b2 * p2));
    let pe = transform_point_error(inst.to_world, PointError(p_object, err_object));
    let ng = normalize(transform_normal(inst.to_object, cross(p1 - p0, p2 - p0)));

    var ns = ng;
    var uv = vec2<f32>(hit.b1, hit.b2);
    var dpdu = vec3<f32>(0.0);
    var dpdv = vec3<f32>(0.0);
    let corners = fetch_triangle_vertices(hit.triangle);
    let v0 = fetch_vertex(corners.x);
    let v1 = fetch_vertex(corners.y);
    let v2 = fetch_vertex(corners.z);
    if ((inst.flags & INSTANCE_HAS_NORMALS) != 0u) {
        let n_object = b0 * decode_octahedral(v0.x) + hit.b1 * decode_octahedral(v1.x) + hit.b2 * decode_octahedral(v2.x);
        let len = length(n_object);
        // Opposing vertex normals can cancel: keep the geometric normal then. The test is
        // on unit-scale object-space normals, so it holds at any instance scale.
        if (len > 1e-6) {
            ns = normalize(transform_normal(inst.to_object, n_object / len));
            if (dot(ns, ng) < 0.0) {
                ns = -ns;
            }
        }
    }
    if ((inst.flags & INSTANCE_HAS_UVS) != 0u) {
        let uv0 = bitcast<vec2<f32>>(v0.yz);
        let uv1 = bitcast<vec2<f32>>(v1.yz);
        let uv2 = bitcast<vec2<f32>>(v2.yz);
        uv = b0 * uv0 + hit.b1 * uv1 + hit.b2 * uv2;
        // pbrt-v4 §6.5.3: solve dp1 = du1 dpdu + dv1 dpdv, dp2 = du2 dpdu + dv2 dpdv.
        let duv1 = uv1 - uv0;
        let duv2 = uv2 - uv0;
        let det = duv1.x * duv2.y - duv1.y * duv2.x;
        if (abs(det) > 1e-12) {
            dpdu = transform_vector(inst.to_world, ((p1 - p0) * duv2.y - (p2 - p0) * duv1.y) / det);
            dpdv = transform_vector(inst.to_world, ((p2 - p0) * duv1.x - (p1 - p0) * duv2.x) / det);
        }
    }
    let color = b0 * unpack4x8unorm(v0.w) + hit.b1 * unpack4x8unorm(v1.w) + hit.b2 * unpack4x8unorm(v2.w);
    var uv1 = vec2<f32>(0.0);
    if (FEATURE_UV1 && (inst.flags & INSTANCE_HAS_UV1) != 0u) {
        uv1 = b0 * uv1_data[corners.x] + hit.b1 * uv1_data[corners.y] + hit.b2 * uv1_data[corners.z];
    }
    return Surface(pe, ng, ns, uv, dpdu, dpdv, color, uv1, inst.material);
}
