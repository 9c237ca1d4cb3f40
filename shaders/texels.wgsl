// Texel tables (`Space::Texels` in src/shader/bindings.rs): arrays of fixed-size elements
// in rgba32uint texels, `TEXELS_PER_*` of them side by side in one row of
// `*_PER_TEXEL_ROW` elements (both generated from `TexelLayout`). Traversal reads the BVHs, the
// triangles and the instances' placements from them: on a software rasteriser a texel
// fetch is one vector gather, a storage load that differs between lanes a loop over the
// lanes for every word.

// What traversal reads of an instance (`GpuPlacement`): the world-to-object rows and the
// root of its mesh's BVH.
struct Placement {
    to_object: array<vec4<f32>, 3>,
    blas_root: u32,
};

// Texel `k` of element `i` in a table of `texels` texels per element, `per_row` elements
// per row.
fn texel_of(t: texture_2d<u32>, i: u32, texels: u32, per_row: u32, k: u32) -> vec4<u32> {
    return textureLoad(t, vec2<u32>(texels * (i % per_row) + k, i / per_row), 0);
}

fn node_from_texels(t: texture_2d<u32>, i: u32) -> BvhNode {
    let a = texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 0u);
    let b = texel_of(t, i, TEXELS_PER_NODE, NODES_PER_TEXEL_ROW, 1u);
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

fn triangle_from_texels(t: texture_2d<u32>, i: u32) -> Triangle {
    return Triangle(
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 0u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 1u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_TRIANGLE, TRIANGLES_PER_TEXEL_ROW, 2u)),
    );
}

fn fetch_tlas_node(i: u32) -> BvhNode {
    return node_from_texels(tlas_texels, i);
}

fn fetch_placement(i: u32) -> Placement {
    let t = placement_texels;
    let rows = array<vec4<f32>, 3>(
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_PLACEMENT, PLACEMENTS_PER_TEXEL_ROW, 0u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_PLACEMENT, PLACEMENTS_PER_TEXEL_ROW, 1u)),
        bitcast<vec4<f32>>(texel_of(t, i, TEXELS_PER_PLACEMENT, PLACEMENTS_PER_TEXEL_ROW, 2u)),
    );
    return Placement(rows, texel_of(t, i, TEXELS_PER_PLACEMENT, PLACEMENTS_PER_TEXEL_ROW, 3u).x);
}
