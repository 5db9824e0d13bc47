//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), through the `gltf` crate without
//! its image decoding: the scene crate keeps `image` out (scripts/test.sh checks the
//! dependency boundaries).
//!
//! What is read:
//! - every triangle primitive of every mesh that a node of the default scene (else the
//!   first scene, else every root node) places, with the node hierarchy's transforms
//!   (`world = parent * local`, glTF 2.0 section 3.5.2); a mesh placed by several nodes is
//!   decoded once;
//! - the first camera met in that traversal;
//! - the lights of `KHR_lights_punctual`: a directional light becomes a `DistantDisk`
//!   whose angular diameter is the light's `extras.angle_degrees` (default 0.5), a point
//!   light a `Sphere` of radius `extras.radius` (default 1 % of the scene's diagonal), a
//!   spot light a `Disk` of radius `extras.radius` facing along the spot (its cone angles
//!   are ignored, and a note says so).
//!
//! Materials, textures, skins and morph targets are ignored (a note says so once per file);
//! points and lines are skipped (a note counts them). Positions must be `VEC3` floats and
//! indices unsigned integers, as glTF 2.0 requires without extensions; an extension marked
//! required that changes geometry (mesh quantisation, Draco, meshopt) is refused, as are
//! sparse accessors. Every read is bounds-checked here (an accessor out of its buffer view,
//! a view out of its buffer, an index past the vertices, a NaN position): the errors name
//! the file and the node, mesh, primitive or accessor.
//!
//! Buffers are the GLB's binary chunk, `data:` URIs (base64), or files beside the glTF file
//! and inside the scene's folder (the OBJ rule: no absolute path, no `..`, no link out),
//! each at most [`MAX_OBJ_BYTES`](crate::validate::MAX_OBJ_BYTES) and all together at
//! most [`MAX_GLTF_BYTES`].
//!
//! The files: this one reads the document and walks its nodes; `buffers.rs` reads the
//! buffers and the accessors in them, `mesh.rs` decodes and places the meshes,
//! `lights.rs` and `camera.rs` map the lights and the camera (`tests.rs`: the unit tests).

use crate::error::{SceneError, SceneErrorKind};
use crate::schema::Camera;
use crate::source::{Instancing, MeshData, read_mesh_file};
use crate::validate::MAX_SCENE_TRIANGLES;
use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec3};
use gltf::mesh::Mode;
use sshc_light::{Light, MAX_LIGHTS};

mod buffers;
mod camera;
mod lights;
mod mesh;
#[cfg(test)]
mod tests;

use buffers::read_buffers;
pub use camera::CAMERA_HEIGHT;
pub(crate) use camera::framing_camera;
use camera::map_camera;
pub(crate) use lights::default_sun;
use lights::map_light;
use mesh::{Primitive, decode_mesh, place_node, shared_mesh};

/// Most bytes a glTF scene reads, its file and every buffer together (1 GiB).
pub const MAX_GLTF_BYTES: u64 = 1 << 30;

/// A light's angular diameter when its `extras` give none, in degrees (about the sun's).
pub const DEFAULT_SUN_DEGREES: f32 = 0.5;

/// A point or spot light's radius when its `extras` give none, as a fraction of the
/// scene's diagonal.
pub const DEFAULT_RADIUS_FRACTION: f32 = 0.01;

/// Extensions that may be marked required: those whose data is ignored here (materials,
/// texture transforms) or read (lights). Any other (mesh quantisation, Draco, meshopt)
/// changes how geometry is stored, and is refused.
const IGNORABLE_REQUIRED: [&str; 2] = ["KHR_materials_", "KHR_texture_"];

/// What a glTF file gives a scene.
pub(crate) struct Imported {
    /// Its triangles in the file's world space (the nodes' transforms applied).
    pub(crate) mesh: MeshData,
    /// Its first camera, at the size its aspect ratio gives (512 pixels high).
    pub(crate) camera: Option<Camera>,
    /// Its lights, in node order.
    pub(crate) lights: Vec<Light>,
    /// What was ignored or assumed, each said once.
    pub(crate) notes: Vec<String>,
    /// The files read: the glTF file and its external buffers.
    pub(crate) files: Vec<PathBuf>,
    /// How many nodes place a mesh, and how many distinct meshes they place.
    pub(crate) placements: (usize, usize),
}

/// Reads `rel` (inside `base`) as glTF.
pub(crate) fn load(rel: &str, base: &Path) -> Result<Imported, SceneError> {
    let (path, bytes) = read_mesh_file(rel, base, "glTF")?;
    let folder = path.parent().map(Path::to_path_buf).unwrap_or_else(|| base.to_path_buf());
    let mut imported = import(&bytes, rel, Some((base, &folder)))?;
    imported.files.insert(0, path);
    Ok(imported)
}

fn fail(file: &str, message: impl std::fmt::Display, hint: &str) -> SceneError {
    SceneError::new(SceneErrorKind::Mesh, format!("glTF `{file}`: {message}")).with_hint(hint)
}

/// Imports glTF `bytes` (JSON or GLB) named `file` in messages. External buffers resolve
/// against `folders = (scene folder, file's folder)`, inside the scene folder; without
/// folders only the GLB chunk and data URIs can be read.
pub(crate) fn import(bytes: &[u8], file: &str, folders: Option<(&Path, &Path)>) -> Result<Imported, SceneError> {
    // the GLB header's length is checked here: the crate subtracts 12 from it unchecked
    if bytes.starts_with(b"glTF") {
        let declared = bytes.get(8..12).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_none_or(|n| n < 12) {
            return Err(fail(
                file,
                "the GLB header is cut short or declares fewer than 12 bytes",
                "write a whole GLB file",
            ));
        }
    }
    let unreadable = |e: &dyn std::fmt::Display| {
        fail(
            file,
            format_args!("cannot read it: {e}"),
            "check that it is glTF 2.0 (JSON or GLB) and that it passes the Khronos glTF validator",
        )
    };
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| unreadable(&e))?;
        (glb.json.into_owned(), glb.bin.map(std::borrow::Cow::into_owned))
    } else {
        (bytes.to_vec(), None)
    };
    let root = gltf::json::Root::from_slice(&json).map_err(|e| unreadable(&e))?;
    // gltf-json 1.4's validation indexes the accessors by POSITION's index before checking
    // it (and panics past the end): checked here first
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some((_, a)) = prim.attributes.iter().find(|(_, a)| a.value() >= root.accessors.len()) {
                return Err(fail(
                    file,
                    format_args!(
                        "mesh {m} primitive {p} names accessor {}, past its {} accessors",
                        a.value(),
                        root.accessors.len()
                    ),
                    "name accessors that exist",
                ));
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| unreadable(&e))?;
    let doc = gltf::Gltf { document, blob };
    for ext in doc.extensions_required() {
        if ext != "KHR_lights_punctual" && !IGNORABLE_REQUIRED.iter().any(|p| ext.starts_with(p)) {
            return Err(fail(
                file,
                format_args!("it requires the extension `{ext}`, which sshc does not read"),
                "export without compression or quantisation (plain float positions and integer indices)",
            ));
        }
    }
    let mut notes = Vec::new();
    let mut files = Vec::new();
    let buffers = read_buffers(&doc, file, folders, bytes.len() as u64, &mut files)?;
    let (placed, cameras, lit) = traverse(&doc, file)?;

    // every triangle counted before any is decoded
    let mut planned = 0usize;
    for (mesh, _, _) in &placed {
        for prim in mesh.primitives() {
            let n = match (prim.mode(), prim.indices()) {
                (Mode::Triangles, Some(a)) => a.count() / 3,
                (Mode::Triangles, None) => prim.get(&gltf::Semantic::Positions).map_or(0, |a| a.count() / 3),
                (Mode::TriangleStrip | Mode::TriangleFan, a) => a
                    .or_else(|| prim.get(&gltf::Semantic::Positions))
                    .map_or(0, |a| a.count().saturating_sub(2)),
                (Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip, _) => 0,
            };
            planned = planned.saturating_add(n);
        }
        if planned > MAX_SCENE_TRIANGLES {
            return Err(fail(
                file,
                format_args!("its nodes place {planned} triangles or more, above the limit of {MAX_SCENE_TRIANGLES}"),
                "use a coarser scene, or fewer instances",
            ));
        }
    }
    // the memory the placed triangles will take, before any is decoded
    crate::memory::check(planned).map_err(|why| fail(file, why, "use a coarser scene, or a machine with more memory"))?;

    let mut decoded: Vec<Option<Vec<Primitive>>> = vec![None; doc.meshes().len()];
    let mut skipped = 0usize;
    let mut triangles = Vec::with_capacity(planned);
    let mut normals = Vec::with_capacity(planned);
    let meshes_used = placed.iter().map(|p| p.0.index()).collect::<std::collections::BTreeSet<_>>().len();
    // Nodes that share a mesh are kept as instances of it too (read once, placed by each
    // node's matrix), unless a matrix mirrors: the placed triangles then turn their winding,
    // which an instance's indices do not.
    let share = placed.len() > meshes_used && placed.iter().all(|(_, world, _)| Mat3::from_mat4(*world).determinant() > 0.0);
    let mut instancing = Instancing::default();
    let mut shared: Vec<Option<usize>> = vec![None; doc.meshes().len()];
    for (mesh, world, node) in &placed {
        let slot = &mut decoded[mesh.index()];
        if slot.is_none() {
            let (prims, skip) = decode_mesh(mesh, &buffers, file)?;
            skipped += skip;
            *slot = Some(prims);
        }
        let Some(prims) = slot.as_ref() else { continue };
        let before = triangles.len();
        place_node(prims, world, &mut triangles, &mut normals);
        // a finite matrix can still carry a finite position past f32 (a scale of 1e30 on a
        // corner at 1e10)
        if let Some(t) = triangles[before..].iter().position(|t| !t.iter().all(|p| p.is_finite())) {
            return Err(fail(
                file,
                format_args!(
                    "{} places triangle {t} of mesh {} outside f32's range (a corner at {:?})",
                    node_label(&doc, *node),
                    mesh.index(),
                    triangles[before + t]
                ),
                "scale the node or the mesh down",
            ));
        }
        if share {
            let k = *shared[mesh.index()].get_or_insert_with(|| {
                instancing.meshes.push(shared_mesh(mesh, prims));
                instancing.meshes.len() - 1
            });
            instancing.instances.push((k, world.to_cols_array()));
        }
    }
    // the scene's extent must stay a finite f32 distance: a corner at 3e38 overflowed
    // where the camera and the light are placed from the bounds, and was blamed on them
    let (lo, hi) = triangles
        .iter()
        .flatten()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let spans = (hi - lo).length_squared().is_finite() && lo.is_finite() && hi.is_finite();
    if !triangles.is_empty() && !spans {
        return Err(fail(
            file,
            format_args!("the placed triangles span from {lo} to {hi}: distances across them overflow f32"),
            "scale the scene down: keep coordinates well within 1e18",
        ));
    }
    let mesh = MeshData {
        triangles,
        normals: Some(normals),
        instancing: share.then_some(instancing),
    };

    let (lo, hi) = sshc_light::bounds_of(mesh.triangles.iter().flatten().copied());
    let diagonal = if lo.is_finite() && hi.is_finite() {
        (hi - lo).length()
    } else {
        0.0
    };
    let mut lights = Vec::new();
    let mut spots = 0usize;
    for (light, world, node) in &lit {
        lights.push(map_light(light, world, *node, diagonal, file, &mut spots)?);
    }
    if lights.len() > MAX_LIGHTS {
        return Err(fail(
            file,
            format_args!(
                "its nodes place {} lights, above the runtime's limit of {MAX_LIGHTS} a frame",
                lights.len()
            ),
            "remove lights, or split the scene",
        ));
    }
    if spots > 0 {
        notes.push(format!(
            "{spots} spot light(s) became disks facing along the spot: their cone angles are ignored"
        ));
    }
    if skipped > 0 {
        notes.push(format!(
            "{skipped} primitive(s) of points or lines were skipped: only triangles are read"
        ));
    }
    let (materials, textures) = (doc.materials().len(), doc.textures().len());
    if materials + textures > 0 {
        notes.push(format!(
            "its {materials} material(s) and {textures} texture(s) are ignored: sshc shades every surface alike"
        ));
    }
    let camera = match cameras {
        Some((camera, world, node)) => Some(map_camera(&camera, &world, node, file)?),
        None => None,
    };
    files.shrink_to_fit();
    Ok(Imported {
        mesh,
        camera,
        lights,
        notes,
        files,
        placements: (placed.len(), meshes_used),
    })
}

type Placed<'a, T> = Vec<(T, Mat4, usize)>;

/// The nodes of the scene, depth first from its roots: the meshes they place and the
/// lights, with their world matrices, and the first camera.
#[allow(clippy::type_complexity)]
fn traverse<'a>(
    doc: &'a gltf::Gltf,
    file: &str,
) -> Result<
    (
        Placed<'a, gltf::Mesh<'a>>,
        Option<(gltf::Camera<'a>, Mat4, usize)>,
        Placed<'a, gltf::khr_lights_punctual::Light<'a>>,
    ),
    SceneError,
> {
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !child[n.index()]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    let (mut meshes, mut lights, mut camera) = (Vec::new(), Vec::new(), None);
    while let Some((node, parent)) = stack.pop() {
        let i = node.index();
        let name = node_name(&node);
        if std::mem::replace(&mut seen[i], true) {
            return Err(fail(
                file,
                format_args!("{name} is reached twice: glTF nodes form a tree (one parent each, no cycle)"),
                "give each node one parent, and place a shared mesh from several nodes instead",
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !local.is_finite() {
            return Err(fail(
                file,
                format_args!("{name} has a transform that is not finite"),
                "write finite numbers",
            ));
        }
        let world = if parent == Mat4::IDENTITY { local } else { parent * local };
        if !world.is_finite() {
            // each factor finite, their product not: two nested scales of 1e20 (issue 48,
            // item 7, placed NaN and infinite triangles and drew an empty, all-lit image)
            return Err(fail(
                file,
                format_args!("{name}'s world transform (its parents' times its own) overflows f32"),
                "scale the nodes so that their product stays within about 1e38",
            ));
        }
        if let Some(mesh) = node.mesh() {
            meshes.push((mesh, world, i));
        }
        if let Some(light) = node.light() {
            lights.push((light, world, i));
        }
        if camera.is_none()
            && let Some(c) = node.camera()
        {
            camera = Some((c, world, i));
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok((meshes, camera, lights))
}

/// [`node_name`] of node `i` of `doc`.
fn node_label(doc: &gltf::Document, i: usize) -> String {
    doc.nodes().nth(i).map_or_else(|| format!("node {i}"), |n| node_name(&n))
}

fn node_name(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("node {} (\"{n}\")", node.index()),
        None => format!("node {}", node.index()),
    }
}
