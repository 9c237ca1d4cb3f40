//! The WGSL node library (`shaders/nodes/`) that compiled material graphs call: it must
//! parse and validate with naga once the kernel's constants are in front of it, export the
//! functions the graph compiler emits calls to, and keep to the kernel's WGSL rules. Also
//! checks the CPU reference (`tests/common/node_reference.rs`) against independent facts,
//! so that GPU value tests can trust it. No GPU needed.

#[path = "common/node_reference.rs"]
mod node_reference;

use node_reference as nr;

/// The kernel defines these; the library uses them and must not define them itself.
const KERNEL_CONSTANTS: &str = "const PI: f32 = 3.14159265358979323846;\n\
                                const INV_PI: f32 = 0.31830988618379067154;\n";

const LIBRARY: [(&str, &str); 4] = [
    ("hash.wgsl", include_str!("../shaders/nodes/hash.wgsl")),
    ("math.wgsl", include_str!("../shaders/nodes/math.wgsl")),
    ("color.wgsl", include_str!("../shaders/nodes/color.wgsl")),
    (
        "textures.wgsl",
        include_str!("../shaders/nodes/textures.wgsl"),
    ),
];

fn library_source() -> String {
    let mut text = String::from(KERNEL_CONSTANTS);
    for (_, file) in LIBRARY {
        text.push_str(file);
        text.push('\n');
    }
    text
}

/// "hash.wgsl: lines a-b, ..." for the concatenation, so that an error's line number in
/// the combined source can be traced to its file.
fn line_map() -> String {
    let mut first = KERNEL_CONSTANTS.lines().count() + 1;
    let mut map = Vec::new();
    for (name, file) in LIBRARY {
        let last = first + file.lines().count() - 1;
        map.push(format!("{name}: lines {first}-{last}"));
        first = last + 2;
    }
    map.join(", ")
}

fn validated_library() -> naga::Module {
    let text = library_source();
    let module = naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| {
        panic!(
            "node library does not parse ({}):\n{}",
            line_map(),
            e.emit_to_string(&text)
        )
    });
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| {
        panic!(
            "node library does not validate ({}):\n{}",
            line_map(),
            e.emit_to_string(&text)
        )
    });
    module
}

#[test]
fn node_library_parses_and_validates_with_naga() {
    let module = validated_library();
    assert!(
        module.functions.len() > 40,
        "only {} functions",
        module.functions.len()
    );
}

/// The public entry points the graph compiler calls, with their parameter counts.
#[test]
fn node_library_exports_every_public_node_function() {
    let module = validated_library();
    let expected: [(&str, usize); 22] = [
        ("node_math", 4),
        ("node_vector_math", 5),
        ("node_map_range", 8),
        ("node_clamp", 4),
        ("node_mapping", 5),
        ("nd_rgb_to_hsv", 1),
        ("nd_hsv_to_rgb", 1),
        ("node_mix_color", 4),
        ("node_hue_saturation_value", 5),
        ("node_invert", 2),
        ("node_gamma", 2),
        ("node_bright_contrast", 3),
        ("node_rgb_to_bw", 1),
        ("node_checker", 4),
        ("node_gradient", 2),
        ("node_noise", 6),
        ("node_white_noise", 1),
        ("node_voronoi", 7),
        ("node_wave", 10),
        ("node_brick", 14),
        ("nd_hash_vec3_to_float", 1),
        ("nd_hash_vec3_to_vec3", 1),
    ];
    for (name, arity) in expected {
        let f = module
            .functions
            .iter()
            .map(|(_, f)| f)
            .find(|f| f.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("{name} is missing"));
        assert_eq!(f.arguments.len(), arity, "{name}'s parameter count");
    }
    for ty in ["NodeVectorMathOut", "NodeTexOut", "NodeVoronoiOut"] {
        assert!(
            module
                .types
                .iter()
                .any(|(_, t)| t.name.as_deref() == Some(ty)),
            "struct {ty} is missing"
        );
    }
}

/// The kernel's rules for included WGSL: no module-scope mutable state, no redefinition
/// of the kernel's constants, no f16, no const arrays (Mesa copies them per access), and
/// every helper/public name in the library's namespaces.
#[test]
fn node_library_keeps_to_the_kernel_wgsl_rules() {
    for (name, text) in LIBRARY {
        for (line_no, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            let at = format!("{name}:{}", line_no + 1);
            assert!(!code.contains("var<private>"), "{at}: module-scope var");
            assert!(!code.contains("f16"), "{at}: f16");
            assert!(!code.contains("array<"), "{at}: array");
            assert!(
                !code.contains("const PI") && !code.contains("const INV_PI"),
                "{at}: redefines a kernel constant"
            );
            if let Some(rest) = code.strip_prefix("fn ") {
                assert!(
                    rest.starts_with("nd_") || rest.starts_with("node_"),
                    "{at}: function outside the nd_/node_ namespaces"
                );
            }
        }
    }
}

// ---- The CPU reference ----

/// Values of lookup3's general `hashword(k, len, 13)` (the seed Cycles uses), computed
/// with an independent transcription of lookup3.c's loop.
#[test]
fn reference_hashes_match_lookup3_hashword() {
    assert_eq!(nr::hash_uint(0), 0x9519dc65);
    assert_eq!(nr::hash_uint(1), 0x4ad7c6a0);
    assert_eq!(nr::hash_uint(0xffff_ffff), 0x428adf39);
    assert_eq!(nr::hash_uint2(1, 2), 0x1037cb9d);
    assert_eq!(nr::hash_uint3(3, 4, 5), 0x780b3b93);
    assert_eq!(nr::hash_uint3(0xdeadbeef, 7, 0x12345678), 0x07c949d7);
    assert_eq!(nr::hash_uint4(1, 2, 3, 4), 0x0584dec1);
    assert_eq!(
        nr::hash_uint4(
            1.5f32.to_bits(),
            (-2.0f32).to_bits(),
            0.25f32.to_bits(),
            1.0f32.to_bits()
        ),
        0x6da8f071
    );
}

/// A small xorshift for sample points, independent of the hashes under test.
struct Points(u32);

impl Points {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / 16_777_216.0
    }

    fn in_box(&mut self, half: f32) -> [f32; 3] {
        [0, 1, 2].map(|_| (self.next() * 2.0 - 1.0) * half)
    }
}

#[test]
fn reference_float_hashes_are_uniform_in_unit_interval_and_decorrelated() {
    let n = 20_000;
    let mut sum = [0.0f64; 3];
    let mut cross = 0.0f64;
    for i in 0..n {
        let c = [
            (i % 31) as f32,
            (i / 31 % 29) as f32 - 14.0,
            (i / 899) as f32,
        ];
        let h = nr::hash_vec3_to_vec3(c);
        assert_eq!(h[0], nr::hash_vec3_to_float(c));
        for (k, &x) in h.iter().enumerate() {
            assert!((0.0..1.0).contains(&x), "hash {x} of {c:?} outside [0, 1)");
            sum[k] += f64::from(x);
        }
        cross += f64::from(h[1] - 0.5) * f64::from(h[2] - 0.5);
    }
    for s in sum {
        let mean = s / f64::from(n);
        assert!(
            (mean - 0.5).abs() < 0.01,
            "mean {mean}, expected 0.5 ± 0.01"
        );
    }
    // The covariance of two independent U(0, 1) is 0; its standard error here is ~6e-4.
    let cov = cross / f64::from(n);
    assert!(cov.abs() < 0.004, "covariance {cov}, expected 0 ± 0.004");
    // Bit patterns are hashed: -0.0 and 0.0 are different keys, as in Cycles.
    assert_ne!(nr::hash_float_to_float(0.0), nr::hash_float_to_float(-0.0));
    assert!(nr::uint_to_unit_float(u32::MAX) < 1.0);
}

#[test]
fn reference_rgb_hsv_round_trip_is_within_1e6_on_unit_cube() {
    let steps = 20;
    for r in 0..=steps {
        for g in 0..=steps {
            for b in 0..=steps {
                let c = [r, g, b].map(|x| x as f32 / steps as f32);
                let hsv = nr::rgb_to_hsv(c);
                assert!((0.0..1.0).contains(&hsv[0]), "hue {} of {c:?}", hsv[0]);
                assert!(
                    (0.0..=1.0).contains(&hsv[1]),
                    "saturation {} of {c:?}",
                    hsv[1]
                );
                let back = nr::hsv_to_rgb(hsv);
                for k in 0..3 {
                    assert!(
                        (back[k] - c[k]).abs() <= 1e-6,
                        "{c:?} -> {hsv:?} -> {back:?}, expected ± 1e-6"
                    );
                }
            }
        }
    }
    assert_eq!(nr::rgb_to_hsv([1.0, 0.0, 0.0]), [0.0, 1.0, 1.0]);
    assert_eq!(nr::rgb_to_hsv([0.0, 0.5, 0.0]), [1.0 / 3.0, 1.0, 0.5]);
    assert_eq!(nr::rgb_to_hsv([0.3, 0.3, 0.3]), [0.0, 0.0, 0.3]);
    assert_eq!(nr::hsv_to_rgb([1.0, 1.0, 1.0]), [1.0, 0.0, 0.0]);
}

fn assert_close3(got: [f32; 3], want: [f32; 3], tol: f32, what: &str) {
    for k in 0..3 {
        assert!(
            (got[k] - want[k]).abs() <= tol,
            "{what}: {got:?}, expected {want:?} ± {tol}"
        );
    }
}

#[test]
fn reference_mix_color_with_zero_factor_returns_the_first_colour() {
    let mut pts = Points(0x9e37_79b9);
    for blend in 0..19 {
        for _ in 0..200 {
            let a = [0, 1, 2].map(|_| pts.next());
            let b = [0, 1, 2].map(|_| pts.next());
            assert_close3(
                nr::mix_color(blend, 0.0, a, b),
                a,
                2e-6,
                &format!("blend {blend}"),
            );
        }
    }
}

#[test]
fn reference_mix_color_matches_blender_formulas_at_known_points() {
    let a = [0.5, 0.25, 0.8];
    let b = [0.5, 1.0, 0.0];
    let cases: [(u32, [f32; 3]); 11] = [
        (0, b),
        (1, [0.25, 0.25, 0.0]),
        (2, [0.75, 1.0, 0.8]),
        (4, [1.0, 1.25, 0.8]),
        (5, [0.0, -0.75, 0.8]),
        (6, [0.0, 0.75, 0.8]),
        (7, [0.5, 1.0, 0.8]),
        (8, [0.5, 0.25, 0.0]),
        // Divide leaves a channel alone where b is 0.
        (9, [1.0, 0.25, 0.8]),
        (17, [0.5, 1.25, -0.2]),
        // a + b - 2ab, floored at 0.
        (18, [0.5, 0.75, 0.8]),
    ];
    for (blend, want) in cases {
        assert_close3(
            nr::mix_color(blend, 1.0, a, b),
            want,
            1e-6,
            &format!("blend {blend}"),
        );
    }
    // Hue and Color take nothing from a grey b; Saturation changes nothing on a grey a.
    let grey = [0.4, 0.4, 0.4];
    assert_eq!(nr::mix_color(12, 1.0, a, grey), a);
    assert_eq!(nr::mix_color(15, 1.0, a, grey), a);
    assert_eq!(nr::mix_color(13, 1.0, grey, b), grey);
    // Value of b = 1 on a red keeps the hue and saturation.
    assert_close3(
        nr::mix_color(14, 1.0, [0.5, 0.0, 0.0], [0.0, 1.0, 0.0]),
        [1.0, 0.0, 0.0],
        1e-6,
        "value",
    );
}

#[test]
fn reference_voronoi_zero_randomness_f1_is_distance_to_nearest_lattice_point() {
    let mut pts = Points(12345);
    for _ in 0..500 {
        let p = pts.in_box(3.0);
        let (f1, f2, pos) = nr::voronoi_brute_force(p, 2.0, 0.0, 0, 1.0);
        let q = p.map(|x| x * 2.0);
        let nearest = q.map(f32::round);
        let d = ((q[0] - nearest[0]).powi(2)
            + (q[1] - nearest[1]).powi(2)
            + (q[2] - nearest[2]).powi(2))
        .sqrt();
        assert!((f1 - d).abs() < 1e-5, "F1 {f1} at {p:?}, expected {d}");
        assert!(f2 >= f1);
        assert_close3(pos, nearest.map(|x| x / 2.0), 1e-6, "F1 position");
    }
}

/// Blender's 3×3×3 search against the 7×7×7 brute force at full randomness. The small
/// window is Blender's own approximation: a point two cells away can be nearer than all
/// 27 searched. Measured over 1e5 points (scale 1.7, Minkowski exponent 1.5), F1 missed
/// 0 / 43 / 0 / 2 times and F2 2 / 387 / 0 / 25 times for euclidean / manhattan /
/// chebyshev / minkowski; this bounds the rates at 0.1 % (F1) and 1 % (F2).
#[test]
fn reference_voronoi_3x3x3_search_agrees_with_brute_force_but_for_rare_misses() {
    let mut pts = Points(777);
    let n = 20_000;
    for metric in 0..4 {
        let (mut f1_misses, mut f2_misses) = (0, 0);
        for _ in 0..n {
            let p = pts.in_box(4.0);
            let (b1, b2, bpos) = nr::voronoi_brute_force(p, 1.7, 1.0, metric, 1.5);
            let (f1, f2, pos1, _, col1, _) = nr::voronoi_blender(p, 1.7, 1.0, metric, 1.5);
            assert!(
                f1 >= b1 && f2 >= b2,
                "3x3x3 found a point the brute force missed"
            );
            if f1 == b1 {
                assert_close3(pos1, bpos, 1e-6, "F1 position");
            } else {
                f1_misses += 1;
            }
            if f2 != b2 {
                f2_misses += 1;
            }
            assert!(col1.iter().all(|c| (0.0..1.0).contains(c)));
            // Bounds from the own cell's point and one face neighbour's (see node_voronoi).
            let (f1_max, f2_max) = match metric {
                0 => (3f32.sqrt(), 6f32.sqrt()),
                1 => (3.0, 4.0),
                2 => (1.0, 2.0),
                _ => (3f32.powf(1.0 / 1.5), 6f32.powf(1.0 / 1.5)),
            };
            assert!((0.0..=f1_max).contains(&f1), "F1 {f1} > {f1_max}");
            assert!(f2 <= f2_max + 1e-6, "F2 {f2} > {f2_max}");
        }
        assert!(
            f1_misses * 1000 <= n && f2_misses * 100 <= n,
            "metric {metric}: F1 missed {f1_misses}, F2 {f2_misses} of {n}; \
             expected at most 0.1 % and 1 %"
        );
    }
}
