//! Compiled pass graphs (`sshc_graph::PassGraph::from_ron`, the whole of the validation a
//! graph gets before a GPU is involved).
//!
//! Two kinds of input. One whose first byte is 0xFF (never the first byte of UTF-8 text)
//! drives a generator of `PassGraph` values: names drawn from small pools (so references
//! resolve, and duplicates and dangling names happen), params near and outside their
//! ranges, non-finite numbers, layer indices around the texture's layer count, shader
//! paths that escape; the value is written with `PassGraph::to_ron` and then edited as
//! text (see `mutate.rs`). Any other input is RON text as it is (the seeds are graphs the
//! compiler emitted).
//!
//! Oracle: no panic; and every graph `from_ron` accepts holds what the validation promises
//! (checked here independently of the library), and survives a round trip through
//! `to_ron` unchanged.
#![no_main]

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sshc_graph::*;

#[path = "mutate.rs"]
mod mutate;

const NAMES: &[&str] = &["shadow", "moments", "filtered", "vis", "tmp", "", "a b", "é"];
const SHADERS: &[&str] = &[
    "depth.wgsl",
    "shade.wgsl",
    "map.wgsl",
    "",
    ".",
    "..",
    ".hidden.wgsl",
    "../up.wgsl",
    "/etc/passwd",
    "a/b.wgsl",
    "c:\\x.wgsl",
    "dir\\x.wgsl",
];
const ENTRIES: &[&str] = &["vs", "fs_main", "cs_rows", ""];
const WORDS: &[&str] = &[
    "buffers",
    "record_bytes",
    "vertices_per_record",
    "buffer",
    "resolve",
    "Silhouettes",
    "Primitives",
    "KeepMin",
    "KeepMax",
    "Add",
    "Multiply",
    "version",
    "technique",
    "title",
    "paper",
    "lights",
    "params",
    "params_size",
    "textures",
    "passes",
    "removed",
    "name",
    "ty",
    "value",
    "range",
    "offset",
    "doc",
    "format",
    "layers",
    "extent",
    "mips",
    "transient",
    "channels",
    "layer",
    "component",
    "bias",
    "scale",
    "kind",
    "views",
    "shader",
    "steps",
    "vertex",
    "fragment",
    "compute",
    "draw",
    "reads",
    "writes",
    "sampler",
    "cost",
    "fetches",
    "ops",
    "binding",
    "texture",
    "view",
    "PreviousLevel",
    "Base",
    "All",
    "Depth",
    "Shade",
    "R32Float",
    "SummedAreaU32",
    "ShadowMap",
    "Camera",
    "LightCenter",
    "PerLightSample",
    "FullScreen",
    "MipLevels",
    "ComputeRows",
    "ComputeTexels",
    "ComputeMipLevels",
    "Any",
    "Point",
    "F32",
    "I32",
    "Bool",
];

fn name(u: &mut Unstructured) -> Result<String> {
    Ok(u.choose(NAMES)?.to_string())
}

fn number(u: &mut Unstructured) -> Result<f64> {
    Ok(match u.int_in_range(0..=9u8)? {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => f64::NEG_INFINITY,
        3 => f64::MAX,
        4 => -0.0,
        5 => u.arbitrary::<f64>()?,
        _ => f64::from(u.int_in_range(-4i8..=8)?) * 0.5,
    })
}

fn light_model(u: &mut Unstructured) -> Result<LightModel> {
    Ok(match u.int_in_range(0..=8u8)? {
        0 => LightModel::Any,
        k => {
            let kind = *u.choose(&LightKind::ALL)?;
            let samples = if k < 4 { u.int_in_range(0..=64)? } else { u.arbitrary()? };
            LightModel::of(kind, samples)
        }
    })
}

fn param(u: &mut Unstructured) -> Result<ParamDecl> {
    Ok(ParamDecl {
        name: name(u)?,
        ty: *u.choose(&[ParamType::F32, ParamType::I32, ParamType::Bool])?,
        value: number(u)?,
        range: if u.arbitrary()? { Some((number(u)?, number(u)?)) } else { None },
        offset: u.arbitrary()?,
        doc: if u.arbitrary()? { Some("d".into()) } else { None },
    })
}

const FORMATS: &[Format] = &[
    Format::R8Unorm,
    Format::Rg8Unorm,
    Format::Rgba8Unorm,
    Format::R16Unorm,
    Format::Rg16Unorm,
    Format::Rgba16Unorm,
    Format::R16Float,
    Format::Rg16Float,
    Format::Rgba16Float,
    Format::R32Float,
    Format::Rg32Float,
    Format::Rgba32Float,
    Format::SummedAreaU32,
];

fn small_u32(u: &mut Unstructured) -> Result<u32> {
    Ok(match u.int_in_range(0..=7u8)? {
        0 => u32::MAX,
        1 => u.arbitrary()?,
        _ => u.int_in_range(0..=4)?,
    })
}

fn texture(u: &mut Unstructured) -> Result<TextureDecl> {
    let channels = (0..u.int_in_range(0..=3)?)
        .map(|_| {
            Ok(ChannelDecl {
                name: name(u)?,
                layer: small_u32(u)?,
                component: small_u32(u)?,
                bias: number(u)?,
                scale: number(u)?,
                range: (number(u)?, number(u)?),
            })
        })
        .collect::<Result<_>>()?;
    Ok(TextureDecl {
        name: name(u)?,
        format: *u.choose(FORMATS)?,
        layers: small_u32(u)?,
        extent: *u.choose(&[Extent::ShadowMap, Extent::Camera])?,
        mips: u.arbitrary()?,
        transient: u.arbitrary()?,
        channels,
        views: u.int_in_range(0..=17)?,
    })
}

fn entry(u: &mut Unstructured) -> Result<Option<String>> {
    Ok(if u.arbitrary()? {
        Some(u.choose(ENTRIES)?.to_string())
    } else {
        None
    })
}

fn step(u: &mut Unstructured) -> Result<Step> {
    let reads = (0..u.int_in_range(0..=3)?)
        .map(|_| {
            Ok(Binding {
                binding: small_u32(u)?,
                texture: name(u)?,
                view: *u.choose(&[View::All, View::Base, View::PreviousLevel])?,
            })
        })
        .collect::<Result<_>>()?;
    let writes = (0..u.int_in_range(0..=2)?)
        .map(|_| {
            Ok(Target {
                texture: name(u)?,
                layer: small_u32(u)?,
            })
        })
        .collect::<Result<_>>()?;
    Ok(Step {
        vertex: entry(u)?,
        fragment: entry(u)?,
        compute: entry(u)?,
        draw: match u.int_in_range(0..=12)? {
            0 => Draw::SceneFromLight,
            1 => Draw::SceneFromCamera,
            2 => Draw::FullScreen,
            3 => Draw::MipLevels,
            4 => Draw::ComputeRows,
            5 => Draw::ComputeColumns,
            6 => Draw::Silhouettes { buffer: name(u)? },
            9 => Draw::ComputeTexels,
            10 => Draw::ComputeMipLevels,
            11 => Draw::CameraGBuffer,
            12 => Draw::ComputePixels,
            7 => Draw::Discontinuities {
                buffer: name(u)?,
                source: *u.choose(&[Neighbour::Previous, Neighbour::Next])?,
            },
            _ => Draw::Primitives {
                buffer: name(u)?,
                resolve: *u.choose(&[Resolve::KeepMin, Resolve::KeepMax, Resolve::Add, Resolve::Multiply])?,
            },
        },
        reads,
        writes,
        params: u.arbitrary()?,
        sampler: u.arbitrary()?,
        light_samples: u.arbitrary()?,
        cost: OpCount {
            fetches: small_u32(u)?,
            ops: small_u32(u)?,
        },
    })
}

fn pass(u: &mut Unstructured) -> Result<PassDecl> {
    Ok(PassDecl {
        name: name(u)?,
        kind: *u.choose(&[
            PassKind::Depth,
            PassKind::Map,
            PassKind::Filter,
            PassKind::Mipmap,
            PassKind::SummedArea,
            PassKind::Geometry,
            PassKind::Shade,
        ])?,
        views: *u.choose(&[Views::LightCenter, Views::PerLightSample])?,
        shader: u.choose(SHADERS)?.to_string(),
        steps: (0..u.int_in_range(0..=3)?).map(|_| step(u)).collect::<Result<_>>()?,
    })
}

fn graph(u: &mut Unstructured) -> Result<PassGraph> {
    Ok(PassGraph {
        version: if u.ratio(1, 16)? { u.arbitrary()? } else { SCHEMA_VERSION },
        technique: name(u)?,
        title: if u.arbitrary()? { Some(name(u)?) } else { None },
        paper: None,
        lights: (0..u.int_in_range(0..=3)?).map(|_| light_model(u)).collect::<Result<_>>()?,
        params: (0..u.int_in_range(0..=4)?).map(|_| param(u)).collect::<Result<_>>()?,
        params_size: small_u32(u)?,
        samples: u.int_in_range(0..=17)?,
        textures: (0..u.int_in_range(0..=5)?).map(|_| texture(u)).collect::<Result<_>>()?,
        buffers: (0..u.int_in_range(0..=2)?)
            .map(|_| {
                Ok(BufferDecl {
                    name: name(u)?,
                    // around the limits: 0, off the 16-byte grid, the largest, beyond
                    record_bytes: *u.choose(&[0, 16, 24, 48, 1024, 1040, u32::MAX])?,
                    vertices_per_record: *u.choose(&[0, 1, 120, 4096, 4097, u32::MAX])?,
                })
            })
            .collect::<Result<_>>()?,
        passes: (0..u.int_in_range(0..=6)?).map(|_| pass(u)).collect::<Result<_>>()?,
        removed: (0..u.int_in_range(0..=2)?).map(|_| name(u)).collect::<Result<_>>()?,
        specialised: if u.arbitrary()? {
            Some(SceneFacts {
                scene: name(u)?,
                light: *u.choose(&LightKind::ALL)?,
                // outside [0, 1] and NaN too: the runtime compares, it does not trust
                depth_floor: if u.arbitrary()? {
                    Some(*u.choose(&[0.0, 0.25, 1.0, -1.0, 2.0, f32::NAN, f32::INFINITY])?)
                } else {
                    None
                },
            })
        } else {
            None
        },
        // 0 and sizes past any device too: the validation refuses them
        shadow_map: if u.arbitrary()? { Some(*u.choose(&[0, 1, 1024, 16384, 16385, u32::MAX])?) } else { None },
    })
}

/// What `from_ron` promises of a graph it accepts, checked without the library's helpers.
fn check_accepted(g: &PassGraph, text: &str) {
    assert_eq!(g.version, SCHEMA_VERSION);
    if let Some(n) = g.shadow_map {
        assert!((1..=sshc_graph::MAX_SHADOW_MAP).contains(&n), "accepted a shadow map of {n} texels: {text}");
    }
    for p in &g.params {
        assert!(p.value.is_finite(), "accepted a non-finite param value: {text}");
        if let Some((lo, hi)) = p.range {
            assert!(lo.is_finite() && hi.is_finite() && lo <= hi && lo <= p.value && p.value <= hi);
        }
    }
    let unique = |names: Vec<&str>| {
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        sorted.len() == names.len()
    };
    assert!(
        unique(g.textures.iter().map(|t| t.name.as_str()).collect()),
        "duplicate texture: {text}"
    );
    assert!(unique(g.passes.iter().map(|p| p.name.as_str()).collect()), "duplicate pass: {text}");
    assert!(
        unique(g.params.iter().map(|p| p.name.as_str()).collect()),
        "duplicate param: {text}"
    );
    assert!(g.textures.iter().all(|t| t.layers >= 1));
    if let Some(f) = g.specialised.as_ref().and_then(|s| s.depth_floor) {
        assert!((0.0..=1.0).contains(&f), "accepted a depth floor outside [0, 1]: {text}");
    }
    for t in &g.textures {
        for c in &t.channels {
            assert!(
                c.bias.is_finite() && c.scale.is_finite() && c.scale != 0.0,
                "accepted a channel's bias or scale: {text}"
            );
            assert!(c.range.0.is_finite() && c.range.1.is_finite() && c.range.0 <= c.range.1);
            assert!(c.layer < t.layers && c.component <= 3, "a channel outside its texture: {text}");
        }
    }
    assert!(
        unique(g.buffers.iter().map(|b| b.name.as_str()).collect()),
        "duplicate buffer: {text}"
    );
    for b in &g.buffers {
        assert!(b.record_bytes >= 16 && b.record_bytes % 16 == 0 && b.record_bytes <= MAX_RECORD_BYTES);
        assert!((1..=MAX_VERTICES_PER_RECORD).contains(&b.vertices_per_record));
    }
    // Light samples: 1 to MAX_LIGHT_SAMPLES; a texture holds one view or one per sample,
    // and per-sample passes write only per-sample textures.
    assert!((1..=MAX_LIGHT_SAMPLES).contains(&g.samples), "samples {}: {text}", g.samples);
    for p in &g.passes {
        for w in p.steps.iter().flat_map(|s| &s.writes) {
            let views = g.texture(&w.texture).map_or(1, |t| t.views);
            let want = if p.views == Views::PerLightSample { g.samples } else { 1 };
            assert_eq!(views, want, "pass {} writes a texture of {views} view(s): {text}", p.name);
        }
    }
    // Camera-sized textures (a Shade's debug outputs): one layer, one view, no mip chain,
    // written by a Shade's camera steps only (and those write nothing else), read by none.
    for t in g.textures.iter().filter(|t| t.extent == Extent::Camera) {
        assert!(t.layers == 1 && t.views == 1 && !t.mips, "a camera-sized texture's shape: {text}");
    }
    for st in g.passes.iter().flat_map(|p| &p.steps) {
        for w in &st.writes {
            let camera = g.texture(&w.texture).is_some_and(|t| t.extent == Extent::Camera);
            assert_eq!(camera, st.draw.writes_camera_textures(), "{:?} writes {}: {text}", st.draw, w.texture);
        }
        let read_camera = st.reads.iter().any(|b| g.texture(&b.texture).is_some_and(|t| t.extent == Extent::Camera));
        assert!(!read_camera, "a camera-sized texture read: {text}");
    }
    // Steps name the entry points their draw needs.
    for st in g.passes.iter().flat_map(|p| &p.steps) {
        if st.draw.is_dispatch() {
            assert!(st.compute.is_some() && st.vertex.is_none() && st.fragment.is_none(), "dispatch entries: {text}");
        } else {
            assert!(st.compute.is_none() && st.vertex.is_some() && st.fragment.is_some(), "draw entries: {text}");
        }
    }
    // Generated buffers: declared, and drawn only after a Silhouettes step wrote them.
    let mut generated: Vec<&str> = Vec::new();
    for st in g.passes.iter().flat_map(|p| &p.steps) {
        match &st.draw {
            Draw::Silhouettes { buffer } | Draw::Discontinuities { buffer, .. } => {
                assert!(g.buffer(buffer).is_some(), "undeclared buffer: {text}");
                generated.push(buffer);
            }
            Draw::Primitives { buffer, .. } => assert!(generated.contains(&buffer.as_str()), "drawn before written: {text}"),
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::ComputeRows
            | Draw::ComputeColumns => {}
            // a deferred Shade: in a Shade pass, the G-buffer drawn before it is read
            Draw::CameraGBuffer | Draw::ComputePixels => {
                let p = g.passes.iter().find(|p| p.steps.iter().any(|x| std::ptr::eq(x, st))).expect("its pass");
                assert_eq!(p.kind, PassKind::Shade, "a deferred Shade's step in a {:?} pass: {text}", p.kind);
                if st.draw == Draw::ComputePixels {
                    let before = p.steps.iter().take_while(|x| !std::ptr::eq(*x, st));
                    assert!(before.into_iter().any(|x| x.draw == Draw::CameraGBuffer), "no G-buffer drawn: {text}");
                }
            }
            // what a compute step stores into has a storage format
            Draw::ComputeTexels | Draw::ComputeMipLevels => {
                for w in &st.writes {
                    let t = g.textures.iter().find(|t| t.name == w.texture).expect("a declared texture");
                    assert!(t.format.storable(), "compute writes {:?}: {text}", t.format);
                }
            }
        }
    }
    let mut written: Vec<&str> = Vec::new();
    for p in &g.passes {
        let s = p.shader.as_str();
        assert!(
            !s.is_empty() && !s.starts_with('.') && !s.contains(['/', '\\', ':']),
            "shader path {s:?}"
        );
        for st in &p.steps {
            for b in &st.reads {
                assert!(g.texture(&b.texture).is_some());
                let own_mips = b.view == View::PreviousLevel && st.writes.iter().any(|w| w.texture == b.texture);
                assert!(own_mips || written.contains(&b.texture.as_str()), "read before write: {text}");
            }
            for w in &st.writes {
                let t = g.texture(&w.texture).expect("a written texture is declared");
                assert!(w.layer < t.layers);
                written.push(&w.texture);
            }
        }
    }
    // Round trip: what the compiler would write for this graph reads back as the same
    // graph (compared as text, as the target always has).
    let again = g.to_ron();
    let back = PassGraph::from_ron(&again).unwrap_or_else(|e| panic!("round trip refused: {e}\n{again}"));
    assert_eq!(back.to_ron(), again, "round trip changed the graph");
}

fn drive(text: &str) {
    match PassGraph::from_ron(text) {
        Ok(g) => check_accepted(&g, text),
        Err(e) => {
            let _ = e.to_string();
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        if let Ok(g) = graph(&mut u) {
            let text = mutate::mutate(&mut u, g.to_ron(), WORDS);
            drive(&text);
        }
    } else if let Ok(text) = std::str::from_utf8(data) {
        drive(text);
    }
});
