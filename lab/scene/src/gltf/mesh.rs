//! A glTF mesh's triangle primitives decoded, and placed by the nodes that place the mesh
//! (as triangles, or kept as instances of one shared mesh).

use super::buffers::{read_indices, read_vec3};
use super::fail;
use crate::error::SceneError;
use crate::source::{SharedMesh, smooth_normals};

use glam::{Mat3, Mat4, Vec3};
use gltf::mesh::Mode;

/// One primitive, as a triangle list.
#[derive(Clone)]
pub(super) struct Primitive {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

/// The primitives of `mesh` as triangle lists, and how many were points or lines.
pub(super) fn decode_mesh(mesh: &gltf::Mesh, buffers: &[Vec<u8>], file: &str) -> Result<(Vec<Primitive>, usize), SceneError> {
    let mut out = Vec::new();
    let mut skipped = 0;
    for prim in mesh.primitives() {
        let at = match mesh.name() {
            Some(n) => format!("mesh {} (\"{n}\") primitive {}", mesh.index(), prim.index()),
            None => format!("mesh {} primitive {}", mesh.index(), prim.index()),
        };
        let mode = prim.mode();
        if matches!(mode, Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
            skipped += 1;
            continue;
        }
        let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
            return Err(fail(
                file,
                format_args!("{at} has no POSITION"),
                "give every triangle primitive its positions",
            ));
        };
        let positions = read_vec3(&pos, buffers, file, &format!("{at} POSITION"))?;
        if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
            return Err(fail(
                file,
                format_args!("{at} POSITION (accessor {}): vertex {k} is NaN or infinite", pos.index()),
                "write finite positions",
            ));
        }
        let normals = match prim.get(&gltf::Semantic::Normals) {
            Some(a) => {
                let n = read_vec3(&a, buffers, file, &format!("{at} NORMAL"))?;
                if n.len() != positions.len() {
                    return Err(fail(
                        file,
                        format_args!(
                            "{at} has {} normals for {} positions (accessor {})",
                            n.len(),
                            positions.len(),
                            a.index()
                        ),
                        "give one normal per position",
                    ));
                }
                Some(n)
            }
            None => None,
        };
        let listed: Vec<u32> = match prim.indices() {
            Some(a) => read_indices(&a, buffers, file, &format!("{at} indices"))?,
            None => (0..u32::try_from(positions.len()).unwrap_or(u32::MAX)).collect(),
        };
        if let Some((k, &i)) = listed.iter().enumerate().find(|(_, i)| **i as usize >= positions.len()) {
            return Err(fail(
                file,
                format_args!("{at}: index {k} is {i}, past its {} vertices", positions.len()),
                "write indices below the POSITION accessor's count",
            ));
        }
        let indices = triangle_list(mode, &listed);
        let normals = normals.unwrap_or_else(|| smooth_normals(&positions, &indices));
        out.push(Primitive {
            positions,
            normals,
            indices,
        });
    }
    Ok((out, skipped))
}

/// The triangles of `mode` over `listed` indices, as a list (strips alternate their
/// winding back to the first triangle's, glTF 2.0 section 3.7.2.1).
pub(super) fn triangle_list(mode: Mode, listed: &[u32]) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => (2..listed.len())
            .flat_map(|k| {
                let (a, b, c) = (listed[k - 2], listed[k - 1], listed[k]);
                if k % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (2..listed.len()).flat_map(|k| [listed[k - 1], listed[k], listed[0]]).collect(),
        Mode::Triangles | Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
            listed[..listed.len() - listed.len() % 3].to_vec()
        }
    }
}

/// A glTF mesh's primitives as one indexed mesh, in the order [`place_node`] lists them.
pub(super) fn shared_mesh(mesh: &gltf::Mesh, prims: &[Primitive]) -> SharedMesh {
    let mut out = SharedMesh {
        name: mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string),
        ..Default::default()
    };
    for p in prims {
        let base = out.positions.len() as u32;
        out.positions.extend(p.positions.iter().map(|v| v.to_array()));
        out.normals.extend(p.normals.iter().map(|v| v.to_array()));
        out.indices.extend(p.indices.iter().map(|i| i + base));
    }
    out
}

/// Appends a node's triangles, placed by its world matrix. The identity places nothing
/// (no rounding: a glTF and an OBJ of the same geometry give the same triangles, bit for
/// bit); a mirroring matrix reverses the winding so triangles keep facing out.
pub(super) fn place_node(prims: &[Primitive], world: &Mat4, triangles: &mut Vec<[Vec3; 3]>, normals: &mut Vec<[Vec3; 3]>) {
    let identity = world.to_cols_array().map(f32::to_bits) == Mat4::IDENTITY.to_cols_array().map(f32::to_bits);
    let m3 = Mat3::from_mat4(*world);
    let normal_matrix = m3.inverse().transpose();
    let mirrored = m3.determinant() < 0.0;
    for p in prims {
        for t in p.indices.chunks_exact(3) {
            let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
            let (mut tri, mut nrm) = (
                [p.positions[a], p.positions[b], p.positions[c]],
                [p.normals[a], p.normals[b], p.normals[c]],
            );
            if !identity {
                tri = tri.map(|q| world.transform_point3(q));
                nrm = nrm.map(|n| normal_matrix * n);
            }
            if mirrored {
                tri.swap(1, 2);
                nrm.swap(1, 2);
            }
            triangles.push(tri);
            normals.push(nrm);
        }
    }
}
