// Bakes a heterogeneous volume into its grid (src/render/volume_grid.rs): one invocation
// per grid point, which evaluates the material graph's volume there, as the path tracer
// would at that point, and stores it as shaders/integrator/media.wgsl reads it. Compiled
// into the path tracer's module only for scenes with such a volume; the renderer runs it
// after building and after every edit of the materials or instances.
//
// A volume's graph sees no direction here: its normal and incoming vector face +z in
// world space (`volume_point` with a path travelling along -z).

@compute @workgroup_size(64)
fn bake_volume_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    let g = params.bake_grid;
    let h = grid_header(g);
    let voxel = params.bake_first + id.x;
    if (voxel >= h.dims.x * h.dims.y * h.dims.z) {
        return;
    }
    let i = vec3<u32>(voxel % h.dims.x, (voxel / h.dims.x) % h.dims.y, voxel / (h.dims.x * h.dims.y));
    let cell = vec3<f32>(
        bitcast<f32>(volume_grid[g + 12u]),
        bitcast<f32>(volume_grid[g + 13u]),
        bitcast<f32>(volume_grid[g + 14u]),
    );
    let material = volume_grid[g + 10u];
    let instance = volume_grid[g + 11u];
    let p = transform_point(fetch_instance(instance).to_world, h.lo + vec3<f32>(i) * cell);
    let v = evaluate_volume(material, volume_point(instance, p, vec3<f32>(0.0, 0.0, -1.0)));
    let inverse = select(0.0, 1.0 / h.scale, h.scale > 0.0);
    let a = max(v.absorption, vec3<f32>(0.0)) * inverse;
    let s = max(v.scattering, vec3<f32>(0.0)) * inverse;
    let e = clamp(v.emission, vec3<f32>(0.0), vec3<f32>(65504.0));
    let gee = clamp(v.g, -HG_MAX_G, HG_MAX_G);
    let w = g + GRID_HEADER_WORDS + voxel * GRID_VOXEL_WORDS;
    volume_grid[w] = pack2x16float(a.xy);
    volume_grid[w + 1u] = pack2x16float(vec2<f32>(a.z, s.x));
    volume_grid[w + 2u] = pack2x16float(s.yz);
    volume_grid[w + 3u] = pack2x16float(vec2<f32>(gee, e.x));
    volume_grid[w + 4u] = pack2x16float(e.yz);
}
