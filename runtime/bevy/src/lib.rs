//! sshc's soft shadows in Bevy 0.20: any compiled technique as a directional light's
//! shadow (docs/bevy.md).
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_sshc::{SshcShadow, SshcShadowsPlugin};
//! fn setup(mut commands: Commands, assets: Res<AssetServer>, mut images: ResMut<Assets<Image>>) {
//!     commands.spawn((
//!         DirectionalLight { shadow_maps_enabled: true, ..default() },
//!         Transform::from_xyz(1.0, 3.0, 2.0).looking_at(Vec3::ZERO, Vec3::Y),
//!         SshcShadow::new(assets.load("techniques/pcss.ron"), &mut images),
//!     ));
//! }
//! ```
//!
//! The stages, as sshc's runtime has them (docs/embedding.md): the technique is an asset
//! (compiled when loaded, again when its file changes), the scene is uploaded once and
//! changed in place as entities spawn and despawn, the targets are per camera view, and
//! each frame is extract (Bevy's `ExtractSchedule`), prepare (`RenderSystems::Prepare`)
//! and record (the `Core3d` schedule, before the main pass).

mod asset;
mod export;
mod material;
mod render;

pub use asset::{MAX_TECHNIQUE_BYTES, SshcTechnique, TechniqueError, TechniqueLoader, compile};
pub use export::{ExportScene, ExportedScene};
pub use material::{SshcMaterial, SshcReceiver, visibility_image};
pub use render::{CpuTimes, DEFAULT_MAP_SIZE, Status, convert_mesh};
pub use sshc_runtime;

use bevy::asset::AssetApp;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::light::SimulationLightSystems;
use bevy::pbr::MaterialPlugin;
use bevy::prelude::*;
use bevy::render::renderer::{RenderAdapter, RenderDevice, RenderQueue};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderSystems};

/// sshc's shadow for a `DirectionalLight`: the technique, its params, its shadow map's size
/// and the sun's angular size (sshc's distant-disk light).
#[derive(Component, Clone, Debug)]
#[require(DirectionalLight)]
pub struct SshcShadow {
    /// A technique file loaded as an asset (`assets.load("techniques/pcss.ron")`).
    pub technique: Handle<SshcTechnique>,
    /// Params by name, set over the technique's defaults.
    pub params: Vec<(String, f64)>,
    /// The shadow map's texels per side; `None`: the technique's own `shadow_map:` (a
    /// `tuned.ron` from `sshc tune` carries its tuned size), else 1024.
    pub map_size: Option<u32>,
    /// The sun's full angular diameter in degrees (about 0.53 for the real sun).
    pub angular_diameter_degrees: f32,
    /// Off: Bevy's own shadow for this light, as if the component were absent.
    pub enabled: bool,
    /// For comparison only: keep Bevy's own casters in its shadow maps, so that the
    /// receivers show Bevy's shadow times sshc's, which is what
    /// `PbrInput::directional_shadow_factor` alone gives (docs/bevy.md, "The shadow term").
    pub keep_bevy_shadow: bool,
    /// The image sshc's visibility is copied into each frame, read by the receivers.
    pub visibility: Handle<Image>,
}

impl SshcShadow {
    /// A technique with its defaults: its own map size (else 1024^2) and a sun of 0.53
    /// degrees.
    pub fn new(technique: Handle<SshcTechnique>, images: &mut Assets<Image>) -> SshcShadow {
        SshcShadow {
            technique,
            params: Vec::new(),
            map_size: None,
            angular_diameter_degrees: 0.53,
            enabled: true,
            keep_bevy_shadow: false,
            visibility: images.add(visibility_image(1, 1)),
        }
    }
}

/// The plugin: the technique asset and its loader, the receivers' material, and sshc's
/// stages in the render world.
pub struct SshcShadowsPlugin;

impl Plugin for SshcShadowsPlugin {
    fn build(&self, app: &mut App) {
        let status = Status::default();
        let times = CpuTimes::default();
        app.init_asset::<SshcTechnique>()
            .register_asset_loader(TechniqueLoader)
            .add_plugins(MaterialPlugin::<SshcMaterial>::default())
            .init_resource::<material::Swapped>()
            .insert_resource(status.clone())
            .insert_resource(times.clone())
            .add_systems(
                PostUpdate,
                (
                    material::swap_materials,
                    material::size_visibility,
                    material::clear_bevy_casters.after(SimulationLightSystems::CheckLightVisibility),
                ),
            )
            .add_systems(Last, export::export_scene);
        let _ = app.world_mut().resource_mut::<Assets<Shader>>().insert(
            &material::RECEIVER_SHADER,
            Shader::from_wesl(include_str!("shaders/receiver.wesl"), "bevy_sshc/receiver.wesl"),
        );
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .insert_resource(status)
                .insert_resource(times)
                .init_resource::<render::Extracted>()
                .add_systems(ExtractSchedule, render::extract)
                .add_systems(Render, render::prepare.in_set(RenderSystems::Prepare))
                .add_systems(Core3d, render::record.after(Core3dSystems::Prepass).before(Core3dSystems::MainPass));
        }
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
        let world = render_app.world();
        let (Some(adapter), Some(device), Some(queue), Some(status)) = (
            world.get_resource::<RenderAdapter>(),
            world.get_resource::<RenderDevice>(),
            world.get_resource::<RenderQueue>(),
            world.get_resource::<Status>(),
        ) else {
            error!("sshc: the render world has no device: sshc's shadows are off");
            return;
        };
        let render = render::SshcRender::new(adapter, device, queue, status.clone());
        render_app.insert_resource(render);
    }
}
