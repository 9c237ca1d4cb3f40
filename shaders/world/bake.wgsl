// Bakes a world graph (src/render/world_bake.rs): `world_radiance(sp)` at the centre of
// each texel of an equirectangular map, laid out as the environment map reads it
// (shaders/lights/environment.wgsl, rotation 0), then for each sun `world_sun(j, sp)`, the
// world with sun j's irradiance added to its sky, at the sun's direction. The world's
// shading point looks from the origin along the direction: position, object and generated
// coordinates are the direction, the normal faces back along it.
//
// probe_in: [0] = (width, height, suns, 0), then one direction per sun (xyz).
// probe_out: width × height texels (rgb), then per sun the world with and without its sun.

@group(1) @binding(0) var<storage, read> probe_in: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;

fn world_point(d: vec3<f32>) -> ShadingPoint {
    let uv = nd_equirectangular_uv(d);
    return ShadingPoint(
        d, -d, -d, uv, vec2<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), -d,
        d, -d, d, vec4<f32>(1.0), 0.0, vec3<f32>(0.0), false,
    );
}

@compute @workgroup_size(64)
fn bake_world(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    let size = vec2<u32>(probe_in[0].xy);
    let texels = size.x * size.y;
    let suns = u32(probe_in[0].z);
    if (i < texels) {
        let x = i % size.x;
        let y = i / size.x;
        let u = (f32(x) + 0.5) / f32(size.x);
        let v = (f32(y) + 0.5) / f32(size.y);
        let phi = (u - 0.5) * 2.0 * 3.14159265;
        let theta = v * 3.14159265;
        let d = vec3<f32>(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
        probe_out[i] = vec4<f32>(nd_finite3(world_radiance(world_point(d))), 0.0);
    } else if (i < texels + suns) {
        let j = i - texels;
        let sp = world_point(probe_in[1u + j].xyz);
        probe_out[texels + 2u * j] = vec4<f32>(nd_finite3(world_sun(j, sp)), 0.0);
        probe_out[texels + 2u * j + 1u] = vec4<f32>(nd_finite3(world_radiance(sp)), 0.0);
    }
}
