// `kiln bench --fetch`: what a dependent, data-driven load costs, from a storage buffer
// (`FETCH_FROM_BUFFER`) or from a texel table (otherwise) read as `TexelTable` says
// (`TexelReads::wgsl` in src/shader/bindings.rs, prepended with the constants). The BVH
// traversal's loads look like this: the next address comes from the data just loaded. Each invocation follows a chain
// of FETCH_STEPS loads through `FETCH_MASK + 1` vec4 entries, so the working set is
// 16 × (FETCH_MASK + 1) bytes. The constants are prepended by src/bench.rs.

@group(0) @binding(0) var<storage, read> entries: array<vec4<u32>>;
@group(0) @binding(1) var texels: TexelTable;
@group(0) @binding(2) var<storage, read_write> sink: array<u32>;

// Texels per row of `texels`.
const FETCH_ROW: u32 = 1024u;

fn fetch_hash(x: u32) -> u32 {
    var v = x * 747796405u + 2891336453u;
    v = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    return (v >> 22u) ^ v;
}

fn fetch_entry(i: u32) -> vec4<u32> {
    if (FETCH_FROM_BUFFER) {
        return entries[i];
    }
    return texel_load(texels, vec2<u32>(i % FETCH_ROW, i / FETCH_ROW));
}

@compute @workgroup_size(8, 8)
fn fetch_chain(@builtin(global_invocation_id) gid: vec3<u32>) {
    let lane = gid.y * FETCH_WIDTH + gid.x;
    var index = fetch_hash(lane) & FETCH_MASK;
    var acc = 0u;
    for (var k = 0u; k < FETCH_STEPS; k++) {
        let v = fetch_entry(index);
        acc += v.y ^ v.z ^ v.w;
        index = (v.x ^ fetch_hash(k + acc)) & FETCH_MASK;
    }
    sink[lane] = acc;
}
