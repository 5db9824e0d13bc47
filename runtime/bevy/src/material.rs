//! The shadow term Bevy applies, made sshc's.
//!
//! Bevy 0.20 multiplies a directional light's contribution by its own shadow-map lookup
//! times `PbrInput::directional_shadow_factor`, and only where the light's shadow maps are
//! on. So, for the light carrying [`crate::SshcShadow`]:
//! - its receivers' `StandardMaterial` becomes [`SshcMaterial`]: the same material,
//!   extended with a fragment shader that sets the factor to sshc's visibility at the pixel
//!   (the swap is the plugin's: a receiver keeps its `StandardMaterial` in the scene);
//! - its shadow maps stay on, but no caster is drawn into them
//!   ([`clear_bevy_casters`]): Bevy's own lookup then gives 1, so the applied term is sshc's
//!   alone, and Bevy's shadow pass only clears its map.
//!
//! Where sshc cannot shade the light (its technique failed to load, a device feature is
//! missing), [`crate::render::Status`] holds the error: the casters stay and the visibility
//! image is left at 1, so Bevy's own shadow is what the receivers show.

use crate::render::Status;
use bevy::asset::RenderAssetUsages;
use bevy::camera::visibility::CascadesVisibleEntities;
use bevy::pbr::{ExtendedMaterial, MaterialExtension};
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::shader::ShaderRef;
use std::collections::HashMap;

/// The receivers' material: Bevy's `StandardMaterial` with sshc's visibility as its
/// directional shadow factor.
pub type SshcMaterial = ExtendedMaterial<StandardMaterial, SshcReceiver>;

/// The extension: the visibility image (sshc's, copied each frame).
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone, Default)]
pub struct SshcReceiver {
    #[texture(100, sample_type = "float", filterable = false)]
    pub visibility: Handle<Image>,
}

/// The receiver shader, registered at build.
pub const RECEIVER_SHADER: Handle<Shader> = bevy::asset::uuid_handle!("5d0c3f3a-6a1e-4b4e-9a3c-2f6e1b7d9c41");

impl MaterialExtension for SshcReceiver {
    fn fragment_shader() -> ShaderRef {
        RECEIVER_SHADER.into()
    }

    fn deferred_fragment_shader() -> ShaderRef {
        RECEIVER_SHADER.into()
    }
}

/// The visibility image: `R32Float` as sshc's, sampled by the receivers and copied into each
/// frame; 1 (unshadowed) until sshc first writes it.
pub fn visibility_image(width: u32, height: u32) -> Image {
    let mut image = Image::new_fill(
        Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        &1.0f32.to_le_bytes(),
        TextureFormat::R32Float,
        RenderAssetUsages::RENDER_WORLD | RenderAssetUsages::MAIN_WORLD,
    );
    // read by the receivers, copied into each frame, read back by a host that wants it
    image.texture_descriptor.usage = TextureUsages::TEXTURE_BINDING | TextureUsages::COPY_DST | TextureUsages::COPY_SRC;
    image
}

/// Each `StandardMaterial` already swapped, and its swap.
#[derive(Resource, Default)]
pub struct Swapped(HashMap<AssetId<StandardMaterial>, Handle<SshcMaterial>>);

/// Receivers of a light with sshc's shadow: their `StandardMaterial` is swapped for the same
/// material extended ([`SshcMaterial`]); a `StandardMaterial` changed later is carried over.
pub fn swap_materials(
    mut commands: Commands,
    mut swapped: ResMut<Swapped>,
    lights: Query<&crate::SshcShadow>,
    receivers: Query<(Entity, &MeshMaterial3d<StandardMaterial>), Without<bevy::light::NotShadowReceiver>>,
    standard: Res<Assets<StandardMaterial>>,
    mut events: MessageReader<AssetEvent<StandardMaterial>>,
    mut extended: ResMut<Assets<SshcMaterial>>,
) {
    let Some(shadow) = lights.iter().find(|s| s.enabled) else { return };
    for e in events.read() {
        if let AssetEvent::Modified { id } = e
            && let (Some(h), Some(base)) = (swapped.0.get(id), standard.get(*id))
            && let Some(mut m) = extended.get_mut(h)
        {
            m.base = base.clone();
        }
    }
    for (entity, material) in &receivers {
        let id = material.0.id();
        let Some(base) = standard.get(id) else { continue };
        let handle = swapped
            .0
            .entry(id)
            .or_insert_with(|| {
                extended.add(SshcMaterial {
                    base: base.clone(),
                    extension: SshcReceiver {
                        visibility: shadow.visibility.clone(),
                    },
                })
            })
            .clone();
        commands
            .entity(entity)
            .remove::<MeshMaterial3d<StandardMaterial>>()
            .insert(MeshMaterial3d(handle));
    }
}

/// The visibility image follows the camera's size (the receivers read it one texel per
/// pixel); the swapped materials are touched so that their bind groups take the new image.
/// Where sshc stops shading the light, the image is made again at 1, so that Bevy's own
/// shadow (its casters back in its maps) is all the receivers show.
pub fn size_visibility(
    lights: Query<(Entity, &crate::SshcShadow)>,
    cameras: Query<(Entity, &Camera), With<Camera3d>>,
    status: Res<Status>,
    mut reset: Local<bool>,
    mut images: ResMut<Assets<Image>>,
    mut extended: ResMut<Assets<SshcMaterial>>,
) {
    let Some((light, shadow)) = lights.iter().find(|(_, s)| s.enabled) else {
        return;
    };
    let Some(size) = crate::render::shaded_camera(cameras.iter()).and_then(|(_, c)| c.physical_viewport_size()) else {
        return;
    };
    let current = images.get(&shadow.visibility).map(|i| (i.width(), i.height()));
    let failed = status.error(light).is_some();
    let cleared = failed && !std::mem::replace(&mut *reset, true);
    if !failed {
        *reset = false;
    }
    if cleared || current != Some((size.x, size.y)) {
        let _ = images.insert(&shadow.visibility, visibility_image(size.x, size.y));
        let ids: Vec<_> = extended.ids().collect();
        for id in ids {
            let _ = extended.get_mut(id);
        }
    }
}

/// For the light with sshc's shadow, when sshc runs for it: no caster in Bevy's own shadow
/// maps (they stay on, so that Bevy applies the receivers' factor, and hold nothing).
pub fn clear_bevy_casters(status: Res<Status>, mut lights: Query<(Entity, &crate::SshcShadow, &mut CascadesVisibleEntities)>) {
    for (entity, shadow, mut visible) in &mut lights {
        if !shadow.enabled || shadow.keep_bevy_shadow || status.error(entity).is_some() {
            continue;
        }
        for cascades in visible.entities.values_mut() {
            for cascade in cascades {
                cascade.entities.clear();
            }
        }
    }
}
