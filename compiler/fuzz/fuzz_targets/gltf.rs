//! glTF scenes (`sshc_scene::Scene::from_gltf_slice`: JSON or GLB bytes, buffers in the GLB
//! chunk or in data URIs).
//!
//! Two kinds of input. One whose first byte is 0xFF drives a generator of glTF documents
//! with bounded sizes: up to 3 buffers (data URIs, the GLB chunk, a file URI that cannot be
//! read, a network address), 6 buffer views and 8 accessors whose offsets, lengths, strides,
//! counts, component types and element types sit on and around the edges of their buffers,
//! 4 meshes of up to 3 primitives (every mode, NORMAL present or not, indices or not), 8
//! nodes (children that may repeat or loop, matrices or TRS with 0, -0, NaN, inf, 1e30, a
//! mirror), cameras, `KHR_lights_punctual` lights of every kind with numeric and broken
//! `extras`, and required extensions. The document is written as JSON or as GLB (its chunk
//! lengths sometimes cut), with the buffer bytes random or holding finite floats and valid
//! indices. Any other input is given to the loader as it is (the seeds include a city).
//!
//! Oracle: no panic; every accepted scene has finite triangles, normals and bounds, one
//! normal triple per triangle, at most `MAX_SCENE_TRIANGLES` triangles and `MAX_LIGHTS`
//! lights, a camera the scene checks accept, and notes that name the file; every refusal
//! names the file (`glTF ...`) and carries a hint.
#![no_main]

use base64::Engine;
use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use serde_json::{Value, json};
use sshc_scene::*;

fn float(u: &mut Unstructured) -> Result<Value> {
    Ok(match u.int_in_range(0..=12u8)? {
        // JSON has no NaN or infinity: serde_json writes them as null
        0 => json!(f64::NAN),
        1 => json!(1e30),
        2 => json!(-1e30),
        3 => json!(1e-30),
        4 => json!(-0.0),
        5 => json!(f32::MAX),
        6 => json!(u.arbitrary::<f32>()?),
        7 => json!("x"),
        _ => json!(f64::from(u.int_in_range(-8i8..=8)?) * 0.5),
    })
}

fn floats(u: &mut Unstructured, n: usize) -> Result<Value> {
    (0..n).map(|_| float(u)).collect::<Result<Vec<_>>>().map(Value::Array)
}

fn small(u: &mut Unstructured, edges: &[i64]) -> Result<Value> {
    Ok(if u.ratio(1u8, 4)? {
        json!(*u.choose(edges)?)
    } else {
        json!(u.int_in_range(0..=64u32)?)
    })
}

/// Bytes of a buffer: random, or finite floats then small indices (so that accessors over
/// it often read valid geometry).
fn buffer_bytes(u: &mut Unstructured) -> Result<Vec<u8>> {
    let len = u.int_in_range(0..=512usize)?;
    if u.arbitrary()? {
        return Ok(u.bytes(len.min(u.len()))?.to_vec());
    }
    let mut out = Vec::with_capacity(len);
    while out.len() + 4 <= len {
        let v: f32 = if out.len() < len / 2 {
            f32::from(u.int_in_range(-8i8..=8)?) * 0.25
        } else {
            f32::from_bits(u32::from(u.int_in_range(0..=5u8)?))
        };
        out.extend(if out.len() < len / 2 { v.to_le_bytes() } else { v.to_bits().to_le_bytes() });
    }
    Ok(out)
}

fn document(u: &mut Unstructured) -> Result<(Value, Option<Vec<u8>>)> {
    let mut blob = None;
    let mut buffers = Vec::new();
    let mut lengths = Vec::new();
    for _ in 0..u.int_in_range(0..=3u8)? {
        let bytes = buffer_bytes(u)?;
        let declared = match u.int_in_range(0..=5u8)? {
            0 => bytes.len() + 4,
            1 => bytes.len().saturating_sub(3),
            2 => 0,
            _ => bytes.len(),
        };
        lengths.push(bytes.len());
        let buffer = match u.int_in_range(0..=5u8)? {
            0 if blob.is_none() => {
                blob = Some(bytes);
                json!({"byteLength": declared})
            }
            1 => json!({"byteLength": declared, "uri": "missing.bin"}),
            2 => json!({"byteLength": declared, "uri": "https://example.invalid/a.bin"}),
            3 => json!({"byteLength": declared, "uri": "data:application/octet-stream;base64,@@"}),
            _ => json!({"byteLength": declared, "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bytes))}),
        };
        buffers.push(buffer);
    }
    let nb = buffers.len().max(1) as u32;
    let mut views = Vec::new();
    for _ in 0..u.int_in_range(0..=6u8)? {
        let b = u.int_in_range(0..=nb)?;
        let len = lengths.get(b as usize).copied().unwrap_or(0) as i64;
        let mut view = json!({
            "buffer": b,
            "byteOffset": small(u, &[0, len, len - 4, 4, i64::from(u32::MAX)])?,
            "byteLength": small(u, &[len, len + 1, 1, 12, 36, i64::from(u32::MAX)])?,
        });
        if u.arbitrary()? {
            view["byteStride"] = small(u, &[4, 12, 16, 252, 256, 0, 3])?;
        }
        views.push(view);
    }
    let nv = views.len().max(1) as u32;
    let mut accessors = Vec::new();
    for _ in 0..u.int_in_range(0..=8u8)? {
        let ty = *u.choose(&["VEC3", "SCALAR", "VEC2", "VEC4", "MAT4", "bogus"])?;
        let component = *u.choose(&[5126, 5125, 5123, 5121, 5122, 5120, 1])?;
        let mut a = json!({
            "componentType": component,
            "count": small(u, &[0, 1, 3, 4096, i64::from(u32::MAX), 1 << 24])?,
            "type": ty,
        });
        if !u.ratio(1u8, 8)? {
            a["bufferView"] = json!(u.int_in_range(0..=nv)?);
        }
        if u.arbitrary()? {
            a["byteOffset"] = small(u, &[0, 4, 3, i64::from(u32::MAX)])?;
        }
        if u.ratio(1u8, 6)? {
            a["normalized"] = json!(true);
        }
        if ty == "VEC3" && !u.ratio(1u8, 6)? {
            a["min"] = floats(u, 3)?;
            a["max"] = floats(u, 3)?;
        }
        if u.ratio(1u8, 12)? {
            a["sparse"] = json!({"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}});
        }
        accessors.push(a);
    }
    let na = accessors.len().max(1) as u32;
    let mut meshes = Vec::new();
    for _ in 0..u.int_in_range(0..=4u8)? {
        let mut prims = Vec::new();
        for _ in 0..u.int_in_range(0..=3u8)? {
            let mut attributes = serde_json::Map::new();
            if !u.ratio(1u8, 8)? {
                attributes.insert("POSITION".into(), json!(u.int_in_range(0..=na)?));
            }
            if u.arbitrary()? {
                attributes.insert("NORMAL".into(), json!(u.int_in_range(0..=na)?));
            }
            let mut p = json!({"attributes": attributes});
            if u.arbitrary()? {
                p["indices"] = json!(u.int_in_range(0..=na)?);
            }
            if u.ratio(1u8, 3)? {
                p["mode"] = json!(u.int_in_range(0..=7u8)?);
            }
            if u.ratio(1u8, 4)? {
                p["material"] = json!(0);
            }
            prims.push(p);
        }
        meshes.push(json!({"primitives": prims}));
    }
    let lights: Vec<Value> = (0..u.int_in_range(0..=6u8)?)
        .map(|_| {
            let kind = *u.choose(&["directional", "point", "spot", "area"])?;
            let mut l = json!({"type": kind});
            if kind == "spot" {
                l["spot"] = json!({"outerConeAngle": 0.5});
            }
            match u.int_in_range(0..=5u8)? {
                0 => l["extras"] = json!({"angle_degrees": float(u)?, "radius": float(u)?}),
                1 => l["extras"] = json!({"radius": "wide"}),
                2 => l["extras"] = json!([1, 2]),
                _ => {}
            }
            Ok(l)
        })
        .collect::<Result<_>>()?;
    let (nm, nl, n_nodes) = (meshes.len().max(1) as u32, lights.len().max(1) as u32, u.int_in_range(0..=8u8)?);
    let mut nodes = Vec::new();
    for _ in 0..n_nodes {
        let mut n = json!({});
        if u.ratio(2u8, 3)? {
            n["mesh"] = json!(u.int_in_range(0..=nm)?);
        }
        if u.ratio(1u8, 4)? {
            let children: Vec<u8> = (0..u.int_in_range(0..=3u8)?).map(|_| u.int_in_range(0..=n_nodes)).collect::<Result<_>>()?;
            n["children"] = json!(children);
        }
        match u.int_in_range(0..=4u8)? {
            0 => n["matrix"] = floats(u, 16)?,
            1 => {
                n["translation"] = floats(u, 3)?;
                n["rotation"] = floats(u, 4)?;
                n["scale"] = floats(u, 3)?;
            }
            2 => n["scale"] = json!([-1.0, 1.0, 1.0]),
            _ => {}
        }
        if u.ratio(1u8, 4)? {
            n["extensions"] = json!({"KHR_lights_punctual": {"light": u.int_in_range(0..=nl)?}});
        }
        if u.ratio(1u8, 8)? {
            n["camera"] = json!(0);
        }
        nodes.push(n);
    }
    let mut root = json!({
        "asset": {"version": "2.0"},
        "buffers": buffers,
        "bufferViews": views,
        "accessors": accessors,
        "meshes": meshes,
        "nodes": nodes,
        "materials": [{}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
    });
    if u.arbitrary()? {
        root["cameras"] = json!([match u.int_in_range(0..=2u8)? {
            0 => json!({"type": "perspective", "perspective": {"yfov": float(u)?, "znear": float(u)?, "aspectRatio": float(u)?}}),
            1 => json!({"type": "orthographic", "orthographic": {"xmag": float(u)?, "ymag": float(u)?, "znear": float(u)?, "zfar": float(u)?}}),
            _ => json!({"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}),
        }]);
    }
    if u.arbitrary()? {
        let all: Vec<u8> = (0..n_nodes).collect();
        root["scenes"] = json!([{"nodes": all}]);
        root["scene"] = json!(0);
    }
    if u.ratio(1u8, 6)? {
        root["extensionsRequired"] = json!([*u.choose(&["KHR_mesh_quantization", "KHR_materials_unlit", "KHR_lights_punctual", "EXT_meshopt_compression"])?]);
    }
    Ok((root, blob))
}

fn glb(u: &mut Unstructured, json: &[u8], blob: Option<&[u8]>) -> Result<Vec<u8>> {
    let pad = |v: &mut Vec<u8>, fill: u8| {
        while !v.len().is_multiple_of(4) {
            v.push(fill);
        }
    };
    let mut j = json.to_vec();
    pad(&mut j, b' ');
    let mut out = Vec::new();
    let total = 12 + 8 + j.len() + blob.map_or(0, |b| 8 + b.len().next_multiple_of(4));
    let cut: u32 = if u.ratio(1u8, 8)? { u.arbitrary()? } else { total as u32 };
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(cut.to_le_bytes());
    let json_len: u32 = if u.ratio(1u8, 8)? { u.arbitrary()? } else { j.len() as u32 };
    out.extend(json_len.to_le_bytes());
    out.extend(b"JSON");
    out.extend(&j);
    if let Some(b) = blob {
        let mut b = b.to_vec();
        pad(&mut b, 0);
        out.extend((b.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(b);
    }
    Ok(out)
}

fn drive(bytes: &[u8]) {
    let scene = match Scene::from_gltf_slice(bytes) {
        Ok(s) => s,
        Err(e) => {
            let text = e.to_string();
            assert!(text.contains("glTF") || text.contains("<scene>"), "a refusal that names no file: {text}");
            assert!(e.hint().is_some_and(|h| !h.is_empty()), "a refusal without a hint: {text}");
            return;
        }
    };
    let (tris, normals) = (scene.triangles(), scene.normals());
    assert!(tris.len() <= MAX_SCENE_TRIANGLES);
    assert_eq!(tris.len(), normals.len());
    assert!(tris.iter().flatten().all(|v| v.is_finite()), "accepted a non-finite triangle");
    assert!(normals.iter().flatten().all(|v| v.is_finite()), "accepted a non-finite normal");
    let (lo, hi) = scene.bounds();
    assert!(lo.is_finite() && hi.is_finite(), "non-finite bounds");
    assert!((1..=MAX_LIGHTS).contains(&scene.lights.len()), "{} lights", scene.lights.len());
    assert!(scene.notes().iter().all(|n| n.starts_with("<memory>: ")), "{:?}", scene.notes());
    // what the commands compute next: no panic
    let _ = scene.camera_view_proj();
    let _ = scene.fingerprint();
    for l in &scene.lights {
        let _ = scene.light_view(l);
        let _ = scene.penumbra_reach(l);
    }
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        let Ok((root, blob)) = document(&mut u) else { return };
        let text = root.to_string().into_bytes();
        let bytes = if blob.is_some() || u.ratio(1u8, 4).unwrap_or(false) {
            let Ok(b) = glb(&mut u, &text, blob.as_deref()) else { return };
            b
        } else {
            text
        };
        drive(&bytes);
    } else {
        drive(data);
    }
});
