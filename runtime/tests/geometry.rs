//! The machinery of Geometry passes on a GPU (lavapipe without one): the edge adjacency
//! built when a scene is bound, a `Silhouettes` compute step appending one record per
//! silhouette edge with the draw arguments, and `Primitives` steps drawing the records
//! indirectly under each resolve rule, with no read-back in between.
//!
//! The classification here is this test's own WGSL, written from the rule in the
//! `adjacency` module's documentation; the counts it produces on the GPU are checked
//! against the CPU statement of the rule (`Adjacency::silhouette_count`).

use sshc_runtime::adjacency::Adjacency;
use sshc_runtime::gpu::{GeneratedLimits, Gpu, RuntimeError, SceneInputs, TargetLimits};
use sshc_runtime::graph::*;

mod common;
use common::identity;

/// Vertices per record in the test's primitive draw: one full-screen triangle.
const VERTS: u32 = 3;

fn shaders() -> (String, String) {
    let classify = format!(
        "{FRAME_WGSL}
@group(0) @binding(0) var<uniform> frame: Frame;
{EDGE_WGSL}struct Record {{ a: vec4<f32>, b: vec4<f32> }}
struct Generated {{
    vertex_count: atomic<u32>, instance_count: u32, first_vertex: u32, first_instance: u32,
    claimed: atomic<u32>, dropped: atomic<u32>, pad: vec2<u32>,
    records: array<Record>,
}}
@group(3) @binding(0) var<storage, read> edges: array<Edge>;
@group(3) @binding(1) var<storage, read> planes: array<vec4<f32>>;
@group(3) @binding(2) var<storage, read> edge_faces: array<u32>;
@group(3) @binding(3) var<storage, read_write> out: Generated;

fn faces_light(f: u32) -> bool {{
    let p = planes[f >> 1u];
    return dot(p.xyz, frame.light_position.xyz) + p.w * frame.light_position.w > 0.0;
}}

@compute @workgroup_size(64)
fn cs_silhouettes(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {{
    let i = id.x + id.y * 64u * n.x;
    if i >= arrayLength(&edges) {{ return; }}
    let e = edges[i];
    var silhouette = e.face_count == 1u;
    let first = faces_light(edge_faces[e.first_face]);
    for (var k = 1u; k < e.face_count; k++) {{
        silhouette = silhouette || faces_light(edge_faces[e.first_face + k]) != first;
    }}
    if !silhouette {{ return; }}
    // the header's contract (GENERATED_HEADER_BYTES): claim a slot, count one past the
    // capacity as dropped, count the vertices once the record is written
    let at = atomicAdd(&out.claimed, 1u);
    if at >= arrayLength(&out.records) {{
        atomicAdd(&out.dropped, 1u);
        return;
    }}
    out.records[at] = Record(vec4<f32>(e.a, 1.0), vec4<f32>(e.b, 1.0));
    atomicAdd(&out.vertex_count, {VERTS}u);
}}
"
    );
    // Each record draws a full-screen triangle whose fragments write a value derived from
    // the record: the same 1/64 shadow amount for `Add`, 0.9 for `Multiply`, and
    // (a.x + 2) / 4 of its first end point for `KeepMin` and `KeepMax`; for `Nearest`,
    // that as its depth and 1 minus it as its value (the value of the nearest fragment
    // is kept, not the smallest value).
    let draw = "
struct Record { a: vec4<f32>, b: vec4<f32> }
struct Generated { vertex_count: u32, instance_count: u32, first_vertex: u32, first_instance: u32, claimed: u32, dropped: u32, pad: vec2<u32>, records: array<Record> }
@group(3) @binding(4) var<storage, read> gen: Generated;
struct VOut { @builtin(position) pos: vec4<f32>, @location(0) @interpolate(flat) v: f32 }
@vertex fn vs_prim(@builtin(vertex_index) vi: u32) -> VOut {
    let r = gen.records[vi / 3u];
    let k = vi % 3u;
    var o: VOut;
    o.pos = vec4<f32>(select(-1.0, 3.0, k == 1u), select(-1.0, 3.0, k == 2u), 0.5, 1.0);
    o.v = (r.a.x + 2.0) / 4.0;
    return o;
}
@fragment fn fs_add(i: VOut) -> @location(0) vec4<f32> { return vec4<f32>(1.0 / 64.0); }
@fragment fn fs_multiply(i: VOut) -> @location(0) vec4<f32> { return vec4<f32>(0.9); }
@fragment fn fs_value(i: VOut) -> @location(0) vec4<f32> { return vec4<f32>(i.v); }
struct DOut { @location(0) c: vec4<f32>, @builtin(frag_depth) depth: f32 }
@fragment fn fs_nearest(i: VOut) -> DOut { return DOut(vec4<f32>(1.0 - i.v), i.v); }
"
    .to_string();
    (classify, draw)
}

fn texture(name: &str) -> TextureDecl {
    TextureDecl {
        name: name.into(),
        format: Format::R16Float,
        layers: 1,
        extent: Extent::ShadowMap,
        mips: false,
        transient: false,
        channels: vec![],
        views: 1,
    }
}

fn step(vertex: Option<&str>, fragment: Option<&str>, compute: Option<&str>, draw: Draw, writes: Option<&str>) -> Step {
    Step {
        vertex: vertex.map(Into::into),
        fragment: fragment.map(Into::into),
        compute: compute.map(Into::into),
        draw,
        reads: vec![],
        writes: writes
            .map(|t| Target {
                texture: t.into(),
                layer: 0,
            })
            .into_iter()
            .collect(),
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    }
}

/// A graph with one Geometry pass: classification, then one `Primitives` step per
/// resolve rule, each into its own texture.
fn graph() -> (PassGraph, Vec<(String, String)>) {
    let (classify, draw) = shaders();
    let prims = |fs: &str, resolve: Resolve, t: &str| {
        step(
            Some("vs_prim"),
            Some(fs),
            None,
            Draw::Primitives {
                buffer: "sil".into(),
                resolve,
            },
            Some(t),
        )
    };
    let graph = PassGraph {
        version: SCHEMA_VERSION,
        technique: "geometry-test".into(),
        title: None,
        paper: None,
        lights: vec![LightModel::Any],
        params: vec![],
        params_size: 0,
        samples: 1,
        textures: {
            let mut t: Vec<TextureDecl> = ["add", "multiply", "min", "max"].map(texture).into();
            // a depth test blends nothing: a 32-bit float target is allowed
            t.push(TextureDecl {
                format: Format::R32Float,
                ..texture("nearest")
            });
            t
        },
        buffers: vec![BufferDecl {
            name: "sil".into(),
            record_bytes: 32,
            vertices_per_record: VERTS,
        }],
        passes: vec![
            PassDecl {
                name: "silhouettes".into(),
                kind: PassKind::Geometry,
                views: Views::LightCenter,
                shader: "classify.wgsl".into(),
                steps: vec![step(
                    None,
                    None,
                    Some("cs_silhouettes"),
                    Draw::Silhouettes { buffer: "sil".into() },
                    None,
                )],
            },
            PassDecl {
                name: "draw".into(),
                kind: PassKind::Geometry,
                views: Views::LightCenter,
                shader: "draw.wgsl".into(),
                steps: vec![
                    prims("fs_add", Resolve::Add, "add"),
                    prims("fs_multiply", Resolve::Multiply, "multiply"),
                    prims("fs_value", Resolve::KeepMin, "min"),
                    prims("fs_value", Resolve::KeepMax, "max"),
                    prims("fs_nearest", Resolve::Nearest, "nearest"),
                ],
            },
        ],
        removed: vec![],
        specialised: None,
        shadow_map: None,
    };
    (graph, vec![("classify.wgsl".into(), classify), ("draw.wgsl".into(), draw)])
}

/// An axis-aligned unit cube centred on `c`, outward-facing.
fn cube(c: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    let mut tris = Vec::new();
    for axis in 0..3 {
        for sign in [-0.5f32, 0.5] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut p = c;
                p[axis] += sign;
                p[u] += a;
                p[v] += b;
                p
            };
            let (p00, p10, p11, p01) = (corner(-0.5, -0.5), corner(0.5, -0.5), corner(0.5, 0.5), corner(-0.5, 0.5));
            if sign > 0.0 {
                tris.extend([[p00, p10, p11], [p00, p11, p01]]);
            } else {
                tris.extend([[p00, p11, p10], [p00, p01, p11]]);
            }
        }
    }
    tris
}

/// Three meshes: a closed cube, an open quad beside it, and three fins sharing one edge.
fn meshes() -> (Vec<[[f32; 3]; 3]>, Vec<std::ops::Range<u32>>) {
    let mut tris = cube([0.0, 0.0, 0.0]);
    let cube_end = tris.len() as u32;
    let q = [[2.0, 0.0, -0.5], [3.0, 0.0, -0.5], [3.0, 0.0, 0.5], [2.0, 0.0, 0.5]];
    tris.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
    let quad_end = tris.len() as u32;
    let (a, b) = ([-3.0, 0.0, 0.0], [-3.0, 1.0, 0.0]);
    tris.extend([[a, b, [-2.0, 0.0, 0.0]], [a, b, [-3.5, 0.0, 0.8]], [b, a, [-3.5, 0.0, -0.8]]]);
    let fins_end = tris.len() as u32;
    (tris, vec![0..cube_end, cube_end..quad_end, quad_end..fins_end])
}

fn inputs(tris: &[[[f32; 3]; 3]], meshes: Vec<std::ops::Range<u32>>, light: [f32; 4]) -> SceneInputs {
    SceneInputs {
        vertices: tris.iter().flatten().flat_map(|p| [p[0], p[1], p[2], 0.0, 1.0, 0.0]).collect(),
        meshes,
        casting_vertices: None,
        unshadowed: vec![],
        camera_view_proj: identity(),
        camera_position: [0.0, 5.0, 0.0],
        camera_size: (4, 4),
        shadow_size: 4,
        light_view: identity(),
        light_view_proj: identity(),
        light_position: light,
        near: 0.1,
        far: 10.0,
        light_size: 0.0,
        light_half_extents: [0.0; 2],
        light_angle: 0.0,
        light_proj_y: 1.0,
        light_orthographic: light[3] == 0.0,
        samples: Vec::new(),
        samples_closed: false,
        light: None,
    }
}

#[test]
fn silhouettes_classified_on_the_gpu_match_the_cpu_count_and_draw_under_every_resolve_rule() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (g, shaders) = graph();
    let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    let (tris, ranges) = meshes();
    let adj = Adjacency::build(&tris, ranges.iter().map(|r| r.start as usize..r.end as usize));
    let lights = [
        [0.0, 10.0, 0.0, 1.0],   // above the cube: its top square
        [10.0, 10.0, 10.0, 1.0], // off a corner: a hexagon
        [0.0, 0.0, 0.0, 1.0],    // inside the cube: nothing of the cube
        [0.3, 1.0, 0.2, 0.0],    // distant, from above
        [-1.0, 0.2, 0.0, 0.0],   // distant, grazing the fins
    ];
    let mut counts = Vec::new();
    for light in lights {
        let mut ex = common::bind(&t, &inputs(&tris, ranges.clone(), light)).unwrap_or_else(|e| panic!("{e}"));
        let c = ex.scene.edge_counts().expect("a graph with Geometry passes has edges");
        assert_eq!(c, adj.counts, "the runtime's adjacency is the CPU's");
        assert_eq!((c.meshes, c.boundary, c.non_manifold), (3, 4 + 6, 1), "{c:?}");
        ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
        let expected = adj.silhouette_count(light);
        let generated = ex.targets.inspect().generated("sil").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(generated.records as usize, expected, "light {light:?}");
        assert_eq!((generated.vertices, generated.instances), (VERTS * generated.records, 1));
        counts.push(expected);

        // Every texel is covered by every record's triangle. f16 targets: each blend rounds
        // to 11 significant bits (relative 2^-11), so n blends are within n 2^-11.
        let n = expected as f32;
        let texel = |t: &str| {
            ex.targets
                .inspect()
                .read_texture(t, 0, 0)
                .unwrap_or_else(|e| panic!("{e}"))
                .channel(0)
        };
        let ulp = 2f32.powi(-11);
        for v in texel("add") {
            assert!((v - (1.0 - n / 64.0)).abs() <= (n + 1.0) * ulp, "add: {v} for {n} records");
        }
        for v in texel("multiply") {
            let want = 0.9f32.powi(expected as i32);
            assert!((v - want).abs() <= (n + 1.0) * ulp * want, "multiply: {v} against {want}");
        }
        let values: Vec<f32> = adj
            .edges
            .iter()
            .filter(|e| adj.is_silhouette(e, light))
            .map(|e| (e.a[0] + 2.0) / 4.0)
            .collect();
        let min = values.iter().copied().fold(1.0f32, f32::min);
        let max = values.iter().copied().fold(0.0f32, f32::max);
        for v in texel("min") {
            assert!((v - min).abs() <= ulp, "min: {v} against {min}");
        }
        for v in texel("max") {
            assert!((v - max).abs() <= ulp, "max: {v} against {max}");
        }
        // f32 target; the depth buffer's 32-bit float orders the records' depths exactly
        for v in texel("nearest") {
            assert!((v - (1.0 - min)).abs() <= f32::EPSILON, "nearest: {v} against {}", 1.0 - min);
        }
    }
    // The lights see different silhouettes (the test is not one case five times).
    assert!(counts.iter().any(|&c| c != counts[0]), "{counts:?}");
}

/// The edges classified in chunks (one binding each) give what one dispatch over them all
/// gives: the same records and the same textures under every resolve rule. A chunk of one
/// edge is rounded up to the device's storage offset alignment (48-byte edges).
#[test]
fn edges_classified_in_chunks_give_the_same_records_and_textures() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (tris, ranges) = meshes();
    let light = [10.0, 10.0, 10.0, 1.0];
    let run = |chunk: Option<u32>| {
        let (g, shaders) = graph();
        let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
        let limits = TargetLimits {
            generated: GeneratedLimits {
                edges_per_chunk: chunk,
                records: None,
            },
            ..TargetLimits::default()
        };
        let mut ex = common::bind_within(&t, &inputs(&tris, ranges.clone(), light), limits).unwrap_or_else(|e| panic!("{e}"));
        ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
        let g = ex.targets.inspect().generated("sil").unwrap_or_else(|e| panic!("{e}"));
        let textures: Vec<Vec<u32>> = ["add", "multiply", "min", "max", "nearest"]
            .iter()
            .map(|t| {
                let img = ex.targets.inspect().read_texture(t, 0, 0).unwrap_or_else(|e| panic!("{e}"));
                img.channel(0).iter().map(|v| v.to_bits()).collect()
            })
            .collect();
        (g, textures)
    };
    let whole = run(None);
    let adj = Adjacency::build(&tris, ranges.iter().map(|r| r.start as usize..r.end as usize));
    assert_eq!(whole.0.records as usize, adj.silhouette_count(light));
    let align = u64::from(gpu.limits.min_storage_buffer_offset_alignment);
    let step = align / gcd(48, align);
    assert!(step < u64::from(adj.counts.edges), "a chunk of {step} edges would hold them all");
    let chunked = run(Some(1));
    assert_eq!(chunked.0, whole.0, "records");
    assert!(
        chunked.1 == whole.1,
        "the textures differ between one dispatch and chunks of {step} edges"
    );
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// A silhouettes buffer smaller than the frame's silhouettes keeps the records that fit,
/// draws those, and counts the rest as dropped: nothing is written past it, nothing half
/// drawn, and the count is reported.
#[test]
fn silhouettes_past_the_buffer_are_counted_as_dropped_and_the_rest_drawn() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (tris, ranges) = meshes();
    let light = [10.0, 10.0, 10.0, 1.0];
    let adj = Adjacency::build(&tris, ranges.iter().map(|r| r.start as usize..r.end as usize));
    let expected = adj.silhouette_count(light) as u32;
    assert!(expected > 3, "{expected}");
    let (g, shaders) = graph();
    let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    let limits = TargetLimits {
        generated: GeneratedLimits {
            edges_per_chunk: None,
            records: Some(3),
        },
        ..TargetLimits::default()
    };
    let mut ex = common::bind_within(&t, &inputs(&tris, ranges, light), limits).unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..2 {
        // twice: the header's counts are reset every frame
        ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
        let g = ex.targets.inspect().generated("sil").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (g.records, g.vertices, g.claimed, g.dropped),
            (3, 3 * VERTS, expected, expected - 3),
            "{g:?}"
        );
    }
    // three records drawn, each a full-screen 1/64 shadow amount under `Add`
    let ulp = 2f32.powi(-11);
    for v in ex
        .targets
        .inspect()
        .read_texture("add", 0, 0)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0)
    {
        assert!((v - (1.0 - 3.0 / 64.0)).abs() <= 4.0 * ulp, "add: {v}");
    }
}

#[test]
fn generated_buffers_are_bounded_before_allocation() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (g, shaders) = graph();
    let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    let (tris, ranges) = meshes();
    // The textures (4 x 16 texels of 2 bytes, the 16-texel depth and the 16-pixel camera
    // outputs: about 800 bytes) fit; the adjacency's bound for 17 triangles (2,108 bytes)
    // does not.
    let limits = TargetLimits {
        max_bytes: 1500,
        ..TargetLimits::default()
    };
    let e = common::bind_within(&t, &inputs(&tris, ranges, [0.0, 10.0, 0.0, 1.0]), limits)
        .err()
        .expect("a budget below the adjacency's bound must be refused");
    assert!(
        matches!(&e, RuntimeError::Limit { what, .. } if what.contains("edge adjacency")),
        "{e}"
    );
}

#[test]
fn drawing_a_buffer_nothing_wrote_is_refused_at_load() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = graph();
    g.passes.swap(0, 1);
    let e = common::load(&gpu, g, shaders).expect_err("drawing before classifying must be refused");
    assert!(e.to_string().contains("no earlier Silhouettes step writes it"), "{e}");
    let (mut g, shaders) = graph();
    g.buffers[0].record_bytes = 24;
    let e = common::load(&gpu, g, shaders).expect_err("a record size off the 16-byte grid must be refused");
    assert!(e.to_string().contains("record_bytes 24"), "{e}");
}
