//! Worlds baked into environment maps. A world graph ([`World`]) is compiled by the
//! material compiler and evaluated once per texel of an equirectangular map by a small
//! kernel of its own (`shaders/world/bake.wgsl`, run as a [`probe`](super::probe)); the
//! path tracer then reads and samples that map exactly as it does an environment map
//! loaded from a file (luminance-weighted CDFs, MIS against BSDF sampling). Cycles bakes
//! its world the same way for importance sampling, though it evaluates the shader itself
//! where rays escape.
//!
//! A Sky Texture's sun is not baked: a 0.5° disc is a texel or two of any map, which would
//! make its shadows hard-edged and its sampling depend on the resolution. The sky node
//! leaves its disc out and reports the sun's irradiance; each sun becomes a distant light
//! of the node's angular diameter, sampled analytically and hit by camera and BSDF rays
//! (`shaders/lights/analytic.wgsl`). What the graph does to the sky after the node (a
//! strength, a tint, a mix) it does to the sun too: the bake evaluates the world at the
//! sun's direction once with the sun's irradiance added to the sky's colour and once
//! without, and the difference is the light's irradiance (exact for any graph linear in
//! the sky, which is every mix, multiply and strength).
//!
//! A world whose output is a constant colour keeps the constant environment's exact
//! path: no map, no sampling tables.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

use glam::Vec3;

use super::context::GpuContext;
use super::environment_cdf::luminance;
use super::materials::scene_textures;
use super::probe::{Probe, run_probe};
use super::renderer::{RenderError, RenderSettings};
use crate::material::compile::{CompiledMaterial, compile_world};
use crate::material::graph::Value;
use crate::material::nodes::{self, WORLD_OUTPUT};
use crate::material::{Graph, Input, Link, Node, Param, library};
use crate::scene::{
    Camera, EnvironmentMap, GraphMaterial, Light, LightObject, Material, Scene, Sun, World,
};

/// What a world bakes into: the environment, and a sun light per Sky Texture with its
/// disc on.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedWorld {
    pub environment: Environment,
    pub suns: Vec<LightObject>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    Constant(Vec3),
    Map(EnvironmentMap),
}

/// `scene` with its world baked in: its environment map (or constant environment) and
/// sun lights in place of the graph. A scene without a world is returned as it is.
pub fn resolve_world<'a>(
    ctx: &GpuContext,
    scene: &'a Scene,
) -> Result<Cow<'a, Scene>, RenderError> {
    let Some(world) = &scene.world else {
        return Ok(Cow::Borrowed(scene));
    };
    let baked = bake_world(ctx, world)?;
    let mut resolved = scene.clone();
    resolved.world = None;
    match baked.environment {
        Environment::Constant(c) => {
            resolved.environment = c;
            resolved.environment_map = None;
        }
        Environment::Map(map) => {
            resolved.environment = Vec3::ZERO;
            resolved.environment_map = Some(map);
        }
    }
    resolved.lights.extend(baked.suns);
    Ok(Cow::Owned(resolved))
}

/// [`bake_world_now`], remembering the last world baked: the editor builds a renderer for
/// every edit of the scene's structure, and most of those leave the world as it was.
///
/// The bake runs on the context's rehearsal device where it has one (the editor's, on a
/// CPU adapter: see [`GpuContext::rehearse_compiles_on`]): the map comes back to the host,
/// so any device of the adapter serves, and lavapipe compiles the bake's kernel inside
/// the submission, which on the window's device would hold up its frames.
pub fn bake_world(ctx: &GpuContext, world: &World) -> Result<BakedWorld, RenderError> {
    static LAST: Mutex<Option<(World, BakedWorld)>> = Mutex::new(None);
    if let Some((w, baked)) = LAST.lock().expect("no panic holds it").as_ref()
        && w == world
    {
        return Ok(baked.clone());
    }
    let baked = bake_world_now(ctx.rehearsal().map_or(ctx, |r| r), world)?;
    *LAST.lock().expect("no panic holds it") = Some((world.clone(), baked.clone()));
    Ok(baked)
}

/// The colour of a world whose output reads no link: its colour × strength.
pub fn constant_world(world: &World) -> Option<Vec3> {
    let graph = &world.graph;
    let id = match &graph.output {
        Some(id) => id.clone(),
        None => {
            let mut outputs = graph.nodes.iter().filter(|(_, n)| n.kind == WORLD_OUTPUT);
            match (outputs.next(), outputs.next()) {
                (Some((id, _)), None) => id.clone(),
                _ => return None,
            }
        }
    };
    let node = graph.nodes.get(&id).filter(|n| n.kind == WORLD_OUTPUT)?;
    let def = nodes::find(WORLD_OUTPUT).expect("the library declares the world output");
    let value = |socket: &str| def.constant_input(node, socket);
    let colour = match value("color")? {
        Value::Vec3(c) => Vec3::from(c),
        Value::Float(f) => Vec3::splat(f),
        _ => return None,
    };
    let Value::Float(strength) = value("strength")? else {
        return None;
    };
    Some(colour.max(Vec3::ZERO) * strength.max(0.0))
}

/// Evaluates `world` into an environment map of `world.resolution` × half texels and its
/// suns into lights.
fn bake_world_now(ctx: &GpuContext, world: &World) -> Result<BakedWorld, RenderError> {
    let invalid = |e: String| RenderError::Scene(format!("world: {e}"));
    world.validate().map_err(invalid)?;
    let suns = world.suns().map_err(|e| invalid(e.to_string()))?;
    if suns.is_empty()
        && let Some(c) = constant_world(world)
    {
        return Ok(BakedWorld {
            environment: Environment::Constant(c),
            suns: Vec::new(),
        });
    }
    let scene = bake_scene(world);
    let code = bake_wgsl(world, &suns, &mut scene_textures(&scene).index)
        .map_err(|e| invalid(e.to_string()))?;
    let (width, height) = (world.resolution, world.resolution / 2);
    let texels = (width * height) as usize;
    let mut input: Vec<[f32; 4]> = vec![[width as f32, height as f32, suns.len() as f32, 0.0]];
    input.extend(suns.iter().map(|s| s.direction.extend(0.0).to_array()));
    let settings = RenderSettings {
        width: 1,
        height: 1,
        samples_per_pixel: 1,
        noise_threshold: 0.0,
        ..RenderSettings::from_scene(&scene)
    };
    let out = run_probe(
        ctx,
        &scene,
        &settings,
        &Probe {
            name: "world bake",
            parts: &[
                ("generated: world", &code),
                (
                    "shaders/world/bake.wgsl",
                    include_str!("../../shaders/world/bake.wgsl"),
                ),
            ],
            entry: "bake_world",
            input: bytemuck::cast_slice(&input),
            output_bytes: ((texels + 2 * suns.len()) * 16) as u64,
            invocations: (texels + suns.len()) as u32,
            material_params: &[],
        },
    )?;
    let out: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let map = EnvironmentMap {
        width,
        height,
        texels: out[..texels]
            .iter()
            .map(|t| Vec3::new(t[0], t[1], t[2]).max(Vec3::ZERO))
            .collect(),
        strength: 1.0,
        rotation_degrees: 0.0,
    };
    map.validate().map_err(invalid)?;
    let suns = suns
        .iter()
        .enumerate()
        .map(|(j, sun)| {
            let with = Vec3::from_slice(&out[texels + 2 * j][..3]);
            let without = Vec3::from_slice(&out[texels + 2 * j + 1][..3]);
            LightObject {
                light: Light::Distant {
                    direction: -sun.direction,
                    irradiance: (with - without).max(Vec3::ZERO),
                    angular_diameter: sun.angular_diameter,
                },
                name: format!("sun of world node \"{}\"", sun.node),
                visible: true,
            }
        })
        .collect();
    Ok(BakedWorld {
        environment: Environment::Map(map),
        suns,
    })
}

/// The luminance of the irradiance a baked world gives a surface facing up: its upper
/// hemisphere (each texel's radiance × cos θ × solid angle) and its suns.
pub fn horizontal_irradiance(baked: &BakedWorld) -> f32 {
    let sky = match &baked.environment {
        Environment::Constant(c) => luminance(*c) * std::f32::consts::PI,
        Environment::Map(map) => {
            let (w, h) = (map.width as usize, map.height as usize);
            let d_theta = std::f32::consts::PI / h as f32;
            let d_phi = std::f32::consts::TAU / w as f32;
            let mut sum = 0.0f64;
            for y in 0..h / 2 {
                let theta = (y as f32 + 0.5) * d_theta;
                let weight = theta.cos() * theta.sin() * d_theta * d_phi;
                let row: f32 = map.texels[y * w..(y + 1) * w]
                    .iter()
                    .map(|t| luminance(*t))
                    .sum();
                sum += f64::from(row * weight);
            }
            sum as f32 * map.strength
        }
    };
    let suns: f32 = baked
        .suns
        .iter()
        .map(|s| match s.light {
            Light::Distant {
                direction,
                irradiance,
                ..
            } => luminance(irradiance) * (-direction.normalize().y).max(0.0),
            _ => 0.0,
        })
        .sum();
    sky + suns
}

/// The exposure (stops) of the look-dev default under `baked`: a mid-grey (18%) ground
/// comes out at 0.18, so a white model stays below clipping in the sun and a dark one in
/// view; 0 for a world that gives no light.
pub fn lookdev_exposure(baked: &BakedWorld) -> f32 {
    let e = horizontal_irradiance(baked);
    if e > 0.0 && e.is_finite() {
        (std::f32::consts::PI / e).log2().clamp(-30.0, 30.0)
    } else {
        0.0
    }
}

/// The scene the bake runs in: empty but for a material holding the world's images, so
/// that they are bound.
fn bake_scene(world: &World) -> Scene {
    let mut scene = Scene::empty(Camera::look_at(Vec3::Z, Vec3::ZERO, 40.0));
    scene.materials = vec![Material {
        name: "world".into(),
        graph: Some(Arc::new(GraphMaterial {
            graph: world.graph.clone(),
            traits: Default::default(),
            images: world.images.clone(),
        })),
        ..Material::default()
    }];
    scene
}

/// The world's WGSL: `world_radiance(sp)`, and `world_sun(j, sp)`, the world with sun j's
/// irradiance added to its sky's colour ([`with_sun`]), with the library functions they
/// call.
fn bake_wgsl(
    world: &World,
    suns: &[Sun],
    textures: &mut BTreeMap<String, u32>,
) -> Result<String, crate::material::GraphError> {
    let mut compiled: Vec<CompiledMaterial> =
        vec![compile_world(&world.graph, "world_radiance", textures)?];
    for (j, sun) in suns.iter().enumerate() {
        compiled.push(compile_world(
            &with_sun(&world.graph, &sun.node),
            &format!("world_sun_{j}"),
            textures,
        )?);
    }
    let mut calls = std::collections::BTreeSet::from([
        "ShadingPoint".to_owned(),
        "nd_finite3".to_owned(),
        "nd_equirectangular_uv".to_owned(),
    ]);
    let mut code = String::new();
    for c in &compiled {
        calls.extend(c.calls.iter().cloned());
        code.push_str(&c.code);
    }
    code.push_str("fn world_sun(j: u32, sp: ShadingPoint) -> vec3<f32> {\n    switch (j) {\n");
    for j in 0..suns.len() {
        let _ = writeln!(code, "        case {j}u: {{ return world_sun_{j}(sp); }}");
    }
    code.push_str("        default: { return vec3<f32>(0.0); }\n    }\n}\n");
    Ok(format!("{}{code}", library::closure(calls)))
}

/// `graph` with the sky node `sky`'s colour, wherever it is read, replaced by its colour
/// plus its sun's irradiance (a Mix node adding them).
fn with_sun(graph: &Graph, sky: &str) -> Graph {
    let mut g = graph.clone();
    let mut id = format!("{sky}~sun");
    while g.nodes.contains_key(&id) {
        id.push('~');
    }
    let colour = Link::new(sky, "color");
    for node in g.nodes.values_mut() {
        for input in node.inputs.values_mut() {
            if *input == Input::Link(colour.clone()) {
                *input = Input::Link(Link::new(&id, "result"));
            }
        }
    }
    g.add(
        &id,
        Node::new("mix_color")
            .param("blend", Param::Text("add".into()))
            .input("factor", Input::Value(Value::Float(1.0)))
            .input("a", Input::Link(colour))
            .input("b", Input::Link(Link::new(sky, "sun"))),
    );
    g
}
