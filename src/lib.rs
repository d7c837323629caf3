//! # bevy_caustics
//!
//! Physically calibrated real-time caustics for Bevy 0.19: light focused by glass, water and
//! mirrors onto diffuse surfaces, in the light's own units (lux for Bevy lights).
//!
//! ```ignore
//! app.add_plugins((DefaultPlugins, CausticsPlugin::default()));
//! commands.spawn((Camera3d::default(), Caustics::default()));
//! commands.spawn((DirectionalLight::default(), CausticLight::default()));
//! // glTF glass (KHR_materials_transmission) and mirrors (metallic, smooth) cast caustics as
//! // they are; `CausticMaterial` overrides the guess.
//! ```
//!
//! A frame: the main world validates the components, gathers casters and receivers into a
//! CPU BVH (on change only) and runs the camera's technique; the render world keeps a
//! per-view caustics buffer of irradiance and the composite pass adds
//! `albedo / π · E · exposure` into the deferred-lit HDR image. A scene without a
//! [`CausticLight`] or without a caster dispatches nothing.
//!
//! The optics core ([`optics`]) holds every formula once, in plain Rust on glam.

#![warn(missing_docs)]

pub mod components;
#[cfg(feature = "tools")]
pub mod headless;
#[cfg(feature = "inspector")]
pub mod inspector;
pub mod limits;
pub mod optics;
#[cfg(feature = "tools")]
pub mod reference;
pub mod render;
pub mod scene;
#[cfg(feature = "tools")]
pub mod scenes;
pub mod volume;

use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::render::render_resource::{DownlevelFlags, WgpuLimits as Limits};
use bevy::render::renderer::{RenderAdapter, RenderDevice};

pub use components::validate::CausticsWarnings;
pub use components::{
    AapsSettings, CausticLight, CausticMaterial, Caustics, CausticsDebugView, CausticsQuality,
    CausticsStereo, CausticsTechnique, CausticsVolume, CausticsVolumeGizmos, ImageSpaceSettings,
    PhotonMapSettings, StereoEye, VolumeFace, mark_every_light,
};
#[cfg(feature = "inspector")]
pub use inspector::CausticsInspectorPlugin;
pub use limits::CausticsLimits;
pub use render::{CausticImage, CausticsCpuImage, CausticsDispatchLog};

/// Everything a user needs.
pub mod prelude {
    pub use crate::{
        AapsSettings, CausticLight, CausticMaterial, Caustics, CausticsDebugView, CausticsPlugin,
        CausticsQuality, CausticsStereo, CausticsTechnique, CausticsVolume, CausticsVolumeGizmos,
        ImageSpaceSettings, PhotonMapSettings, StereoEye, VolumeFace,
    };
}

/// The plugin's main-world system sets, chained in `PostUpdate` after transform propagation.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum CausticsSystems {
    /// Clamp invalid component values (with a warning).
    Validate,
    /// Gather casters, receivers and lights; rebuild BVHs on change.
    Gather,
    /// Run the cameras' techniques' main-world parts.
    Technique,
}

/// Adds caustics to cameras with [`Caustics`].
///
/// The composite adds caustic light to the deferred G-buffer's receivers, so the plugin makes
/// [`OpaqueRendererMethod::Deferred`](bevy::material::OpaqueRendererMethod::Deferred) the app's default
/// opaque method ([`DefaultOpaqueRendererMethod`]) when it is added, with one `info!` if it
/// replaces Bevy's forward default. To keep forward rendering, insert
/// `DefaultOpaqueRendererMethod::forward()` *after* adding the plugin: receivers rendered
/// forward (by that default, by their material's `opaque_render_method`, or by a blended
/// `alpha_mode`) get no caustic, and each one a caustics camera sees is named in one `warn!`.
#[derive(Default)]
pub struct CausticsPlugin;

/// Make deferred the default opaque method unless the app has chosen one (see
/// [`CausticsPlugin`]).
fn default_to_deferred(app: &mut App) {
    let world = app.world_mut();
    match world.get_resource_mut::<DefaultOpaqueRendererMethod>() {
        None => world.insert_resource(DefaultOpaqueRendererMethod::deferred()),
        Some(mut method) if scene::forward::is_forward_default(&method) => {
            method.set_to_deferred();
            info!(
                "bevy_caustics: the default opaque render method is now Deferred (caustics are \
                 composited onto the deferred G-buffer); insert \
                 DefaultOpaqueRendererMethod::forward() after CausticsPlugin to keep Forward"
            );
        }
        Some(_) => {}
    }
}

/// Whether the GPU supports the plugin; set in `Plugin::finish`.
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub enum CausticsSupport {
    /// Everything needed is there.
    Supported,
    /// Disabled; the missing features and limits.
    Unsupported(Vec<String>),
}

/// What the plugin needs of the GPU, as a list of what is missing.
pub fn missing_gpu_capabilities(flags: DownlevelFlags, limits: &Limits) -> Vec<String> {
    let mut missing = Vec::new();
    if !flags.contains(DownlevelFlags::COMPUTE_SHADERS) {
        missing.push("DownlevelFlags::COMPUTE_SHADERS".to_string());
    }
    if limits.max_storage_buffers_per_shader_stage < 8 {
        missing.push(format!(
            "max_storage_buffers_per_shader_stage >= 8 (have {})",
            limits.max_storage_buffers_per_shader_stage
        ));
    }
    if limits.max_storage_textures_per_shader_stage < 1 {
        missing.push("max_storage_textures_per_shader_stage >= 1 (have 0)".to_string());
    }
    missing
}

impl Plugin for CausticsPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<Caustics>()
            .register_type::<AapsSettings>()
            .register_type::<ImageSpaceSettings>()
            .register_type::<PhotonMapSettings>()
            .register_type::<CausticsStereo>()
            .register_type::<CausticLight>()
            .register_type::<CausticMaterial>()
            .register_type::<CausticsVolume>()
            .register_type::<CausticsVolumeGizmos>()
            .configure_sets(
                PostUpdate,
                (
                    CausticsSystems::Validate,
                    CausticsSystems::Gather,
                    CausticsSystems::Technique,
                )
                    .chain()
                    .after(bevy::transform::TransformSystems::Propagate),
            )
            .init_resource::<render::CausticsDispatchLog>();
        default_to_deferred(app);
        components::validate::plugin(app);
        app.add_plugins(scene::ScenePlugin)
            .add_systems(Update, volume::volumes_from_gltf);
    }

    fn finish(&self, app: &mut App) {
        let missing = match app.get_sub_app(RenderApp) {
            Some(render_app) => {
                let world = render_app.world();
                match (
                    world.get_resource::<RenderAdapter>(),
                    world.get_resource::<RenderDevice>(),
                ) {
                    (Some(adapter), Some(device)) => missing_gpu_capabilities(
                        adapter.get_downlevel_capabilities().flags,
                        &device.limits(),
                    ),
                    _ => vec!["a render device (the RenderPlugin is not initialised)".to_string()],
                }
            }
            None => vec!["the RenderApp (add DefaultPlugins or RenderPlugin)".to_string()],
        };
        if !missing.is_empty() {
            warn!(
                "bevy_caustics disabled: the GPU lacks {}",
                missing.join(", ")
            );
            app.insert_resource(CausticsSupport::Unsupported(missing));
            return;
        }
        app.insert_resource(CausticsSupport::Supported);
        // The device's maxima, once: the main world validates against them, the render world
        // sizes its buffers by them.
        if let Some(render_app) = app.get_sub_app_mut(RenderApp)
            && let Some(device) = render_app.world().get_resource::<RenderDevice>()
        {
            let limits = CausticsLimits::new(&device.limits());
            render_app.insert_resource(limits.clone());
            app.insert_resource(limits);
        }
        #[cfg(feature = "tools")]
        reference::technique::plugin(app);
        let log = app
            .world()
            .resource::<render::CausticsDispatchLog>()
            .clone();
        render::build(app, log);
    }
}
