// The media a path is inside, for the volumetric path tracer (shaders/integrator/path.wgsl).
//
// Nesting rule: a path starts in the media of the objects around the camera (found on the
// CPU by ray parity against their closed meshes, outermost first). Crossing into
// an object that light passes through — through its surface's transmission or through a
// volume's bare boundary — pushes the medium of that object's inside: its volume
// (shaders/nodes/volume.wgsl), plus the Beer–Lambert absorption of a transmissive
// surface. Crossing out of it removes the innermost entry of that object's material,
// wherever it is in the stack. The medium a segment runs through is the innermost one, so
// a medium inside a glass inside fog sees the medium, then the glass's, then the fog's.
// Objects nested deeper than MEDIA_DEPTH are treated as vacuum inside.
//
// A homogeneous volume's coefficients are the material buffer's, which the compiler
// computes from the volume node's constant inputs. A heterogeneous one (its inputs vary)
// is baked into a grid over its object's bounds by the material graph's volume
// (shaders/integrator/volume_bake.wgsl) and read here trilinearly (`volume_grid_at`);
// paths track through it against its majorant, an extinction the compiler proved no
// point exceeds (nor, then, any blend of grid points): delta tracking for free flights,
// ratio tracking for transmittance.

const MEDIA_DEPTH: u32 = 4u;

// Whether a path can be inside a medium: only volumes and refracting surfaces have an
// inside. Without them the kernel leaves the media code out (lavapipe would otherwise run
// it at every bounce under a lane mask, taken or not).
const FEATURE_MEDIA: bool = FEATURE_VOLUME || FEATURE_HETEROGENEOUS || FEATURE_GLASS;
// Whether a medium can scatter, emit or vary inside (a volume). Without one a medium is a
// transmissive surface's Beer–Lambert absorption alone, and its other fields stay unset.
const FEATURE_VOLUME_MEDIA: bool = FEATURE_VOLUME || FEATURE_HETEROGENEOUS;

struct Media {
    count: u32,
    // The material whose inside each entry is, and the instance (for object space).
    material: array<u32, 4>,
    instance: array<u32, 4>,
    // Homogeneous: the medium. Heterogeneous: the constant part (a transmissive
    // surface's absorption) the graph's volume adds to.
    medium: array<Medium, 4>,
    // A heterogeneous medium's majorant (its graph's, plus the constant part); 0 for a
    // homogeneous one.
    majorant: array<f32, 4>,
    // Emitted radiance per unit length.
    emission: array<vec3<f32>, 4>,
};

fn media_empty() -> Media {
    var m: Media;
    m.count = 0u;
    return m;
}

// The media after entering the inside of `material`: its volume (the material buffer's)
// with `absorption` more (a transmissive surface's Beer–Lambert extinction).
fn media_entered(media_in: Media, material: u32, instance: u32, absorption: vec3<f32>) -> Media {
    var media = media_in;
    let i = media.count;
    if (i < MEDIA_DEPTH) {
        media.material[i] = material;
        media.instance[i] = instance;
        media.medium[i] = material_medium(material, absorption);
        if (FEATURE_VOLUME_MEDIA) {
            media.majorant[i] = 0.0;
            let majorant = fetch_material(material).volume_majorant;
            if (FEATURE_HETEROGENEOUS && majorant > 0.0) {
                let a = max(absorption, vec3<f32>(0.0));
                media.majorant[i] = majorant + max(a.x, max(a.y, a.z));
            }
            media.emission[i] = fetch_material(material).volume_emission.xyz;
        }
        media.count = i + 1u;
    }
    return media;
}

// The media a camera path starts in: those of the objects around the camera, outermost
// first (Params.camera_media). A transmissive surface's inside has the Beer–Lambert
// absorption of its fixed parameters (a graph's, which vary over the surface, are not
// known here: the path picks them up when it next enters); a thin wall has no inside.
fn camera_media() -> Media {
    var media = media_empty();
    for (var i = 0u; i < min(params.camera_media_count, MEDIA_DEPTH); i++) {
        let instance = params.camera_media[i];
        let material = fetch_instance(instance).material;
        var absorption = vec3<f32>(0.0);
        if (fetch_material(material).boundary_only == 0u) {
            let p = principled_unpack(fetch_material(material).principled);
            if (p.thin_walled) {
                continue;
            }
            absorption = principled_extinction(p);
        }
        media = media_entered(media, material, instance, absorption);
    }
    return media;
}

// The media after leaving the inside of `material`: its innermost entry is removed and
// the entries inside it move out by one. Leaving an object never entered (the camera
// inside it, or one nested too deep) changes nothing.
fn media_left(media_in: Media, material: u32) -> Media {
    var media = media_in;
    let n = media.count;
    var found = false;
    for (var k = 0u; k < n; k++) {
        let i = n - 1u - k;
        if (!found && media.material[i] == material) {
            found = true;
            for (var j = i; j + 1u < n; j++) {
                media.material[j] = media.material[j + 1u];
                media.instance[j] = media.instance[j + 1u];
                media.medium[j] = media.medium[j + 1u];
                if (FEATURE_VOLUME_MEDIA) {
                    media.majorant[j] = media.majorant[j + 1u];
                    media.emission[j] = media.emission[j + 1u];
                }
            }
        }
    }
    if (found) {
        media.count = n - 1u;
    }
    return media;
}

// The medium inside material `id`: its homogeneous volume (the material buffer's), with
// `absorption` more (a transmissive surface's Beer–Lambert extinction).
fn material_medium(id: u32, absorption: vec3<f32>) -> Medium {
    if (!FEATURE_VOLUME_MEDIA) {
        return Medium(max(absorption, vec3<f32>(0.0)), vec3<f32>(0.0), 0.0);
    }
    let m = fetch_material(id);
    let sigma_s = max(m.volume_scattering.xyz, vec3<f32>(0.0));
    let sigma_t = max(m.volume_absorption.xyz, vec3<f32>(0.0)) + max(absorption, vec3<f32>(0.0)) + sigma_s;
    let albedo = select(vec3<f32>(0.0), min(sigma_s / sigma_t, vec3<f32>(1.0)), sigma_t > vec3<f32>(0.0));
    return Medium(sigma_t, albedo, m.volume_absorption.w);
}

// ∫₀ᵗ e^(-σt s) Le ds per channel: what an emitting medium adds along a segment.
fn medium_emission(m: Medium, emission: vec3<f32>, t: f32) -> vec3<f32> {
    let thick = m.sigma_t * t > vec3<f32>(1e-4);
    let exact = emission * (vec3<f32>(1.0) - exp(-m.sigma_t * t)) / m.sigma_t;
    // Thin: the series 1 - σt t / 2, which the formula above loses to rounding.
    let thin = emission * t * (vec3<f32>(1.0) - 0.5 * m.sigma_t * t);
    return select(thin, exact, thick);
}

// ---- Heterogeneous media ----

// A tracked path gives up after this many tentative collisions in one segment (its
// energy is lost; a majorant of 100 per unit crosses 40 units before).
const HETEROGENEOUS_MAX_STEPS: u32 = 4096u;

// A heterogeneous medium at a point: absorption, scattering and emission per unit length
// and the phase function's g.
struct MediumPoint {
    sigma_a: vec3<f32>,
    sigma_s: vec3<f32>,
    emission: vec3<f32>,
    g: f32,
};

// Entry `i` of `media` at `p`.
fn medium_at(media: Media, i: u32, p: vec3<f32>) -> MediumPoint {
    let v = volume_grid_at(media.instance[i], p);
    return MediumPoint(
        max(v.absorption, vec3<f32>(0.0)) + media.medium[i].sigma_t,
        max(v.scattering, vec3<f32>(0.0)),
        max(v.emission, vec3<f32>(0.0)),
        clamp(v.g, -HG_MAX_G, HG_MAX_G),
    );
}

struct Tracked {
    // Scattered inside the medium at distance t (else it reached t_max).
    scattered: bool,
    t: f32,
    g: f32,
    // The path's throughput after the segment, or at the scattering point.
    throughput: vec3<f32>,
    // Radiance the medium emitted toward the path's start, weighted by the throughput.
    emitted: vec3<f32>,
    // False when the path was absorbed (or ran out of steps): it ends.
    valid: bool,
};

// A free flight through the innermost medium of `media`, heterogeneous, toward a boundary
// `t_max` away, by delta tracking with a scalar majorant σ̄ made spectral as Kutz et al.
// ("Spectral and Decomposition Tracking", 2017): tentative collisions come at rate σ̄; at
// each the path scatters or passes on (a null collision) with probabilities in
// proportion to throughput × σs and throughput × σn (σn = σ̄ - σt), and is weighted by
// the coefficient over σ̄ times that probability, so that absorption lowers its weight
// instead of ending it. Emission adds throughput × Le / σ̄ at every tentative collision,
// whose expectation is the segment's integral of transmittance × Le. A path past its volume
// bounces (`scatters` false) never scatters: every collision is null, weighted σn / σ̄, so
// the flight is ratio tracking and the medium absorbs its whole extinction.
fn heterogeneous_flight(media: Media, origin: vec3<f32>, dir: vec3<f32>, t_max: f32, throughput: vec3<f32>, scatters: bool) -> Tracked {
    let top = media.count - 1u;
    let majorant = media.majorant[top];
    var r: Tracked;
    r.throughput = throughput;
    r.emitted = vec3<f32>(0.0);
    r.valid = true;
    var t = 0.0;
    for (var i = 0u; i < HETEROGENEOUS_MAX_STEPS; i++) {
        t -= log(1.0 - rand()) / majorant;
        if (t >= t_max) {
            r.t = t_max;
            return r;
        }
        let c = medium_at(media, top, origin + dir * t);
        r.emitted += r.throughput * c.emission / majorant;
        let sigma_n = max(vec3<f32>(majorant) - c.sigma_a - c.sigma_s, vec3<f32>(0.0));
        let ws = select(vec3<f32>(0.0), r.throughput * c.sigma_s, scatters);
        let wn = r.throughput * sigma_n;
        let ps = ws.x + ws.y + ws.z;
        let pn = wn.x + wn.y + wn.z;
        if (!(ps + pn > 0.0)) {
            r.valid = false;
            return r;
        }
        if (rand() * (ps + pn) < ps) {
            r.throughput *= c.sigma_s * ((ps + pn) / (majorant * ps));
            r.scattered = true;
            r.t = t;
            r.g = c.g;
            return r;
        }
        r.throughput *= sigma_n * ((ps + pn) / (majorant * pn));
    }
    r.valid = false;
    return r;
}

// The transmittance of the innermost medium of `media`, heterogeneous, from `origin` along
// `dir` to `t_max`, by ratio tracking (Novák et al. 2014): the product of σn / σ̄ over
// tentative collisions, per channel. Russian roulette ends estimates that fall low.
fn ratio_tracking(media: Media, origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> vec3<f32> {
    let top = media.count - 1u;
    let majorant = media.majorant[top];
    var tr = vec3<f32>(1.0);
    var t = 0.0;
    for (var i = 0u; i < HETEROGENEOUS_MAX_STEPS; i++) {
        t -= log(1.0 - rand()) / majorant;
        if (t >= t_max) {
            return tr;
        }
        let c = medium_at(media, top, origin + dir * t);
        tr *= max(vec3<f32>(1.0) - (c.sigma_a + c.sigma_s) / majorant, vec3<f32>(0.0));
        let m = max(tr.x, max(tr.y, tr.z));
        if (!(m > 0.0)) {
            return vec3<f32>(0.0);
        }
        if (m < 0.1) {
            if (rand() < 0.5) {
                return vec3<f32>(0.0);
            }
            tr *= 2.0;
        }
    }
    return vec3<f32>(0.0);
}

// ---- Baked grids (src/render/volume_grid.rs) ----

// Words of a grid's header and of one voxel in `volume_grid`.
const GRID_HEADER_WORDS: u32 = 16u;
const GRID_VOXEL_WORDS: u32 = 5u;

// A grid's header: its object-space origin and points per unit, its points per axis, and
// the scale its σ values were divided by (the material's majorant).
struct GridHeader {
    lo: vec3<f32>,
    to_grid: vec3<f32>,
    dims: vec3<u32>,
    scale: f32,
};

fn grid_header(g: u32) -> GridHeader {
    let f = vec3<f32>(
        bitcast<f32>(volume_grid[g]),
        bitcast<f32>(volume_grid[g + 1u]),
        bitcast<f32>(volume_grid[g + 2u]),
    );
    let t = vec3<f32>(
        bitcast<f32>(volume_grid[g + 3u]),
        bitcast<f32>(volume_grid[g + 4u]),
        bitcast<f32>(volume_grid[g + 5u]),
    );
    let d = vec3<u32>(volume_grid[g + 6u], volume_grid[g + 7u], volume_grid[g + 8u]);
    return GridHeader(f, t, d, bitcast<f32>(volume_grid[g + 9u]));
}

// Voxel `index` of the grid whose voxels start at word `data`, its σ values as stored
// (divided by the grid's scale).
fn grid_voxel(data: u32, index: u32) -> VolumeEval {
    let w = data + index * GRID_VOXEL_WORDS;
    let a = unpack2x16float(volume_grid[w]);
    let b = unpack2x16float(volume_grid[w + 1u]);
    let c = unpack2x16float(volume_grid[w + 2u]);
    let d = unpack2x16float(volume_grid[w + 3u]);
    let e = unpack2x16float(volume_grid[w + 4u]);
    return VolumeEval(vec3<f32>(a.x, a.y, b.x), vec3<f32>(b.y, c.x, c.y), vec3<f32>(d.y, e.x, e.y), d.x);
}

// The baked volume of instance `instance` at world point `p`: the trilinear blend of the
// eight grid points around it (points outside the grid take its nearest face's).
fn volume_grid_at(instance: u32, p: vec3<f32>) -> VolumeEval {
    let inst = fetch_instance(instance);
    let g = inst.volume_grid;
    let h = grid_header(g);
    let top = vec3<f32>(h.dims - vec3<u32>(1u));
    let x = clamp((transform_point(inst.to_object, p) - h.lo) * h.to_grid, vec3<f32>(0.0), top);
    let i0 = min(vec3<u32>(floor(x)), h.dims - vec3<u32>(2u));
    let f = x - vec3<f32>(i0);
    let data = g + GRID_HEADER_WORDS;
    let row = h.dims.x;
    let slice = h.dims.x * h.dims.y;
    var sum = nd_no_volume();
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, corner >> 2u);
        let wv = select(vec3<f32>(1.0) - f, f, o == vec3<u32>(1u));
        let w = wv.x * wv.y * wv.z;
        let i = i0 + o;
        let v = grid_voxel(data, i.x + i.y * row + i.z * slice);
        sum.absorption += w * v.absorption;
        sum.scattering += w * v.scattering;
        sum.emission += w * v.emission;
        sum.g += w * v.g;
    }
    sum.absorption *= h.scale;
    sum.scattering *= h.scale;
    return sum;
}
