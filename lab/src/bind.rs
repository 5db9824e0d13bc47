//! From a [`Scene`] to the plain data the executor binds ([`SceneInputs`]).

use crate::scene::Scene;
use sshc_runtime::gpu::SceneInputs;

/// The scene's geometry, camera and first light, as the executor needs them.
///
/// The vertex buffer lists the objects that cast shadows first, in file order, then those
/// that do not (`casts: false`), in file order: the light's draws take only the first
/// `casting_vertices`, and the meshes whose edges Geometry passes extrude are the casters
/// only. With every object casting, the buffer is [`Scene::vertex_data`] as it is.
/// The light's view is fitted as the scene's `shadow_fit` says ([`Scene::light_view`]).
pub fn scene_inputs(scene: &Scene) -> Result<SceneInputs, String> {
    let light = scene
        .lights
        .first()
        .ok_or_else(|| "the scene has no light: add one to `lights`".to_string())?;
    let v = scene.light_view(light);
    let cam = scene.camera_position();
    let n = scene.objects().len();
    let order: Vec<usize> = (0..n)
        .filter(|&i| scene.casts(i))
        .chain((0..n).filter(|&i| !scene.casts(i)))
        .collect();
    // Built straight from the triangles: one copy of the geometry (1.2 GB at the scene
    // limit of 2^24 triangles), not a second for `Scene::vertex_data`'s order.
    let (tris, normals) = (scene.triangles(), scene.normals());
    let mut vertices = Vec::with_capacity(tris.len() * 18);
    // One mesh per casting object: Geometry passes find edges within each.
    let mut meshes = Vec::new();
    let mut casting = 0usize;
    for &i in &order {
        let r = scene.object_triangles(i);
        let start = vertices.len() / 18;
        for (tri, nrm) in tris[r.clone()].iter().zip(&normals[r]) {
            for k in 0..3 {
                vertices.extend_from_slice(&tri[k].to_array());
                vertices.extend_from_slice(&nrm[k].to_array());
            }
        }
        if scene.casts(i) {
            meshes.push(start as u32..(vertices.len() / 18) as u32);
            casting = vertices.len() / 6;
        }
    }
    if meshes.is_empty() {
        // no caster: an empty mesh (an empty list would mean one mesh of everything)
        meshes.push(0..0);
    }
    let every = casting == vertices.len() / 6;
    Ok(SceneInputs {
        vertices,
        meshes,
        casting_vertices: (!every).then_some(casting as u32),
        camera_view_proj: scene.camera_view_proj().to_cols_array(),
        camera_position: cam.to_array(),
        camera_size: scene.camera_size(),
        shadow_size: scene.shadow_map,
        light_view: v.view.to_cols_array(),
        light_view_proj: v.view_proj.to_cols_array(),
        light_position: v.position_or_direction.to_array(),
        near: v.near,
        far: v.far,
        light_size: v.size,
        light_half_extents: v.half_extents.to_array(),
        light_angle: v.angle,
        light_proj_y: v.proj.y_axis.y,
        light_orthographic: v.orthographic,
        samples: Vec::new(),
        samples_closed: false,
    })
}
