//! What every mesh reader shares: the object-space mesh it returns, the files it may open
//! (inside the scene's folder, capped in size) and smooth normals for meshes without them.

use crate::error::{SceneError, SceneErrorKind};
use crate::validate::MAX_OBJ_BYTES;
use std::path::{Component, Path, PathBuf};

use glam::Vec3;

/// Object-space triangles with per-corner normals (`None`: use face normals), and the
/// instancing they were placed from, where a glTF file shares meshes between nodes.
pub(crate) struct MeshData {
    pub(crate) triangles: Vec<[Vec3; 3]>,
    pub(crate) normals: Option<Vec<[Vec3; 3]>>,
    pub(crate) instancing: Option<Instancing>,
}

/// Meshes read once and placed by several nodes, as a glTF file holds them: indices as
/// they are, positions and normals in the mesh's own space, and a world matrix per node
/// that places one. The scene's triangles are these placed (the runtime's
/// `bind_geometry` takes them as meshes and instances instead of a soup).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Instancing {
    pub meshes: Vec<SharedMesh>,
    /// Per node that places a mesh, in the order its triangles are listed: the mesh, and
    /// its column-major object-to-world matrix.
    pub instances: Vec<(usize, [f32; 16])>,
}

/// One indexed mesh of an [`Instancing`] (its primitives' triangles, one after the other).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SharedMesh {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

impl Instancing {
    /// Triangles its instances place.
    pub fn triangles(&self) -> usize {
        self.instances.iter().map(|(m, _)| self.meshes[*m].indices.len() / 3).sum()
    }
}

/// Resolves `rel` inside `base`, refusing absolute paths, `..` and links leading out.
pub(crate) fn resolve_inside(rel: &str, base: &Path) -> Result<PathBuf, SceneError> {
    let escape = |what: &str| {
        SceneError::new(SceneErrorKind::Mesh, format!("the mesh path `{rel}` {what}"))
            .with_hint("write a path relative to the scene file's folder, without `..`, and put the mesh beside the scene")
    };
    let p = Path::new(rel);
    if rel.is_empty() {
        return Err(escape("is empty"));
    }
    if p.is_absolute() || p.has_root() {
        return Err(escape("is absolute"));
    }
    // `..` is taken lexically: a path that climbs and comes back down inside the folder
    // (`sub/../sub2.bin`, a glTF in `sub/` naming `../sub2.bin`) stays inside; one that
    // climbs above the folder leaves it
    let mut inside = PathBuf::new();
    for c in p.components() {
        match c {
            Component::Normal(n) => inside.push(n),
            Component::CurDir => {}
            Component::ParentDir => {
                if !inside.pop() {
                    return Err(escape("leaves the scene's folder (`..`)"));
                }
            }
            Component::RootDir | Component::Prefix(_) => return Err(escape("is absolute")),
        }
    }
    let joined = base.join(&inside);
    let canon_base = base.canonicalize().map_err(|e| {
        SceneError::new(
            SceneErrorKind::Io,
            format!("cannot open the scene's folder `{}`: {e}", base.display()),
        )
        .with_hint("load the scene from an existing folder")
    })?;
    let canon = joined.canonicalize().map_err(|e| {
        SceneError::new(SceneErrorKind::Io, format!("cannot open the mesh file `{}`: {e}", joined.display()))
            .with_hint("check that the mesh file is beside the scene file")
    })?;
    if !canon.starts_with(&canon_base) {
        return Err(escape("leads out of the scene's folder through a link"));
    }
    Ok(canon)
}

/// The area-weighted smooth normal of each vertex of an indexed triangle list (not
/// normalised: placing the mesh normalises).
pub(crate) fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut smooth = vec![Vec3::ZERO; positions.len()];
    for f in indices.chunks_exact(3) {
        let (a, b, c) = (positions[f[0] as usize], positions[f[1] as usize], positions[f[2] as usize]);
        let n = (b - a).cross(c - a);
        if n.is_finite() {
            for &k in f {
                smooth[k as usize] += n;
            }
        }
    }
    smooth
}

/// Reads a regular file of at most `cap` bytes; anything else (a FIFO, a device, a folder,
/// a larger file) is refused without reading it (or, if it grows, past `cap + 1` bytes).
/// The one reader of files for sshc's commands (issue 48, item 8): a regular file (after
/// links; FIFOs, devices and folders are refused from their metadata, never opened) of at
/// most `cap` bytes, read through `take` so that a file growing while read stops at the
/// cap. A missing file keeps its `NotFound` kind.
pub fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::other("it is not a regular file"));
    }
    if meta.len() > cap {
        return Err(std::io::Error::other(format!(
            "it has {} bytes, above the limit of {cap}",
            meta.len()
        )));
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(std::io::Error::other(format!("it grew above the limit of {cap} bytes")));
    }
    Ok(bytes)
}

/// [`read_capped`] as UTF-8 text.
pub fn read_text(path: &Path, cap: u64) -> std::io::Result<String> {
    String::from_utf8(read_capped(path, cap)?).map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "it is not UTF-8 text"))
}

/// The largest text file a command reads: a technique, a scene, a sweep file, a viewer
/// script, a shard's manifest or a claim (the bundled ones are under 40 KiB).
pub const MAX_TEXT_BYTES: u64 = 16 << 20;

/// Reads the mesh file `rel` (a `what` file: "OBJ", "glTF") inside `base`, refusing paths
/// that leave it and files over [`MAX_OBJ_BYTES`]: its path and bytes.
pub(crate) fn read_mesh_file(rel: &str, base: &Path, what: &str) -> Result<(PathBuf, Vec<u8>), SceneError> {
    let path = resolve_inside(rel, base)?;
    let bytes = read_capped(&path, MAX_OBJ_BYTES).map_err(|e| {
        SceneError::new(SceneErrorKind::Io, format!("cannot read the {what} file `{}`: {e}", path.display())).with_hint(format!(
            "give a regular file (not a pipe or device) of at most {} MiB",
            MAX_OBJ_BYTES >> 20
        ))
    })?;
    Ok((path, bytes))
}
