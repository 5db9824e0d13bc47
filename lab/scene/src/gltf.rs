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
//! each at most [`MAX_OBJ_BYTES`] and all together at most [`MAX_GLTF_BYTES`].

use crate::error::{SceneError, SceneErrorKind};
use crate::schema::Camera;
use crate::source::{Instancing, MeshData, SharedMesh, read_capped, read_mesh_file, resolve_inside, smooth_normals};
use crate::validate::{MAX_OBJ_BYTES, MAX_SCENE_TRIANGLES};
use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::khr_lights_punctual::Kind;
use gltf::mesh::Mode;
use sshc_light::{Light, MAX_LIGHTS};

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

/// Every buffer's bytes, cut to its declared length.
fn read_buffers(
    doc: &gltf::Gltf,
    file: &str,
    folders: Option<(&Path, &Path)>,
    mut total: u64,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let what = match buffer.name() {
            Some(n) => format!("buffer {i} (\"{n}\")"),
            None => format!("buffer {i}"),
        };
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                fail(
                    file,
                    format_args!("{what} is the GLB binary chunk, which the file does not have"),
                    "write a GLB file with its BIN chunk",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, file, &what, folders, files)?,
        };
        total = total.saturating_add(data.len() as u64);
        if total > MAX_GLTF_BYTES {
            return Err(fail(
                file,
                format_args!("its buffers reach {total} bytes with {what}, above the limit of {MAX_GLTF_BYTES}"),
                "use a smaller scene",
            ));
        }
        if data.len() < buffer.length() {
            return Err(fail(
                file,
                format_args!("{what} declares {} bytes but holds {}", buffer.length(), data.len()),
                "write the buffer's true byteLength",
            ));
        }
        data.truncate(buffer.length());
        out.push(data);
    }
    Ok(out)
}

fn read_uri(uri: &str, file: &str, what: &str, folders: Option<(&Path, &Path)>, files: &mut Vec<PathBuf>) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        use base64::Engine;
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(fail(
                file,
                format_args!("{what} is a data URI that is not base64"),
                "write `data:application/octet-stream;base64,...`",
            ));
        };
        return base64::engine::general_purpose::STANDARD.decode(payload).map_err(|e| {
            fail(
                file,
                format_args!("{what}'s data URI is not valid base64: {e}"),
                "write the buffer as standard base64",
            )
        });
    }
    if uri.contains("://") {
        return Err(fail(
            file,
            format_args!("{what} is at `{uri}`: sshc reads no network address"),
            "put the buffer beside the glTF file, or write a GLB",
        ));
    }
    let Some((scene_folder, gltf_folder)) = folders else {
        return Err(fail(
            file,
            format_args!("{what} is the file `{uri}`, and this glTF has no folder to read it from"),
            "write a GLB, or embed the buffer as a data URI",
        ));
    };
    let decoded = percent_encoding::percent_decode_str(uri).decode_utf8().map_err(|_| {
        fail(
            file,
            format_args!("{what}'s URI `{uri}` is not UTF-8 once decoded"),
            "name the buffer file in UTF-8",
        )
    })?;
    // relative to the glTF's folder, which lies inside the scene folder
    let rel_to_scene = gltf_folder
        .strip_prefix(scene_folder)
        .map(|f| f.join(decoded.as_ref()))
        .unwrap_or_else(|_| PathBuf::from(decoded.as_ref()));
    let rel = rel_to_scene.to_string_lossy().into_owned();
    let path =
        resolve_inside(&rel, scene_folder).map_err(|e| fail(file, format_args!("{what}: {}", e.message()), e.hint().unwrap_or("")))?;
    let data = read_capped(&path, MAX_OBJ_BYTES).map_err(|e| {
        fail(
            file,
            format_args!("cannot read {what} `{}`: {e}", path.display()),
            "check that the buffer file is beside the glTF file",
        )
    })?;
    files.push(path);
    Ok(data)
}

/// One primitive, as a triangle list.
#[derive(Clone)]
struct Primitive {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

/// The primitives of `mesh` as triangle lists, and how many were points or lines.
fn decode_mesh(mesh: &gltf::Mesh, buffers: &[Vec<u8>], file: &str) -> Result<(Vec<Primitive>, usize), SceneError> {
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
fn triangle_list(mode: Mode, listed: &[u32]) -> Vec<u32> {
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

/// The bytes of an accessor's `count` elements of `size` bytes: (data, stride, count).
fn accessor_bytes<'b>(a: &gltf::Accessor, buffers: &'b [Vec<u8>], file: &str, what: &str) -> Result<(&'b [u8], usize, usize), SceneError> {
    let bad = |m: String| {
        fail(
            file,
            format_args!("{what} (accessor {}): {m}", a.index()),
            "check the accessor against its buffer view",
        )
    };
    if a.sparse().is_some() {
        return Err(bad("sparse accessors are not read".into()));
    }
    let Some(view) = a.view() else {
        return Err(bad("it has no buffer view".into()));
    };
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| bad("its buffer is missing".into()))?;
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| data.get(view.offset()..end))
        .ok_or_else(|| {
            bad(format!(
                "its buffer view {} lies outside its buffer of {} bytes",
                view.index(),
                data.len()
            ))
        })?;
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(bad(format!("its stride of {stride} bytes is below its element size of {size}")));
    }
    let count = a.count();
    if count == 0 {
        return Ok((&[], stride, 0));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(a.offset()));
    match end {
        Some(end) if end <= view_bytes.len() => Ok((&view_bytes[a.offset()..end], stride, count)),
        _ => Err(bad(format!(
            "{count} elements from byte {} are out of range of buffer view {} ({} bytes)",
            a.offset(),
            view.index(),
            view_bytes.len()
        ))),
    }
}

fn read_vec3(a: &gltf::Accessor, buffers: &[Vec<u8>], file: &str, what: &str) -> Result<Vec<Vec3>, SceneError> {
    if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Vec3 || a.normalized() {
        return Err(fail(
            file,
            format_args!(
                "{what} (accessor {}) is {:?} {:?}, not VEC3 FLOAT",
                a.index(),
                a.dimensions(),
                a.data_type()
            ),
            "store positions and normals as 32-bit floats (no quantisation)",
        ));
    }
    let (bytes, stride, count) = accessor_bytes(a, buffers, file, what)?;
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    Ok((0..count)
        .map(|k| k * stride)
        .map(|o| Vec3::new(f(o), f(o + 4), f(o + 8)))
        .collect())
}

fn read_indices(a: &gltf::Accessor, buffers: &[Vec<u8>], file: &str, what: &str) -> Result<Vec<u32>, SceneError> {
    let width = match (a.data_type(), a.dimensions()) {
        (DataType::U8, Dimensions::Scalar) => 1,
        (DataType::U16, Dimensions::Scalar) => 2,
        (DataType::U32, Dimensions::Scalar) => 4,
        (t, d) => {
            return Err(fail(
                file,
                format_args!("{what} (accessor {}) is {d:?} {t:?}, not an unsigned integer scalar", a.index()),
                "store indices as UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT scalars",
            ));
        }
    };
    let (bytes, stride, count) = accessor_bytes(a, buffers, file, what)?;
    Ok((0..count)
        .map(|k| {
            let o = k * stride;
            match width {
                1 => u32::from(bytes[o]),
                2 => u32::from(u16::from_le_bytes([bytes[o], bytes[o + 1]])),
                _ => u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]),
            }
        })
        .collect())
}

/// A glTF mesh's primitives as one indexed mesh, in the order [`place_node`] lists them.
fn shared_mesh(mesh: &gltf::Mesh, prims: &[Primitive]) -> SharedMesh {
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
fn place_node(prims: &[Primitive], world: &Mat4, triangles: &mut Vec<[Vec3; 3]>, normals: &mut Vec<[Vec3; 3]>) {
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

/// A number from a light's `extras` (an object), or `default` when absent.
fn extra(light: &gltf::khr_lights_punctual::Light, key: &str, default: f32, file: &str, at: &str) -> Result<f32, SceneError> {
    let Some(raw) = light.extras() else { return Ok(default) };
    let value: serde_json::Value = serde_json::from_str(raw.get()).map_err(|e| {
        fail(
            file,
            format_args!("{at}'s extras are not JSON: {e}"),
            "write the extras as a JSON object",
        )
    })?;
    match value.get(key) {
        None => Ok(default),
        Some(v) => v.as_f64().map(|x| x as f32).filter(|x| x.is_finite()).ok_or_else(|| {
            fail(
                file,
                format_args!("{at}'s `extras.{key}` is {v}, not a finite number"),
                "write a number",
            )
        }),
    }
}

fn map_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &Mat4,
    node: usize,
    diagonal: f32,
    file: &str,
    spots: &mut usize,
) -> Result<Light, SceneError> {
    let at = match light.name() {
        Some(n) => format!("light {} (\"{n}\") of node {node}", light.index()),
        None => format!("light {} of node {node}", light.index()),
    };
    let position = world.transform_point3(Vec3::ZERO);
    // a light shines along its node's -Z
    let facing = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let radius = |file: &str| -> Result<f32, SceneError> {
        let r = extra(light, "radius", DEFAULT_RADIUS_FRACTION * diagonal, file, &at)?;
        if r < 0.0 {
            return Err(fail(
                file,
                format_args!("{at}'s `extras.radius` is {r}, below 0"),
                "write a radius >= 0",
            ));
        }
        Ok(r)
    };
    let unit = |v: Vec3| {
        if v == Vec3::ZERO {
            Err(fail(
                file,
                format_args!("{at}: its node's transform collapses the light's direction"),
                "give the light's node an invertible transform",
            ))
        } else {
            Ok(v)
        }
    };
    let light = match light.kind() {
        Kind::Directional => {
            let angle_degrees = extra(light, "angle_degrees", DEFAULT_SUN_DEGREES, file, &at)?;
            if !(0.0..180.0).contains(&angle_degrees) {
                return Err(fail(
                    file,
                    format_args!("{at}'s `extras.angle_degrees` is {angle_degrees}, outside [0, 180)"),
                    "write the sun's angular diameter in degrees (about 0.53)",
                ));
            }
            Light::DistantDisk {
                direction: unit(-facing)?,
                angle_degrees,
            }
        }
        Kind::Point => Light::Sphere {
            center: position,
            radius: radius(file)?,
        },
        Kind::Spot { .. } => {
            *spots += 1;
            Light::Disk {
                center: position,
                normal: unit(facing)?,
                radius: radius(file)?,
            }
        }
    };
    if !(position.is_finite()) {
        return Err(fail(
            file,
            format_args!("{at} is placed at a position that is not finite"),
            "write finite transforms",
        ));
    }
    Ok(light)
}

/// Pixels of an imported camera's image height; its width follows the aspect ratio.
pub const CAMERA_HEIGHT: u32 = 512;

fn map_camera(camera: &gltf::Camera, world: &Mat4, node: usize, file: &str) -> Result<Camera, SceneError> {
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if !(position.is_finite() && forward != Vec3::ZERO && up != Vec3::ZERO) {
        return Err(fail(
            file,
            format_args!("camera {} of node {node} has a transform that collapses its view", camera.index()),
            "give the camera's node an invertible transform",
        ));
    }
    let target = position + forward;
    let size = |aspect: f32| {
        let w = (CAMERA_HEIGHT as f32 * aspect).round();
        if w.is_finite() && w >= 1.0 {
            (w.min(4096.0) as u32, CAMERA_HEIGHT)
        } else {
            (CAMERA_HEIGHT, CAMERA_HEIGHT)
        }
    };
    Ok(match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            // glTF's yfov is in radians: said so here, not as the scene format's degrees
            let yfov = p.yfov();
            if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
                return Err(fail(
                    file,
                    format_args!(
                        "camera {}'s yfov is {yfov} radians ({:.1} degrees), outside (0, pi)",
                        camera.index(),
                        yfov.to_degrees()
                    ),
                    "write `yfov` in radians, such as 0.8 (46 degrees)",
                ));
            }
            let (width, height) = size(p.aspect_ratio().unwrap_or(1.0));
            Camera::Perspective {
                position,
                target,
                up,
                fov_y_degrees: p.yfov().to_degrees(),
                width,
                height,
                near: Some(p.znear()),
                far: p.zfar(),
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            let (width, height) = size(o.xmag() / o.ymag());
            Camera::Orthographic {
                position,
                target,
                up,
                half_height: o.ymag(),
                width,
                height,
                near: Some(o.znear()),
                far: Some(o.zfar()),
            }
        }
    })
}

/// A camera framing `bounds`: 40 degrees, from above and in front (+Y, +Z), the bounding
/// sphere filling the view's height, 512 x 512 pixels.
pub(crate) fn framing_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let (centre, radius) = if lo.is_finite() && hi.is_finite() {
        ((lo + hi) * 0.5, (0.5 * (hi - lo).length()).max(1e-3))
    } else {
        (Vec3::ZERO, 1.0)
    };
    let fov = 40.0f32;
    let distance = radius / (0.5 * fov).to_radians().sin();
    let from = Vec3::new(0.35, 0.55, 1.0).normalize();
    Camera::Perspective {
        position: centre + from * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_degrees: fov,
        width: CAMERA_HEIGHT,
        height: CAMERA_HEIGHT,
        near: None,
        far: None,
    }
}

/// The light of a glTF scene that has none: a sun from above, [`DEFAULT_SUN_DEGREES`] wide.
pub(crate) fn default_sun() -> Light {
    Light::DistantDisk {
        direction: Vec3::new(0.4, 1.0, 0.3).normalize(),
        angle_degrees: DEFAULT_SUN_DEGREES,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;
    use serde_json::{Value, json};

    /// A glTF (JSON) whose one buffer is a data URI holding `floats` then `indices`.
    /// Accessor 0: the positions (`floats.len() / 3` VEC3); accessor 1: the indices.
    fn with_buffer(mut root: Value, floats: &[f32], indices: &[u32]) -> Vec<u8> {
        use base64::Engine;
        let mut bin: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
        let split = bin.len();
        bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for v in floats.chunks_exact(3) {
            for k in 0..3 {
                (lo[k], hi[k]) = (lo[k].min(v[k]), hi[k].max(v[k]));
            }
        }
        // glTF 2.0 requires POSITION's bounds; a NaN corner keeps them finite (min/max skip it)
        let defaults = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": bin.len(), "uri": uri}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": split},
                {"buffer": 0, "byteOffset": split, "byteLength": bin.len() - split},
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": floats.len() / 3, "type": "VEC3", "min": lo, "max": hi},
                {"bufferView": 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR"},
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        });
        let (Value::Object(d), Value::Object(r)) = (defaults, &mut root) else {
            unreachable!()
        };
        for (k, v) in d {
            r.entry(k).or_insert(v);
        }
        root.to_string().into_bytes()
    }

    const TRIANGLE: [f32; 9] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0];

    fn error_of(bytes: &[u8]) -> String {
        match Scene::from_gltf_slice(bytes) {
            Ok(_) => panic!("accepted"),
            Err(e) => e.to_string(),
        }
    }

    /// glTF 2.0 section 3.5.2: a node's world matrix is its parent's times its own, its own
    /// being T * R * S. The expected corners are worked by hand, child first: child scale
    /// 0.5 and move +Y; parent scale 2, turn 90 degrees about +Y, move +X. The reverse order
    /// (parent's matrix applied first) would put (1, 0, 0) at (0.5, 1, -1), not (1, 2, -1).
    #[test]
    fn nested_node_transforms_apply_the_child_first_then_the_parent() {
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let root = json!({
            "scenes": [{"nodes": [0]}],
            "nodes": [
                {"children": [1], "translation": [1.0, 0.0, 0.0], "rotation": [0.0, s, 0.0, s], "scale": [2.0, 2.0, 2.0]},
                {"mesh": 0, "translation": [0.0, 1.0, 0.0], "scale": [0.5, 0.5, 0.5]},
            ],
        });
        let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
        let tri = scene.triangles()[0];
        // (1,0,0) -> child (0.5,1,0) -> parent scale (1,2,0) -> turn (0,2,-1) -> move (1,2,-1)
        // (0,0,1) -> (0,1,0.5) -> (0,2,1) -> (1,2,0) -> (2,2,0)
        // (0,1,0) -> (0,1.5,0) -> (0,3,0) -> (0,3,0) -> (1,3,0)
        let want = [Vec3::new(1.0, 2.0, -1.0), Vec3::new(2.0, 2.0, 0.0), Vec3::new(1.0, 3.0, 0.0)];
        for (got, want) in tri.iter().zip(want) {
            // a turn by 90 degrees in f32 (cos is 4e-8, not 0), scaled by 2: a few ulps of 3
            assert!(got.distance(want) < 4.0 * f32::EPSILON * 3.0, "{tri:?} against {want:?}");
        }
    }

    /// Issue 48, item 7: two nested scales of 1e20 multiply past f32 (each finite), and a
    /// finite scale of 1e30 carries a corner past it: both are refused naming the node,
    /// where they placed NaN and infinite triangles and drew an empty, all-lit image.
    #[test]
    fn transforms_that_overflow_f32_are_refused_naming_the_node() {
        let nested = json!({
            "scenes": [{"nodes": [0]}],
            "nodes": [
                {"name": "outer", "children": [1], "scale": [1e20, 1e20, 1e20]},
                {"name": "inner", "mesh": 0, "scale": [1e20, 1e20, 1e20]},
            ],
        });
        let e = Scene::from_gltf_slice(&with_buffer(nested, &TRIANGLE, &[0, 1, 2]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("inner") && e.contains("world transform (its parents' times its own) overflows f32"),
            "{e}"
        );
        let far = json!({
            "scenes": [{"nodes": [0]}],
            "nodes": [{"name": "far", "mesh": 0, "scale": [1e30, 1e30, 1e30]}],
        });
        let big = [1e10f32, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let e = Scene::from_gltf_slice(&with_buffer(far, &big, &[0, 1, 2])).unwrap_err().to_string();
        assert!(e.contains("far") && e.contains("outside f32's range"), "{e}");
    }

    /// A mesh placed by two nodes is read once and placed twice; the scene says so.
    #[test]
    fn a_mesh_shared_by_nodes_is_placed_by_each() {
        let root = json!({
            "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [0.0, 0.0, 5.0]}],
        });
        let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.triangles().len(), 2);
        assert_eq!(scene.placements(), (2, 1));
        assert_eq!(scene.triangles()[1][0], Vec3::new(1.0, 0.0, 5.0));
        // no camera and no light: a framing camera and a sun, both noted
        let notes = scene.notes().join("\n");
        assert!(notes.contains("no camera") && notes.contains("no light"), "{notes}");
        assert!(matches!(scene.lights[..], [Light::DistantDisk { .. }]));
    }

    /// KHR_lights_punctual: a light shines along its node's -Z. Directional: a distant disk
    /// towards +Z of the node, `extras.angle_degrees` wide (default 0.5). Point: a sphere of
    /// `extras.radius` (default 1 % of the diagonal). Spot: a disk facing along the spot.
    #[test]
    fn each_light_kind_maps_as_documented() {
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let root = json!({
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "directional", "extras": {"angle_degrees": 2.0}},
                {"type": "directional"},
                {"type": "point", "extras": {"radius": 0.25}},
                {"type": "spot", "spot": {"outerConeAngle": 0.5}},
            ]}},
            "nodes": [
                {"mesh": 0},
                // turned -90 degrees about X: -Z becomes -Y (shining down), +Z becomes +Y
                {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-s, 0.0, 0.0, s]},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"extensions": {"KHR_lights_punctual": {"light": 2}}, "translation": [0.0, 4.0, 0.0]},
                {"extensions": {"KHR_lights_punctual": {"light": 3}}, "translation": [0.0, 3.0, 0.0], "rotation": [-s, 0.0, 0.0, s]},
            ],
        });
        let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
        let diagonal = (scene.bounds().1 - scene.bounds().0).length();
        let near = |a: Vec3, b: Vec3| a.distance(b) < 1e-6;
        match &scene.lights[..] {
            [
                Light::DistantDisk {
                    direction: d0,
                    angle_degrees: a0,
                },
                Light::DistantDisk {
                    direction: d1,
                    angle_degrees: a1,
                },
                Light::Sphere { center, radius },
                Light::Disk {
                    center: c3,
                    normal,
                    radius: r3,
                },
            ] => {
                assert!(near(*d0, Vec3::Y) && *a0 == 2.0, "{d0} {a0}");
                assert!(near(*d1, Vec3::Z) && *a1 == DEFAULT_SUN_DEGREES, "{d1} {a1}");
                assert!(*center == Vec3::new(0.0, 4.0, 0.0) && *radius == 0.25);
                assert!(near(*normal, Vec3::NEG_Y) && *c3 == Vec3::new(0.0, 3.0, 0.0));
                assert_eq!(*r3, DEFAULT_RADIUS_FRACTION * diagonal);
            }
            other => panic!("{other:?}"),
        }
        assert!(
            scene.notes().iter().any(|n| n.contains("cone angles are ignored")),
            "{:?}",
            scene.notes()
        );
    }

    #[test]
    fn more_lights_than_the_runtime_binds_are_refused_with_the_count() {
        let n = MAX_LIGHTS + 1;
        let lights: Vec<Value> = (0..n).map(|_| json!({"type": "point"})).collect();
        let mut nodes = vec![json!({"mesh": 0})];
        nodes.extend((0..n).map(|i| json!({"extensions": {"KHR_lights_punctual": {"light": i}}})));
        let root = json!({"extensions": {"KHR_lights_punctual": {"lights": lights}}, "nodes": nodes});
        let e = error_of(&with_buffer(root, &TRIANGLE, &[0, 1, 2]));
        assert!(
            e.contains(&format!("{n} lights")) && e.contains(&format!("limit of {MAX_LIGHTS}")),
            "{e}"
        );
    }

    /// The first camera the traversal meets: its node's position, looking down its -Z.
    #[test]
    fn the_first_camera_is_placed_by_its_node() {
        let root = json!({
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1, "aspectRatio": 2.0}}],
            "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.5, 6.0]}],
        });
        let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
        match scene.camera {
            Camera::Perspective {
                position,
                target,
                fov_y_degrees,
                width,
                height,
                ..
            } => {
                assert_eq!(position, Vec3::new(0.0, 0.5, 6.0));
                assert_eq!(target, Vec3::new(0.0, 0.5, 5.0));
                assert_eq!((width, height), (2 * CAMERA_HEIGHT, CAMERA_HEIGHT));
                assert!((fov_y_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
            }
            Camera::Orthographic { .. } => panic!("orthographic"),
        }
    }

    /// Bad files name the file and the node, mesh, primitive or accessor at fault.
    #[test]
    fn bad_files_are_errors_that_name_the_part_at_fault() {
        let ok = json!({"nodes": [{"mesh": 0}]});
        let tri = |root: Value| with_buffer(root, &TRIANGLE, &[0, 1, 2]);
        let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
            ("not glTF", b"{ nonsense".to_vec(), &["cannot read it"]),
            (
                "a short GLB header",
                b"glTF\x02\x00\x00\x00\x05\x00\x00\x00".to_vec(),
                &["GLB header"],
            ),
            (
                "an index past the vertices",
                with_buffer(ok.clone(), &TRIANGLE, &[0, 1, 7]),
                &["mesh 0 primitive 0", "index 2 is 7"],
            ),
            (
                "NaN positions",
                with_buffer(ok.clone(), &[f32::NAN, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0], &[0, 1, 2]),
                &["POSITION (accessor 0)", "vertex 0 is NaN"],
            ),
            (
                "a cycle of nodes",
                tri(json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "children": [1]}, {"children": [0]}]})),
                &["node 0", "reached twice"],
            ),
            (
                "a required extension",
                tri(
                    json!({"nodes": [{"mesh": 0}], "extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"]}),
                ),
                &["KHR_draco_mesh_compression"],
            ),
            (
                "a missing buffer file",
                tri(json!({"nodes": [{"mesh": 0}], "buffers": [{"byteLength": 48, "uri": "missing.bin"}]})),
                &["buffer 0", "missing.bin"],
            ),
            (
                "an accessor out of its view",
                tri(json!({"nodes": [{"mesh": 0}], "accessors": [
                    {"bufferView": 0, "componentType": 5126, "count": 1000, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
                    {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
                ]})),
                &["accessor 0", "1000 elements", "out of range"],
            ),
            (
                "a view out of its buffer",
                tri(json!({"nodes": [{"mesh": 0}], "bufferViews": [
                    {"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 400},
                ]})),
                &["buffer view 1", "outside its buffer"],
            ),
            (
                "positions of the wrong type",
                tri(json!({"nodes": [{"mesh": 0}], "accessors": [
                    {"bufferView": 0, "componentType": 5123, "count": 9, "type": "SCALAR", "min": [0], "max": [1]},
                    {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
                ]})),
                &["meshes[0].primitives[0]", "POSITION"],
            ),
        ];
        for (what, bytes, wants) in cases {
            let e = error_of(&bytes);
            assert!(e.contains("glTF `<memory>`"), "{what}: {e}");
            for w in wants {
                assert!(e.contains(w), "{what}: `{w}` missing from: {e}");
            }
            assert!(e.contains("hint:"), "{what}: {e}");
        }
    }

    /// Points and lines are skipped and counted; materials are ignored, said once.
    #[test]
    fn what_is_ignored_is_said_once() {
        let root = json!({
            "materials": [{}, {}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "material": 0},
                {"attributes": {"POSITION": 0}, "mode": 1},
            ]}],
        });
        let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.triangles().len(), 1);
        let notes = scene.notes();
        assert_eq!(notes.iter().filter(|n| n.contains("2 material(s)")).count(), 1, "{notes:?}");
        assert_eq!(
            notes.iter().filter(|n| n.contains("1 primitive(s) of points or lines")).count(),
            1,
            "{notes:?}"
        );
    }

    /// Strips and fans become the triangles glTF 2.0 section 3.7.2.1 lists.
    #[test]
    fn strips_and_fans_become_triangle_lists() {
        assert_eq!(triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3, 4]), [0, 1, 2, 2, 1, 3, 2, 3, 4]);
        assert_eq!(triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]), [1, 2, 0, 2, 3, 0]);
        assert_eq!(triangle_list(Mode::Triangles, &[0, 1, 2, 3]), [0, 1, 2]);
    }

    /// The generated city: the same bytes for the same seed, at least the triangles asked
    /// for and less than one tower more, each tower a node placing one of six meshes.
    #[test]
    fn the_city_is_reproducible_and_reaches_its_size() {
        let a = crate::generate::city_glb(20_000, 7);
        assert_eq!(a, crate::generate::city_glb(20_000, 7));
        assert_ne!(a, crate::generate::city_glb(20_000, 8));
        let scene = Scene::from_gltf_slice(&a).unwrap_or_else(|e| panic!("{e}"));
        let n = scene.triangles().len();
        // the largest tower has 8 * 12 * 32 + 12 = 3084 triangles
        assert!((20_000..20_000 + 3084).contains(&n), "{n}");
        let (nodes, meshes) = scene.placements();
        // the ground and some of the six towers' meshes, each read once
        assert!((3..=7).contains(&meshes), "{meshes}");
        assert!(nodes > 10, "{nodes}");
        // every tower stands on the ground
        assert!(scene.bounds().0.y.abs() < 1e-6, "{:?}", scene.bounds());
    }
}
