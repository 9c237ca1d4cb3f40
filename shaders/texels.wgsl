// Texel tables (`Space::Texels` in src/shader/bindings.rs): arrays of fixed-size elements
// in rgba32uint texels, `TEXELS_PER_*` of them side by side in one row of
// `*_PER_TEXEL_ROW` elements (both generated from `TexelLayout`), declared as `TexelTable`
// and read with `texel_load` (both generated from `TexelReads`). Traversal reads the BVHs,
// the triangles and the instances from them, and shading the instances, the vertices and
// their indices: on a software rasteriser a texel read is a vector load per lane.

// What traversal reads of an instance: the world-to-object rows and the root of its mesh's
// BVH, texels 3–6 of its nine (`Instance` in shaders/scene.wgsl).
struct Placement {
    to_object: array<vec4<f32>, 3>,
    blas_root: u32,
};

// Texel `k` of element `i` in a table of `texels` texels per element, `per_row` elements
// per row.
fn texel_of(t: TexelTable, i: u32, texels: u32, per_row: u32, k: u32) -> vec4<u32> {
    return texel_load(t, vec2<u32>(texels * (i % per_row) + k, i / per_row));
}

fn node_from_texels(t: TexelTable, i: u32) -> WideNode {
    let a = texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 0u);
    let steps = array<vec4<u32>, 2>(
        texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 2u),
        texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 3u),
    );
    return WideNode(bitcast<vec3<f32>>(a.xyz), a.w, texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 1u), steps);
}

fn triangle_from_texels(t: TexelTable, i: u32) -> Triangle {
    return Triangle(
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 0u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 1u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 2u)),
    );
}

fn fetch_tlas_node(i: u32) -> WideNode {
    return node_from_texels(tlas_texels, i);
}

// Texel `k` of instance `i`.
fn instance_texel(i: u32, k: u32) -> vec4<u32> {
    return texel_of(instance_texels, i, TEXELS_PER_INSTANCE, INSTANCES_PER_TEXEL_ROW, k);
}

fn fetch_placement(i: u32) -> Placement {
    let rows = array<vec4<f32>, 3>(
        bitcast<vec4<f32>>(instance_texel(i, 3u)),
        bitcast<vec4<f32>>(instance_texel(i, 4u)),
        bitcast<vec4<f32>>(instance_texel(i, 5u)),
    );
    return Placement(rows, instance_texel(i, 6u).x);
}

fn fetch_instance(i: u32) -> Instance {
    let to_world = array<vec4<f32>, 3>(
        bitcast<vec4<f32>>(instance_texel(i, 0u)),
        bitcast<vec4<f32>>(instance_texel(i, 1u)),
        bitcast<vec4<f32>>(instance_texel(i, 2u)),
    );
    let to_object = array<vec4<f32>, 3>(
        bitcast<vec4<f32>>(instance_texel(i, 3u)),
        bitcast<vec4<f32>>(instance_texel(i, 4u)),
        bitcast<vec4<f32>>(instance_texel(i, 5u)),
    );
    let last = instance_texel(i, 6u);
    let mesh_min = bitcast<vec4<f32>>(instance_texel(i, 7u));
    let mesh_max = bitcast<vec4<f32>>(instance_texel(i, 8u));
    return Instance(to_world, to_object, last.x, last.y, last.z, last.w, mesh_min, mesh_max);
}

// The attributes of vertex `i` (`vertex_texels`).
fn fetch_vertex(i: u32) -> vec4<u32> {
    return texel_of(vertex_texels, i, TEXELS_PER_VERTEX, VERTICES_PER_TEXEL_ROW, 0u);
}

// The global vertex indices of triangle `i`.
fn fetch_triangle_vertices(i: u32) -> vec3<u32> {
    let t = triangle_vertex_texels;
    return texel_of(t, i, TEXELS_PER_TRIANGLE_VERTEX, TRIANGLE_VERTICES_PER_TEXEL_ROW, 0u).xyz;
}

// Texel `k` of material `i`.
fn material_texel(i: u32, k: u32) -> vec4<u32> {
    return texel_of(material_texels, i, TEXELS_PER_MATERIAL, MATERIALS_PER_TEXEL_ROW, k);
}

fn fetch_material(i: u32) -> Material {
    var principled: array<vec4<f32>, PRINCIPLED_VEC4S>;
    for (var k = 0u; k < PRINCIPLED_VEC4S; k++) {
        principled[k] = bitcast<vec4<f32>>(material_texel(i, k));
    }
    let n = PRINCIPLED_VEC4S;
    let flags = material_texel(i, n + 1u);
    return Material(
        principled,
        bitcast<vec4<f32>>(material_texel(i, n)),
        flags.x,
        flags.y,
        bitcast<f32>(flags.z),
        flags.w,
        bitcast<vec4<f32>>(material_texel(i, n + 2u)),
        bitcast<vec4<f32>>(material_texel(i, n + 3u)),
        bitcast<vec4<f32>>(material_texel(i, n + 4u)),
    );
}

fn fetch_light_triangle(i: u32) -> LightTriangle {
    let t = light_triangle_texels;
    let n = TEXELS_PER_LIGHT_TRIANGLE;
    let per_row = LIGHT_TRIANGLES_PER_TEXEL_ROW;
    return LightTriangle(
        bitcast<vec4<f32>>(texel_of(t, i, n, per_row, 0u)),
        bitcast<vec4<f32>>(texel_of(t, i, n, per_row, 1u)),
        bitcast<vec4<f32>>(texel_of(t, i, n, per_row, 2u)),
        bitcast<vec4<f32>>(texel_of(t, i, n, per_row, 3u)),
    );
}

// Entry `i` of the light CDF, four to a texel.
fn light_cdf_at(i: u32) -> f32 {
    let t = texel_of(light_cdf_texels, i / 4u, TEXELS_PER_LIGHT_CDF, LIGHT_CDFS_PER_TEXEL_ROW, 0u);
    return bitcast<f32>(t[i % 4u]);
}
