//! From a [`Scene`] to the plain data the executor binds ([`SceneInputs`]).

use crate::scene::Scene;
use sshc_runtime::gpu::SceneInputs;

/// The scene's geometry, camera and first light, as the executor needs them.
pub fn scene_inputs(scene: &Scene) -> Result<SceneInputs, String> {
    let light = scene
        .lights
        .first()
        .ok_or_else(|| "the scene has no light: add one to `lights`".to_string())?;
    let v = light.view(scene.bounds());
    let cam = scene.camera_position();
    Ok(SceneInputs {
        vertices: scene.vertex_data(),
        // One mesh per object: Geometry passes find edges within each.
        meshes: (0..scene.objects().len())
            .map(|i| {
                let r = scene.object_triangles(i);
                r.start as u32..r.end as u32
            })
            .collect(),
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
    })
}
