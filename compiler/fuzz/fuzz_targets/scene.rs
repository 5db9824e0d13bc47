//! Scene files (`sshc_scene::Scene::from_str` with a base folder for OBJ paths).
//!
//! Two kinds of input. One whose first byte is 0xFF (never the first byte of UTF-8 text)
//! drives a generator of `SceneDesc` values with bounded sizes (at most 6 objects and
//! `MAX_LIGHTS + 1` lights, one past what a scene may hold; numbers near the edges: 0,
//! -0, 1e-30, 1e30, f32::MAX, NaN, inf; sizes around the limits: 4096 x 4096 pixels,
//! 1024 sphere segments, u32::MAX), written as RON (with or without struct names) and
//! then edited as text (see `mutate.rs`). Any other input is RON text as it is (the
//! seeds are the bundled scenes).
//!
//! OBJ paths resolve in a folder made once per process: small valid and broken OBJ files,
//! a subfolder, and symbolic links leading out of it (refused by the loader).
//!
//! Scenes of more than 65,536 triangles within the limit are skipped (see
//! `MAX_FUZZ_TRIANGLES`); those over the limit are still read, and refused.
//!
//! Oracle: no panic, no allocation over libFuzzer's `-rss_limit_mb` / `-malloc_limit_mb`
//! (2048 MB by default), and every accepted scene has finite triangles, normals and
//! bounds, one normal triple per triangle, and at most `MAX_SCENE_TRIANGLES` triangles.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sshc_scene::*;

#[path = "mutate.rs"]
mod mutate;

const OBJ_PATHS: &[&str] = &[
    "tri.obj",
    "normals.obj",
    "empty.obj",
    "broken.obj",
    "nan.obj",
    "index.obj",
    "sub/tri.obj",
    "sub",
    "missing.obj",
    "out.obj",
    "zero.obj",
    "../tri.obj",
    "/etc/hostname",
    "",
    ".",
    "sub/../tri.obj",
    "./tri.obj",
];
const WORDS: &[&str] = &[
    "Scene",
    "camera",
    "shadow_map",
    "lights",
    "objects",
    "Perspective",
    "Orthographic",
    "position",
    "target",
    "up",
    "fov_y_degrees",
    "half_height",
    "width",
    "height",
    "near",
    "far",
    "Point",
    "Directional",
    "Sphere",
    "Disk",
    "Rectangle",
    "Segment",
    "Triangle",
    "DistantDisk",
    "direction",
    "center",
    "radius",
    "normal",
    "u_axis",
    "half_width",
    "a",
    "b",
    "c",
    "d",
    "angle_degrees",
    "Object",
    "name",
    "mesh",
    "transform",
    "flat_normals",
    "Plane",
    "Box",
    "Triangle",
    "Quad",
    "Obj",
    "path",
    "size",
    "segments",
    "translate",
    "rotate",
    "scale",
    "None",
    "Euler",
    "AxisAngle",
    "axis",
    "degrees",
    "(0.0, 1.0, 0.0)",
    "1024",
    "1025",
    "4096",
    "4097",
];

/// The OBJ folder, made once.
fn base() -> &'static PathBuf {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    BASE.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("sshc-fuzz-scene-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).expect("temp folder");
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let files: &[(&str, &str)] = &[
            ("tri.obj", tri),
            ("sub/tri.obj", tri),
            (
                "normals.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 0\nf 1//1 2//1 3//2 4//1\n",
            ),
            ("empty.obj", ""),
            ("broken.obj", "v 1 2\nf 1 2 x\n\u{0}"),
            ("nan.obj", "v nan 0 0\nv 1 inf 0\nv 0 1 0\nv 1e39 1 1\nf 1 2 3\nf 2 3 4\n"),
            ("index.obj", "v 0 0 0\nv 1 0 0\nf 1 2 99999\nf -1 -2 -3\nf 0 1 2\n"),
        ];
        for (name, text) in files {
            std::fs::write(dir.join(name), text).expect("temp file");
        }
        let _ = std::os::unix::fs::symlink("/etc/hostname", dir.join("out.obj"));
        let _ = std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj"));
        dir
    })
}

fn float(u: &mut Unstructured) -> Result<f32> {
    Ok(match u.int_in_range(0..=15u8)? {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => -1e30,
        3 => 1e30,
        4 => f32::MAX,
        5 => 1e-30,
        6 => -0.0,
        7 => u.arbitrary::<f32>()?,
        _ => f32::from(u.int_in_range(-8i8..=8)?) * 0.5,
    })
}

fn vec3(u: &mut Unstructured) -> Result<Vec3> {
    Ok(Vec3::new(float(u)?, float(u)?, float(u)?))
}

fn size(u: &mut Unstructured) -> Result<u32> {
    Ok(match u.int_in_range(0..=11u8)? {
        0 => u32::MAX,
        1 => 4096,
        2 => 4097,
        3 => 1 << 16,
        4 => u.arbitrary()?,
        _ => u.int_in_range(0..=64)?,
    })
}

fn near_far(u: &mut Unstructured) -> Result<Option<f32>> {
    Ok(if u.arbitrary()? { Some(float(u)?) } else { None })
}

fn camera(u: &mut Unstructured) -> Result<Camera> {
    let (position, target, up) = (vec3(u)?, vec3(u)?, if u.arbitrary()? { vec3(u)? } else { Vec3::Y });
    let (width, height) = (size(u)?, size(u)?);
    Ok(if u.arbitrary()? {
        Camera::Perspective {
            position,
            target,
            up,
            fov_y_degrees: if u.arbitrary()? { 45.0 } else { float(u)? },
            width,
            height,
            near: near_far(u)?,
            far: near_far(u)?,
        }
    } else {
        Camera::Orthographic {
            position,
            target,
            up,
            half_height: float(u)?,
            width,
            height,
            near: near_far(u)?,
            far: near_far(u)?,
        }
    })
}

fn light(u: &mut Unstructured) -> Result<Light> {
    Ok(match u.int_in_range(0..=7u8)? {
        0 => Light::Point { position: vec3(u)? },
        1 => Light::Directional { direction: vec3(u)? },
        2 => Light::Sphere {
            center: vec3(u)?,
            radius: float(u)?,
        },
        3 => Light::Disk {
            center: vec3(u)?,
            normal: vec3(u)?,
            radius: float(u)?,
        },
        4 => Light::Rectangle {
            center: vec3(u)?,
            normal: vec3(u)?,
            u_axis: vec3(u)?,
            half_width: float(u)?,
            half_height: float(u)?,
        },
        5 => Light::Segment { a: vec3(u)?, b: vec3(u)? },
        6 => Light::Triangle {
            a: vec3(u)?,
            b: vec3(u)?,
            c: vec3(u)?,
        },
        _ => Light::DistantDisk {
            direction: vec3(u)?,
            angle_degrees: float(u)?,
        },
    })
}

fn mesh(u: &mut Unstructured) -> Result<Mesh> {
    Ok(match u.int_in_range(0..=6u8)? {
        0 => Mesh::Plane {
            size: Vec2::new(float(u)?, float(u)?),
        },
        1 => Mesh::Box { size: vec3(u)? },
        2 => Mesh::Sphere {
            radius: float(u)?,
            segments: match u.int_in_range(0..=9u8)? {
                0 => MAX_SPHERE_SEGMENTS,
                1 => MAX_SPHERE_SEGMENTS + 1,
                2 => u32::MAX,
                _ => u.int_in_range(0..=48)?,
            },
        },
        3 => Mesh::Triangle {
            a: vec3(u)?,
            b: vec3(u)?,
            c: vec3(u)?,
        },
        4 => Mesh::Quad {
            a: vec3(u)?,
            b: vec3(u)?,
            c: vec3(u)?,
            d: vec3(u)?,
        },
        5 => Mesh::City {
            triangles: match u.int_in_range(0..=5u8)? {
                0 => u32::MAX,
                1 => MAX_SCENE_TRIANGLES as u32 + 1,
                _ => u.int_in_range(0..=6000)?,
            },
            seed: u.arbitrary()?,
        },
        _ => Mesh::Obj {
            path: u.choose(OBJ_PATHS)?.to_string(),
        },
    })
}

fn object(u: &mut Unstructured) -> Result<Object> {
    let rotate = match u.int_in_range(0..=2u8)? {
        0 => Rotation::None,
        1 => Rotation::Euler(float(u)?, float(u)?, float(u)?),
        _ => Rotation::AxisAngle {
            axis: vec3(u)?,
            degrees: float(u)?,
        },
    };
    Ok(Object {
        name: if u.arbitrary()? { Some("o".into()) } else { None },
        mesh: mesh(u)?,
        transform: Transform {
            translate: if u.arbitrary()? { Vec3::ZERO } else { vec3(u)? },
            rotate,
            scale: if u.arbitrary()? { Vec3::ONE } else { vec3(u)? },
        },
        flat_normals: u.arbitrary()?,
        casts: u.arbitrary()?,
        receives: u.arbitrary()?,
    })
}

fn scene(u: &mut Unstructured) -> Result<SceneDesc> {
    Ok(SceneDesc {
        camera: camera(u)?,
        shadow_map: size(u)?,
        lights: (0..u.int_in_range(0..=MAX_LIGHTS + 1)?).map(|_| light(u)).collect::<Result<_>>()?,
        objects: (0..u.int_in_range(0..=6)?).map(|_| object(u)).collect::<Result<_>>()?,
        shadow_fit: if u.arbitrary()? { ShadowFit::Casters } else { ShadowFit::Scene },
        cascades: if u.ratio(1u8, 4)? {
            Some(Cascades {
                count: u.int_in_range(0..=5)?,
                lambda: float(u)?,
                band: float(u)?,
            })
        } else {
            None
        },
    })
}

/// Scenes whose built-in meshes make more triangles than this (and no more than the
/// limit, over which the loader refuses them before building anything) are skipped:
/// building a million triangles takes 0.1-0.2 s in the instrumented build, and a corpus
/// that keeps a few such inputs runs at a tenth of the rate (228 exec/s against 1,658 in
/// the first campaign run, nearly all of it in meshing and hashing).
const MAX_FUZZ_TRIANGLES: usize = 1 << 16;

/// The triangles of a scene's built-in meshes (OBJ files here are a few triangles each),
/// as `Scene::build` counts them before building.
fn planned_triangles(text: &str) -> usize {
    let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let Ok(desc) = options.from_str::<SceneDesc>(text) else { return 0 };
    desc.objects
        .iter()
        .map(|o| match o.mesh {
            Mesh::Plane { .. } | Mesh::Quad { .. } => 2,
            Mesh::Box { .. } => 12,
            Mesh::Triangle { .. } => 1,
            // Refused before building (above MAX_SPHERE_SEGMENTS): kept.
            Mesh::Sphere { segments, .. } if segments > MAX_SPHERE_SEGMENTS => 0,
            Mesh::Sphere { segments, .. } => (segments as usize).saturating_mul((segments as usize / 2).max(2)).saturating_mul(2),
            // generated as glTF; refused before building above the limit
            Mesh::City { triangles, .. } if triangles as usize > MAX_SCENE_TRIANGLES => 0,
            Mesh::City { triangles, .. } => triangles as usize,
            Mesh::Obj { .. } | Mesh::Gltf { .. } => 0,
        })
        .fold(0usize, usize::saturating_add)
}

/// `SSHC_FUZZ_ALL_SIZES=1` turns the skip off (to replay an input at the limit, and see
/// its time and memory).
fn skip_large() -> bool {
    static SKIP: OnceLock<bool> = OnceLock::new();
    *SKIP.get_or_init(|| std::env::var_os("SSHC_FUZZ_ALL_SIZES").is_none())
}

fn drive(text: &str) {
    if skip_large() && (MAX_FUZZ_TRIANGLES + 1..=MAX_SCENE_TRIANGLES).contains(&planned_triangles(text)) {
        return;
    }
    let scene = match Scene::from_str(text, base()) {
        Ok(s) => s,
        Err(e) => {
            let _ = e.to_string();
            return;
        }
    };
    let (tris, normals) = (scene.triangles(), scene.normals());
    assert!(tris.len() <= MAX_SCENE_TRIANGLES);
    assert_eq!(tris.len(), normals.len());
    assert!(
        tris.iter().flatten().all(|v| v.is_finite()),
        "accepted a non-finite triangle: {text}"
    );
    assert!(
        normals.iter().flatten().all(|v| v.is_finite()),
        "accepted a non-finite normal: {text}"
    );
    let (lo, hi) = scene.bounds();
    assert!(lo.is_finite() && hi.is_finite(), "non-finite bounds: {text}");
    for i in 0..scene.objects().len() {
        assert!(scene.object_triangles(i).end <= tris.len());
    }
    // What the executor and the ground truth compute from a scene next: no panic.
    let _ = scene.camera_view_proj();
    let _ = scene.fingerprint();
    assert!(scene.lights.len() <= MAX_LIGHTS, "{} lights accepted: {text}", scene.lights.len());
    for l in &scene.lights {
        let _ = l.view(scene.bounds());
        let _ = scene.light_view(l);
        let _ = scene.fit_report(l);
        let _ = scene.penumbra_reach(l);
        let _ = l.segment_samples(4);
        // the light-sample chains of per-sample techniques (segment, triangle, rectangle)
        for n in [1, 3, 4, 12, 17] {
            if let Ok((points, _)) = l.sample_chain(n, 16) {
                assert_eq!(points.len(), n as usize, "{n} samples asked: {text}");
            }
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        if let Ok(desc) = scene(&mut u) {
            let config = ron::ser::PrettyConfig::new().struct_names(u.arbitrary().unwrap_or(false));
            let Ok(text) = ron::ser::to_string_pretty(&desc, config) else {
                return;
            };
            let text = mutate::mutate(&mut u, text, WORDS);
            drive(&text);
        }
    } else if let Ok(text) = std::str::from_utf8(data) {
        drive(text);
    }
});
