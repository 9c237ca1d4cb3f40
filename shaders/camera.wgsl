// Perspective camera with an optional thin lens: primary rays for a film position.

// `film_pos` is in pixels with (0, 0) the top-left corner of the film.
fn camera_ray(film_pos: vec2<f32>, u_lens: vec2<f32>) -> Ray {
    let size = vec2<f32>(params.film_size);
    let ndc = film_pos / size * 2.0 - vec2<f32>(1.0);
    let tan_half = params.cam_lens.x;
    let aspect = params.cam_lens.y;
    // Direction in camera space with z = 1 (forward), y up.
    let d = vec3<f32>(ndc.x * tan_half * aspect, -ndc.y * tan_half, 1.0);
    let right = params.cam_right.xyz;
    let up = params.cam_up.xyz;
    let forward = params.cam_forward.xyz;
    let dir = normalize(d.x * right + d.y * up + d.z * forward);
    let aperture = params.cam_lens.z;
    if (aperture <= 0.0) {
        return Ray(params.cam_position.xyz, dir);
    }
    // Thin lens: every ray through the lens meets the pinhole ray on the plane of focus.
    let focus = params.cam_position.xyz + (d.x * right + d.y * up + forward) * params.cam_lens.w;
    let lens = aperture * sample_concentric_disk(u_lens);
    let origin = params.cam_position.xyz + lens.x * right + lens.y * up;
    return Ray(origin, normalize(focus - origin));
}
