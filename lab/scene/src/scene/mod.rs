//! The loaded scene: its description, the world-space triangles built from it, the camera
//! and the light views fitted to it.
//!
//! The files: this one holds the scene and what it answers of its geometry; `load.rs` reads
//! and builds it, `camera.rs` answers for its camera, `fit.rs` fits the light views to it
//! (`FitReport`, and the `Occluders` the light crate fits to), `precision.rs` checks what
//! f32 resolves at its extent.

use crate::error::SceneError;
use crate::schema::{Camera, Object, ShadowFit};
use crate::validate::validate_light;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;
use sshc_light::Light;

mod camera;
mod fit;
mod load;
mod precision;

pub use fit::FitReport;

/// A loaded scene: its description plus the world-space triangles built from it.
///
/// `camera`, `shadow_map` and `lights` may be changed after loading (a test can shrink
/// the image); the geometry is fixed once loaded.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera (may be changed, e.g. by [`Scene::set_camera_size`]).
    pub camera: Camera,
    /// Side of the square shadow map in texels.
    pub shadow_map: u32,
    /// The lights.
    pub lights: Vec<Light>,
    shadow_fit: ShadowFit,
    cascades: Option<crate::schema::Cascades>,
    objects: Vec<Object>,
    source: Option<PathBuf>,
    notes: Vec<String>,
    files: Vec<PathBuf>,
    placements: (usize, usize),
    triangles: Vec<[Vec3; 3]>,
    normals: Vec<[Vec3; 3]>,
    object_triangles: Vec<Range<usize>>,
    /// Per object: the glTF instancing its triangles were placed from, where kept.
    instancing: Vec<Option<crate::source::Instancing>>,
    bounds: (Vec3, Vec3),
}

/// Side of the shadow map of a scene read from a glTF file.
pub const GLTF_SHADOW_MAP: u32 = 2048;

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// `light` checked and its directions normalised as a scene file's light `i` is (checking
/// a checked light changes nothing).
pub fn checked_light(i: usize, mut light: Light) -> Result<Light, SceneError> {
    let name = light.kind_name();
    validate_light(&mut light, &|field: &str| format!("lights[{i}] ({name}).{field}"))?;
    Ok(light)
}

impl Scene {
    /// Replaces light `i` (or adds it, at `i` = the number of lights), checked and its
    /// directions normalised as a scene file's are.
    pub fn set_light(&mut self, i: usize, light: Light) -> Result<(), SceneError> {
        let light = checked_light(i, light)?;
        match i.cmp(&self.lights.len()) {
            std::cmp::Ordering::Less => self.lights[i] = light,
            std::cmp::Ordering::Equal => self.lights.push(light),
            std::cmp::Ordering::Greater => {
                return Err(SceneError::invalid(
                    format!("lights[{i}]"),
                    format!("the scene has {} light(s): light {i} would leave a gap", self.lights.len()),
                    "replace an existing light or add the next one",
                ));
            }
        }
        Ok(())
    }

    /// Whether object `i` casts shadows (`casts` in the file; default true).
    pub fn casts(&self, i: usize) -> bool {
        self.objects[i].casts
    }

    /// Whether object `i` receives shadows (`receives` in the file; default true).
    pub fn receives(&self, i: usize) -> bool {
        self.objects[i].receives
    }

    /// For each triangle of [`Scene::triangles`], whether its object casts shadows.
    pub fn casting_triangles(&self) -> Vec<bool> {
        let mut out = vec![true; self.triangles.len()];
        for (i, o) in self.objects.iter().enumerate() {
            if !o.casts {
                out[self.object_triangles[i].clone()].fill(false);
            }
        }
        out
    }

    /// Number of triangles of casting objects.
    pub fn caster_triangles(&self) -> usize {
        (0..self.objects.len())
            .filter(|&i| self.objects[i].casts)
            .map(|i| self.object_triangles[i].len())
            .sum()
    }

    /// The object that triangle `t` of [`Scene::triangles`] belongs to.
    pub fn object_of_triangle(&self, t: usize) -> Option<usize> {
        // object ranges are in file order and do not overlap
        let i = self.object_triangles.partition_point(|r| r.end <= t);
        (i < self.object_triangles.len() && self.object_triangles[i].contains(&t)).then_some(i)
    }

    /// What loading noted: what a glTF file had that was ignored or assumed. Each says its
    /// file; a command prints them once.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The mesh files read (OBJ, glTF and its buffers), besides the scene file itself.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// For a scene loaded from a glTF file: how many nodes place a mesh, and how many
    /// distinct meshes they place (the instancing the file holds); (0, 0) otherwise.
    pub fn placements(&self) -> (usize, usize) {
        self.placements
    }

    /// The scene file this scene was loaded from, if any.
    pub fn source(&self) -> Option<&Path> {
        self.source.as_deref()
    }

    /// The objects as written in the file.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// World-space triangles after transforms, object by object in file order;
    /// degenerate triangles (zero area, non-finite corners) are dropped.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// World-space unit normals of the three corners of each triangle of
    /// [`Scene::triangles`] (smooth where the mesh has smooth normals).
    pub fn normals(&self) -> &[[Vec3; 3]] {
        &self.normals
    }

    /// The range of [`Scene::triangles`] that object `i` produced.
    pub fn object_triangles(&self, i: usize) -> Range<usize> {
        self.object_triangles[i].clone()
    }

    /// Object `i`'s meshes and instances, where a glTF file shares meshes between nodes
    /// (read once, each node's instance placed by its matrix): its triangles
    /// ([`Scene::object_triangles`]) are these instances placed, in order. `None` for
    /// other objects, and where the scene's triangles are not exactly the instances' (the
    /// object has a transform of its own or flat normals, a node's matrix mirrors, or a
    /// degenerate triangle was dropped).
    pub fn instancing(&self, i: usize) -> Option<&crate::source::Instancing> {
        self.instancing.get(i)?.as_ref()
    }

    /// Vertex buffer for the GPU: 3 vertices per triangle, each 6 `f32`: world position
    /// xyz, then world unit normal xyz (stride 24 bytes).
    pub fn vertex_data(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.triangles.len() * 18);
        for (tri, nrm) in self.triangles.iter().zip(&self.normals) {
            for k in 0..3 {
                out.extend_from_slice(&tri[k].to_array());
                out.extend_from_slice(&nrm[k].to_array());
            }
        }
        out
    }

    /// Axis-aligned bounds (min, max) of all triangles; (0, 0) for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// A 64-bit FNV-1a hash of everything that determines a ground-truth image: the
    /// world-space triangles and normals, the camera and the lights (not the file's text or
    /// paths). A key for caches.
    pub fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        // The vertex data's values in its order, without building it (at the triangle limit
        // that copy doubled the scene's memory).
        for (tri, nrm) in self.triangles.iter().zip(&self.normals) {
            for k in 0..3 {
                for v in tri[k].to_array().into_iter().chain(nrm[k].to_array()) {
                    eat(&v.to_bits().to_le_bytes());
                }
            }
        }
        let rest = ron::to_string(&(&self.camera, self.shadow_map, &self.lights)).unwrap_or_default();
        eat(rest.as_bytes());
        // Which objects cast (only when some does not, so that the keys of scenes where
        // every object casts stay as they were).
        if self.objects.iter().any(|o| !o.casts) {
            eat(b"casts");
            for o in &self.objects {
                eat(&[u8::from(o.casts)]);
            }
        }
        // and which receive (only when some does not, likewise)
        if self.objects.iter().any(|o| !o.receives) {
            eat(b"receives");
            for o in &self.objects {
                eat(&[u8::from(o.receives)]);
            }
        }
        h
    }
}
