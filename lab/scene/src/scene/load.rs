//! Reading a scene (a RON scene file, or a glTF file as a scene of its own) and building
//! its world-space triangles, object by object within the triangle and memory limits.

use super::{GLTF_SHADOW_MAP, Scene, is_gltf};
use crate::error::{SceneError, SceneErrorKind, syntax_error};
use crate::mesh::{Reads, analytic_triangles, build_mesh, place};
use crate::schema::{Object, SceneDesc, ShadowFit};
use crate::source::MeshData;
use crate::validate::{MAX_SCENE_TRIANGLES, validate};
use std::path::{Path, PathBuf};

use sshc_light::bounds_of;

impl Scene {
    /// Reads a scene file. OBJ paths resolve against the file's folder. A `.gltf` or `.glb`
    /// file is read as a scene of its own ([`Scene::load_gltf`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        if is_gltf(path) {
            return Scene::load_gltf(path);
        }
        let text = crate::source::read_text(path, crate::source::MAX_TEXT_BYTES).map_err(|e| {
            SceneError::new(SceneErrorKind::Io, format!("cannot read the scene: {e}"))
                .with_file(Some(path))
                .with_hint("check the path of the scene file")
        })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let base = if base.as_os_str().is_empty() { PathBuf::from(".") } else { base };
        let mut scene = Scene::parse(&text, &base, Some(path))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Reads a glTF 2.0 file as a scene: its triangles as one object that casts and
    /// receives, its first camera (else one framing the scene, 512 x 512), its
    /// `KHR_lights_punctual` lights (else a sun from above, with a note), a
    /// [`GLTF_SHADOW_MAP`]-texel shadow map fitted to the scene. What was ignored is in
    /// [`Scene::notes`].
    pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let folder = if folder.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            folder
        };
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let imported = crate::gltf::load(&name, &folder).map_err(|e| e.with_file(Some(path)))?;
        let mut scene = Scene::from_imported(imported, &name, &folder).map_err(|e| e.with_file(Some(path)))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::load_gltf`] of glTF bytes (JSON or GLB) held in memory: only the GLB chunk
    /// and data URIs can hold its buffers.
    pub fn from_gltf_slice(bytes: &[u8]) -> Result<Scene, SceneError> {
        let imported = crate::gltf::import(bytes, "<memory>", None)?;
        Scene::from_imported(imported, "<memory>", Path::new("."))
    }

    fn from_imported(imported: crate::gltf::Imported, name: &str, folder: &Path) -> Result<Scene, SceneError> {
        let crate::gltf::Imported {
            mesh,
            camera,
            lights,
            mut notes,
            files,
            placements,
        } = imported;
        let bounds = bounds_of(mesh.triangles.iter().flatten().copied());
        let camera = camera.unwrap_or_else(|| {
            notes.push("it has no camera: a camera framing the scene is used".into());
            crate::gltf::framing_camera(bounds)
        });
        let lights = if lights.is_empty() {
            notes.push(format!(
                "it has no light (KHR_lights_punctual): a sun from above, {} degrees wide, is used",
                crate::gltf::DEFAULT_SUN_DEGREES
            ));
            vec![crate::gltf::default_sun()]
        } else {
            lights
        };
        let desc = SceneDesc {
            camera,
            shadow_map: GLTF_SHADOW_MAP,
            lights,
            objects: vec![Object {
                name: Some(name.to_string()),
                mesh: crate::schema::Mesh::Gltf { path: name.to_string() },
                transform: Default::default(),
                flat_normals: false,
                casts: true,
                receives: true,
            }],
            shadow_fit: ShadowFit::Scene,
            cascades: None,
        };
        let mut scene = Scene::build_with(desc, folder, vec![Some(mesh)])?;
        scene.notes = notes.into_iter().map(|n| format!("{name}: {n}")).collect();
        scene.files = files;
        scene.placements = placements;
        Ok(scene)
    }

    /// Reads a scene from RON text; OBJ paths resolve against `base_dir`.
    pub fn from_str(text: &str, base_dir: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::parse(text, base_dir.as_ref(), None)
    }

    /// Builds a scene from a description (OBJ paths resolve against `base_dir`).
    pub fn from_desc(desc: SceneDesc, base_dir: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::build(desc, base_dir.as_ref()).map_err(|e| e.with_file(None))
    }

    fn parse(text: &str, base: &Path, file: Option<&Path>) -> Result<Scene, SceneError> {
        let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let desc: SceneDesc = options.from_str(text).map_err(|e| syntax_error(&e).with_file(file))?;
        Scene::build(desc, base).map_err(|e| e.with_file(file))
    }

    fn build(desc: SceneDesc, base: &Path) -> Result<Scene, SceneError> {
        Scene::build_with(desc, base, Vec::new())
    }

    /// Builds the scene; `built[i]`, where given, is object `i`'s mesh already read.
    fn build_with(mut desc: SceneDesc, base: &Path, mut built: Vec<Option<MeshData>>) -> Result<Scene, SceneError> {
        validate(&mut desc)?;
        // The analytic meshes' triangles, all counted before any is built.
        let mut planned = 0usize;
        for (i, object) in desc.objects.iter().enumerate() {
            planned = planned.saturating_add(analytic_triangles(&object.mesh).unwrap_or(0));
            if planned > MAX_SCENE_TRIANGLES {
                return Err(SceneError::invalid(
                    format!("objects[{i}].mesh"),
                    format!("the scene's meshes reach {planned} triangles by this object, above the limit of {MAX_SCENE_TRIANGLES}"),
                    "use coarser meshes (fewer sphere segments) or fewer objects",
                ));
            }
        }
        // the memory the analytic meshes (and what is already read) will take, before any
        // is built
        let read: usize = built.iter().flatten().map(|m| m.triangles.len()).sum();
        crate::memory::check(planned.saturating_add(read))
            .map_err(|why| SceneError::invalid("objects", why, "use coarser meshes, or a machine with more memory"))?;
        let mut triangles = Vec::new();
        let mut normals = Vec::new();
        let mut object_triangles = Vec::with_capacity(desc.objects.len());
        let mut instancing = Vec::with_capacity(desc.objects.len());
        let mut reads = Reads::default();
        for (i, object) in desc.objects.iter().enumerate() {
            let start = triangles.len();
            let too_many = |count: usize| {
                let at = match &object.name {
                    Some(n) => format!("objects[{i}] (\"{n}\").mesh"),
                    None => format!("objects[{i}].mesh"),
                };
                SceneError::invalid(
                    at,
                    format!("the scene reaches {count} triangles with this object, above the limit of {MAX_SCENE_TRIANGLES}"),
                    "use coarser meshes or fewer objects",
                )
            };
            if let Some(n) = analytic_triangles(&object.mesh)
                && start.saturating_add(n) > MAX_SCENE_TRIANGLES
            {
                return Err(too_many(start.saturating_add(n)));
            }
            let mut mesh = match built.get_mut(i).and_then(Option::take) {
                Some(mesh) => mesh,
                None => build_mesh(i, object, base, &mut reads)?,
            };
            if start.saturating_add(mesh.triangles.len()) > MAX_SCENE_TRIANGLES {
                return Err(too_many(start.saturating_add(mesh.triangles.len())));
            }
            place(&mesh, object, &mut triangles, &mut normals);
            object_triangles.push(start..triangles.len());
            // kept where the triangles are its instances' exactly: the object's transform
            // adds none, its normals are the file's, and no triangle was dropped
            let identity =
                object.transform.matrix().to_cols_array().map(f32::to_bits) == glam::Mat4::IDENTITY.to_cols_array().map(f32::to_bits);
            let placed = triangles.len() - start;
            instancing.push(
                mesh.instancing
                    .take()
                    .filter(|s| identity && !object.flat_normals && s.triangles() == placed),
            );
        }
        let bounds = bounds_of(triangles.iter().flatten().copied());
        let scene = Scene {
            camera: desc.camera,
            shadow_map: desc.shadow_map,
            lights: desc.lights,
            shadow_fit: desc.shadow_fit,
            cascades: desc.cascades,
            objects: desc.objects,
            source: None,
            notes: reads.notes,
            files: reads.files,
            placements: (0, 0),
            triangles,
            normals,
            object_triangles,
            instancing,
            bounds,
        };
        scene.check_precision()?;
        scene.check_fit(scene.shadow_fit)?;
        Ok(scene)
    }
}
