//! Meshes: the built-in shapes, OBJ files (inside the scene's folder, capped in size), and
//! their placement in the world.

use crate::error::{SceneError, SceneErrorKind};
use crate::schema::{Mesh, Object};
use crate::source::{MeshData, read_mesh_file, smooth_normals};
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};

/// What reading the meshes noted (said once per file) and the files they read.
#[derive(Default)]
pub(crate) struct Reads {
    pub(crate) notes: Vec<String>,
    pub(crate) files: Vec<PathBuf>,
}

pub(crate) fn build_mesh(index: usize, object: &Object, base: &Path, reads: &mut Reads) -> Result<MeshData, SceneError> {
    let flat = |triangles| MeshData {
        triangles,
        normals: None,
        instancing: None,
    };
    Ok(match &object.mesh {
        Mesh::Plane { size } => {
            let (x, z) = (0.5 * size.x, 0.5 * size.y);
            let (a, b, c, d) = (
                Vec3::new(-x, 0.0, -z),
                Vec3::new(-x, 0.0, z),
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 0.0, -z),
            );
            flat(vec![[a, b, c], [a, c, d]])
        }
        Mesh::Box { size } => flat(box_triangles(*size * 0.5)),
        Mesh::Sphere { radius, segments } => sphere(*radius, *segments),
        Mesh::Triangle { a, b, c } => flat(vec![[*a, *b, *c]]),
        Mesh::Quad { a, b, c, d } => flat(vec![[*a, *b, *c], [*a, *c, *d]]),
        Mesh::Obj { path } => {
            let at = match &object.name {
                Some(n) => format!("objects[{index}] (\"{n}\").mesh.path"),
                None => format!("objects[{index}].mesh.path"),
            };
            let (mesh, file) = load_obj(path, base).map_err(|e| e.with_at(at))?;
            reads.files.push(file);
            mesh
        }
        Mesh::Gltf { path } => {
            let at = match &object.name {
                Some(n) => format!("objects[{index}] (\"{n}\").mesh.path"),
                None => format!("objects[{index}].mesh.path"),
            };
            let imported = crate::gltf::load(path, base).map_err(|e| e.with_at(at))?;
            reads.notes.extend(imported.notes.into_iter().map(|n| format!("{path}: {n}")));
            if imported.camera.is_some() || !imported.lights.is_empty() {
                reads.notes.push(format!(
                    "{path}: its camera and lights are ignored where a scene file includes it (load the glTF file as the scene to use them)"
                ));
            }
            reads.files.extend(imported.files);
            imported.mesh
        }
        Mesh::City { triangles, seed } => {
            let bytes = crate::generate::city_glb(*triangles as usize, *seed);
            crate::gltf::import(&bytes, &format!("city (seed {seed})"), None)?.mesh
        }
    })
}

/// Triangles an analytic mesh makes (`None` for OBJ files, counted once read).
pub(crate) fn analytic_triangles(mesh: &Mesh) -> Option<usize> {
    match mesh {
        Mesh::Plane { .. } | Mesh::Quad { .. } => Some(2),
        Mesh::Box { .. } => Some(12),
        Mesh::Triangle { .. } => Some(1),
        Mesh::Sphere { segments, .. } => {
            let s = *segments as usize;
            Some(s.saturating_mul((s / 2).max(2)).saturating_mul(2))
        }
        Mesh::City { triangles, .. } => Some(*triangles as usize),
        Mesh::Obj { .. } | Mesh::Gltf { .. } => None,
    }
}

fn box_triangles(h: Vec3) -> Vec<[Vec3; 3]> {
    let mut out = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // u x v = n, so (c-u-v, c+u-v, c+u+v, c-u+v) runs counter-clockwise around n.
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let c = n * h;
            let (u, v) = (u * h, v * h);
            let q = [c - u - v, c + u - v, c + u + v, c - u + v];
            out.push([q[0], q[1], q[2]]);
            out.push([q[0], q[2], q[3]]);
        }
    }
    out
}

pub(crate) fn sphere(radius: f32, segments: u32) -> MeshData {
    let rings = (segments / 2).max(2);
    // The poles are exact points (f32's sin(pi) is not 0), so that their triangles share
    // one vertex and the mesh is closed: edge adjacency (silhouettes) welds by position.
    let point = |ring: u32, seg: u32| {
        if ring == 0 || ring == rings {
            return Vec3::new(0.0, if ring == 0 { 1.0 } else { -1.0 }, 0.0);
        }
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (seg % segments) as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
    };
    let mut triangles = Vec::new();
    let mut normals = Vec::new();
    for ring in 0..rings {
        for seg in 0..segments {
            let p00 = point(ring, seg);
            let p01 = point(ring, seg + 1);
            let p10 = point(ring + 1, seg);
            let p11 = point(ring + 1, seg + 1);
            for tri in [[p00, p10, p11], [p00, p11, p01]] {
                // Face outwards: flip where the winding points in.
                let centroid = tri[0] + tri[1] + tri[2];
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                let tri = if n.dot(centroid) < 0.0 { [tri[0], tri[2], tri[1]] } else { tri };
                normals.push(tri);
                triangles.push(tri.map(|p| p * radius));
            }
        }
    }
    MeshData {
        triangles,
        normals: Some(normals),
        instancing: None,
    }
}

fn load_obj(rel: &str, base: &Path) -> Result<(MeshData, PathBuf), SceneError> {
    let (path, bytes) = read_mesh_file(rel, base, "OBJ")?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    // Material libraries are never opened: they could name files outside the folder.
    let (models, _materials) =
        tobj::load_obj_buf(&mut bytes.as_slice(), &options, |_| Err(tobj::LoadError::OpenFileFailed)).map_err(|e| {
            SceneError::new(SceneErrorKind::Mesh, format!("cannot parse the OBJ file `{rel}`: {e}"))
                .with_hint("check that the file is a Wavefront OBJ with `v` and `f` lines")
        })?;
    let mut triangles = Vec::new();
    let mut normals = Vec::new();
    let mut all_have_normals = true;
    let mut computed = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let vertex = |i: u32| {
            let i = i as usize * 3;
            m.positions.get(i..i + 3).map(|s| Vec3::new(s[0], s[1], s[2]))
        };
        let has_normals = m.normals.len() == m.positions.len() && !m.normals.is_empty();
        all_have_normals &= has_normals;
        let mut tris = Vec::with_capacity(m.indices.len() / 3);
        for f in m.indices.chunks_exact(3) {
            let (Some(a), Some(b), Some(c)) = (vertex(f[0]), vertex(f[1]), vertex(f[2])) else {
                return Err(
                    SceneError::new(SceneErrorKind::Mesh, format!("the OBJ file `{rel}` has a face index out of range"))
                        .with_hint("check the face indices of the OBJ file"),
                );
            };
            tris.push([a, b, c]);
            if has_normals {
                let nr = |i: u32| {
                    let i = i as usize * 3;
                    Vec3::new(m.normals[i], m.normals[i + 1], m.normals[i + 2])
                };
                normals.push([nr(f[0]), nr(f[1]), nr(f[2])]);
            }
        }
        // area-weighted smooth normals by vertex index, for meshes without normals
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|s| Vec3::new(s[0], s[1], s[2])).collect();
        let smooth = smooth_normals(&positions, &m.indices);
        computed.extend(
            m.indices
                .chunks_exact(3)
                .map(|f| [smooth[f[0] as usize], smooth[f[1] as usize], smooth[f[2] as usize]]),
        );
        triangles.extend(tris);
    }
    let normals = if all_have_normals { normals } else { computed };
    Ok((
        MeshData {
            triangles,
            normals: Some(normals),
            instancing: None,
        },
        path,
    ))
}

/// Transforms a mesh to world space, drops degenerate triangles, and appends it.
pub(crate) fn place(mesh: &MeshData, object: &Object, triangles: &mut Vec<[Vec3; 3]>, normals: &mut Vec<[Vec3; 3]>) {
    let m = object.transform.matrix();
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    let mirrored = Mat3::from_mat4(m).determinant() < 0.0;
    for (i, tri) in mesh.triangles.iter().enumerate() {
        let mut w = tri.map(|p| m.transform_point3(p));
        let e1 = w[1] - w[0];
        let e2 = w[2] - w[0];
        let e3 = w[2] - w[1];
        let cross = e1.cross(e2);
        let longest = e1.length_squared().max(e2.length_squared()).max(e3.length_squared());
        // Zero area up to f32 rounding of the cross product (about 1.2e-7 * |e1| |e2|).
        if !(w.iter().all(|p| p.is_finite()) && cross.is_finite() && cross.length() > 1e-6 * longest) {
            continue;
        }
        let face = cross.normalize();
        let mut n = match (&mesh.normals, object.flat_normals) {
            (Some(ns), false) => ns[i].map(|n| {
                let n = normal_matrix * n;
                if n.is_finite() && n.length_squared() > 0.0 {
                    n.normalize()
                } else {
                    face
                }
            }),
            _ => [face; 3],
        };
        if mirrored {
            w.swap(1, 2);
            n.swap(1, 2);
        }
        if mesh.normals.is_none() || object.flat_normals {
            // Recompute after a possible swap so the face normal matches the winding.
            let f = (w[1] - w[0]).cross(w[2] - w[0]).normalize();
            n = [f; 3];
        }
        triangles.push(w);
        normals.push(n);
    }
}
