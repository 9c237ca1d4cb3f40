// Two-level BVH traversal: a BVH over instances (TLAS) whose leaves hold instances, each
// pointing at its mesh's BVH (BLAS) in object space. Both levels descend into the nearer
// child first and keep the farther one, with its entry distance, on a fixed-size stack;
// the host checks every tree's depth against these sizes before upload.

const TLAS_STACK_SIZE: u32 = 48u;
const BLAS_STACK_SIZE: u32 = 64u;

// Traversal stacks live at module scope: WGSL zero-initialises function-scope arrays at
// every call, which for a call per instance visited costs more than the traversal itself.
var<private> blas_stack_node: array<u32, BLAS_STACK_SIZE>;
var<private> blas_stack_t: array<f32, BLAS_STACK_SIZE>;
var<private> tlas_stack_node: array<u32, TLAS_STACK_SIZE>;
var<private> tlas_stack_t: array<f32, TLAS_STACK_SIZE>;

struct SceneHit {
    hit: bool,
    t: f32,
    instance: u32,
    triangle: u32,
    b1: f32,
    b2: f32,
};

// Reciprocal direction without infinities: 0 * inf would make the slab test NaN for rays
// that start on a box face.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = 1e-32;
    let s = select(vec3<f32>(-tiny), vec3<f32>(tiny), d >= vec3<f32>(0.0));
    return 1.0 / select(d, s, abs(d) < vec3<f32>(tiny));
}

fn transform_point(m: array<vec4<f32>, 3>, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}

fn transform_vector(m: array<vec4<f32>, 3>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(m[0].xyz, v), dot(m[1].xyz, v), dot(m[2].xyz, v));
}

// Normals transform by the inverse transpose: the columns of the world-to-object rows.
fn transform_normal(to_object: array<vec4<f32>, 3>, n: vec3<f32>) -> vec3<f32> {
    return to_object[0].xyz * n.x + to_object[1].xyz * n.y + to_object[2].xyz * n.z;
}

// Searches one mesh's BVH; updates `best` with any closer hit. With `any_hit` it returns
// at the first hit found (shadow rays).
fn traverse_blas(instance_index: u32, root: u32, ray: Ray, any_hit: bool, best: ptr<function, SceneHit>) -> bool {
    let inv_dir = safe_inverse(ray.dir);
    let rs = ray_shear(ray.dir);
    var sp = 0u;
    var found = false;
    let root_node = fetch_blas_node(root);
    if (intersect_aabb(ray.origin, inv_dir, (*best).t, root_node.min, root_node.max) < 0.0) {
        return false;
    }
    var node_index = root;
    loop {
        let node = fetch_blas_node(node_index);
        var descend = false;
        if (node.count > 0u) {
            for (var i = node.first; i < node.first + node.count; i++) {
                let tri = fetch_triangle(i);
                let h = intersect_triangle(ray, rs, (*best).t, tri.p0.xyz, tri.p1.xyz, tri.p2.xyz);
                if (h.hit) {
                    *best = SceneHit(true, h.t, instance_index, i, h.b1, h.b2);
                    found = true;
                    if (any_hit) {
                        return true;
                    }
                }
            }
        } else {
            let left = fetch_blas_node(node.first);
            let right = fetch_blas_node(node.first + 1u);
            let tl = intersect_aabb(ray.origin, inv_dir, (*best).t, left.min, left.max);
            let tr = intersect_aabb(ray.origin, inv_dir, (*best).t, right.min, right.max);
            if (tl >= 0.0 && tr >= 0.0) {
                let left_first = tl <= tr;
                blas_stack_node[sp] = select(node.first, node.first + 1u, left_first);
                blas_stack_t[sp] = max(tl, tr);
                sp++;
                node_index = select(node.first + 1u, node.first, left_first);
                descend = true;
            } else if (tl >= 0.0) {
                node_index = node.first;
                descend = true;
            } else if (tr >= 0.0) {
                node_index = node.first + 1u;
                descend = true;
            }
        }
        if (!descend) {
            // Pop the next subtree that can still hold a closer hit.
            var popped = false;
            while (sp > 0u) {
                sp--;
                if (blas_stack_t[sp] <= (*best).t * BOX_T_SLACK) {
                    node_index = blas_stack_node[sp];
                    popped = true;
                    break;
                }
            }
            if (!popped) {
                break;
            }
        }
    }
    return found;
}

fn traverse_scene(ray: Ray, t_max: f32, any_hit: bool) -> SceneHit {
    var best = SceneHit(false, t_max, 0u, 0u, 0.0, 0.0);
    if (params.instance_count == 0u) {
        return best;
    }
    let inv_dir = safe_inverse(ray.dir);
    var sp = 0u;
    let root_node = tlas_nodes[0];
    if (intersect_aabb(ray.origin, inv_dir, t_max, root_node.min, root_node.max) < 0.0) {
        return best;
    }
    var node_index = 0u;
    loop {
        let node = tlas_nodes[node_index];
        var descend = false;
        if (node.count > 0u) {
            for (var i = node.first; i < node.first + node.count; i++) {
                let inst = instances[i];
                // The direction is not renormalised, so t means the same in both spaces.
                let local = Ray(transform_point(inst.to_object, ray.origin), transform_vector(inst.to_object, ray.dir));
                if (traverse_blas(i, inst.blas_root, local, any_hit, &best) && any_hit) {
                    return best;
                }
            }
        } else {
            let left = tlas_nodes[node.first];
            let right = tlas_nodes[node.first + 1u];
            let tl = intersect_aabb(ray.origin, inv_dir, best.t, left.min, left.max);
            let tr = intersect_aabb(ray.origin, inv_dir, best.t, right.min, right.max);
            if (tl >= 0.0 && tr >= 0.0) {
                let left_first = tl <= tr;
                tlas_stack_node[sp] = select(node.first, node.first + 1u, left_first);
                tlas_stack_t[sp] = max(tl, tr);
                sp++;
                node_index = select(node.first + 1u, node.first, left_first);
                descend = true;
            } else if (tl >= 0.0) {
                node_index = node.first;
                descend = true;
            } else if (tr >= 0.0) {
                node_index = node.first + 1u;
                descend = true;
            }
        }
        if (!descend) {
            var popped = false;
            while (sp > 0u) {
                sp--;
                if (tlas_stack_t[sp] <= best.t * BOX_T_SLACK) {
                    node_index = tlas_stack_node[sp];
                    popped = true;
                    break;
                }
            }
            if (!popped) {
                break;
            }
        }
    }
    return best;
}

fn intersect_scene(ray: Ray) -> SceneHit {
    return traverse_scene(ray, 3.0e38, false);
}

// True when something blocks the segment origin + t * dir, t in (0, t_max).
fn occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_scene(ray, t_max, true).hit;
}
