//! The scene the plugin shades, handed over as an sshc scene file, so that `sshc truth`
//! computes the ray-traced visibility at the very pixels Bevy's camera draws
//! (docs/bevy.md, "Against the truth").
//!
//! Insert [`ExportScene`] as a resource: in the app's next `Last`, after transforms have
//! propagated, the plugin writes `scene.ron` and its meshes into the folder, and replaces
//! the request with an [`ExportedScene`] saying where, or why not. What is written is what
//! the extract step reads: the mesh entities that cast or are seen (with Bevy's
//! `NotShadowCaster` and `NotShadowReceiver` as sshc's `casts` and `receives`), placed in
//! world space (one GLB per kind of object, the triangles listed out), the first active
//! perspective camera (its position, view direction, up, vertical field of view, near
//! plane and target size; Bevy's far plane is at infinity, so the scene's far is fitted)
//! and the light carrying the enabled [`crate::SshcShadow`] (else any), as a distant disk
//! of the component's angular diameter.

use crate::SshcShadow;
use crate::render::convert_mesh;
use bevy::camera::{Camera, Projection};
use bevy::light::{NotShadowCaster, NotShadowReceiver};
use bevy::prelude::*;
use sshc_runtime::light::glam::Vec3 as SVec3;
use sshc_scene::{Camera as SceneCamera, Mesh as SceneMesh, Object, SceneDesc, ShadowFit, Transform as SceneTransform};
use std::path::{Path, PathBuf};

/// A request: write the scene into this folder (made when missing) in the next frame.
#[derive(Resource, Clone, Debug)]
pub struct ExportScene(pub PathBuf);

/// What the last [`ExportScene`] did: the scene file written, or why not.
#[derive(Resource, Clone, Debug)]
pub struct ExportedScene(pub Result<PathBuf, String>);

/// The objects' kinds, each written as one GLB: (file, casts, receives).
const KINDS: [(&str, bool, bool); 4] = [
    ("casts-receives.glb", true, true),
    ("casts.glb", true, false),
    ("receives.glb", false, true),
    ("seen.glb", false, false),
];

/// The mesh entities as the extract step reads them.
type MeshEntities<'w, 's> = Query<
    'w,
    's,
    (
        &'static Mesh3d,
        &'static GlobalTransform,
        &'static ViewVisibility,
        Has<NotShadowCaster>,
        Has<NotShadowReceiver>,
    ),
>;
type Cameras<'w, 's> = Query<'w, 's, (&'static Camera, &'static GlobalTransform, &'static Projection)>;
type Lights<'w, 's> = Query<'w, 's, (&'static SshcShadow, &'static GlobalTransform), With<DirectionalLight>>;

/// A kind's triangles and their corners' normals, in world space.
type Soup = (Vec<[SVec3; 3]>, Vec<[SVec3; 3]>);

/// The system behind [`ExportScene`] (in `Last`).
pub fn export_scene(
    mut commands: Commands,
    request: Option<Res<ExportScene>>,
    meshes: Res<Assets<Mesh>>,
    entities: MeshEntities,
    cameras: Cameras,
    lights: Lights,
) {
    let Some(request) = request else { return };
    let dir = request.0.clone();
    commands.remove_resource::<ExportScene>();
    let outcome = write_scene(&dir, &meshes, &entities, &cameras, &lights);
    match &outcome {
        Ok(p) => info!("sshc: the scene as shaded written to {}", p.display()),
        Err(e) => error!("sshc: the scene could not be written to {}: {e}", dir.display()),
    }
    commands.insert_resource(ExportedScene(outcome));
}

fn write_scene(dir: &Path, meshes: &Assets<Mesh>, entities: &MeshEntities, cameras: &Cameras, lights: &Lights) -> Result<PathBuf, String> {
    let camera = scene_camera(cameras)?;
    let (shadow, sun) = lights
        .iter()
        .find(|(s, _)| s.enabled)
        .or_else(|| lights.iter().next())
        .ok_or("no DirectionalLight carries an SshcShadow")?;
    let light = sshc_scene::Light::DistantDisk {
        direction: SVec3::from_array(sun.back().to_array()),
        angle_degrees: shadow.angular_diameter_degrees,
    };
    // each kind's triangles and corner normals, in world space
    let mut soups: [Soup; 4] = Default::default();
    for (mesh, transform, visible, no_cast, no_receive) in entities {
        // as the extract step: an entity neither seen nor casting is not in sshc's scene
        if !visible.get() && no_cast {
            continue;
        }
        let Some(kind) = KINDS.iter().position(|k| (k.1, k.2) == (!no_cast, !no_receive)) else {
            continue;
        };
        let m = meshes
            .get(mesh.0.id())
            .ok_or_else(|| format!("mesh {:?} is not in the main world (still loading?)", mesh.0.id()))
            .and_then(convert_mesh)?;
        let affine = transform.affine();
        let normal_matrix = affine.matrix3.inverse().transpose();
        let (tris, normals) = &mut soups[kind];
        for t in m.indices.chunks_exact(3) {
            let corner = |k: usize| SVec3::from_array(affine.transform_point3(Vec3::from_array(m.positions[t[k] as usize])).to_array());
            let normal = |k: usize| {
                let n = normal_matrix * Vec3::from_array(m.normals[t[k] as usize]);
                SVec3::from_array(n.normalize_or_zero().to_array())
            };
            tris.push([corner(0), corner(1), corner(2)]);
            normals.push([normal(0), normal(1), normal(2)]);
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut objects = Vec::new();
    for ((file, casts, receives), (tris, normals)) in KINDS.iter().zip(&soups) {
        if tris.is_empty() {
            continue;
        }
        let path = dir.join(file);
        std::fs::write(&path, sshc_scene::generate::soup_glb(tris, normals)).map_err(|e| format!("{}: {e}", path.display()))?;
        objects.push(Object {
            name: Some(file.trim_end_matches(".glb").into()),
            mesh: SceneMesh::Gltf { path: (*file).into() },
            transform: SceneTransform::default(),
            flat_normals: false,
            casts: *casts,
            receives: *receives,
        });
    }
    if objects.is_empty() {
        return Err("no mesh entity is in sshc's scene".into());
    }
    let scene = SceneDesc {
        camera,
        shadow_map: shadow.map_size.unwrap_or(crate::DEFAULT_MAP_SIZE),
        lights: vec![light],
        objects,
        shadow_fit: ShadowFit::Casters,
        cascades: None,
    };
    let text = ron::ser::to_string_pretty(&scene, ron::ser::PrettyConfig::default()).map_err(|e| e.to_string())?;
    let path = dir.join("scene.ron");
    let header = "// The scene a Bevy app shaded with sshc's shadows, written by bevy_sshc's ExportScene:\n// `sshc truth --scene` of this file gives the visibility at the app's pixels.\n";
    std::fs::write(&path, format!("{header}{text}\n")).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// The first active camera with a perspective projection, as sshc's scene camera.
fn scene_camera(cameras: &Cameras) -> Result<SceneCamera, String> {
    let (camera, transform, projection) = cameras
        .iter()
        .find(|(c, _, p)| c.is_active && matches!(p, Projection::Perspective(_)))
        .ok_or("no active camera with a perspective projection")?;
    let Projection::Perspective(p) = projection else {
        return Err("no perspective projection".into());
    };
    let size = camera
        .physical_target_size()
        .ok_or("the camera's target has no size yet (export a frame later)")?;
    let v = |v: Vec3| SVec3::from_array(v.to_array());
    let position = transform.translation();
    Ok(SceneCamera::Perspective {
        position: v(position),
        target: v(position + transform.forward().as_vec3()),
        up: v(transform.up().as_vec3()),
        fov_y_degrees: p.fov.to_degrees(),
        width: size.x,
        height: size.y,
        near: Some(p.near),
        far: None,
    })
}
