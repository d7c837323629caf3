//! The GPU photon tracer shared by the BVH techniques (AAPS and the photon map): the scene in
//! GPU buffers ([`scene`]: BVH, normals, materials, light table), its extraction and upload,
//! and the WGSL every tracer concatenates (`bvh.wgsl`, `optics.wgsl` and `surface.wgsl`: the
//! scene bindings, the light and material tables, surface normals, guarded reflection and
//! refraction, and photon emission from a light's parameter square).
//!
//! Render world only. The scene is uploaded once per scene generation while a camera uses a
//! BVH technique and dropped when none does.

pub mod scene;

use bevy::prelude::*;
use bevy::render::renderer::RenderDevice;
use bevy::render::{ExtractSchedule, MainWorld, Render, RenderApp, RenderSystems};

use crate::CausticsTechnique;
use crate::render::ExtractedCaustics;
use crate::scene::CausticsScene;
use scene::{ExtractedCausticsScene, TraceSceneBuffers};

/// The WGSL every photon tracer starts with: BVH traversal (bindings 0 to 4), the optics twins
/// and the scene's surfaces and lights (bindings 5, 6 and 8).
pub fn tracer_source() -> String {
    [
        include_str!("../bvh.wgsl"),
        include_str!("../optics.wgsl"),
        include_str!("surface.wgsl"),
    ]
    .join("\n")
}

/// Whether a camera with `technique` traces photons through the BVH.
pub fn uses_bvh(technique: CausticsTechnique) -> bool {
    matches!(
        technique,
        CausticsTechnique::Aaps | CausticsTechnique::PhotonMap
    )
}

fn extract_scene(
    mut commands: Commands,
    main: Res<MainWorld>,
    current: Option<Res<ExtractedCausticsScene>>,
) {
    let Some(scene) = main.get_resource::<CausticsScene>() else {
        return;
    };
    if current.is_some_and(|c| c.0.generation == scene.generation) {
        return;
    }
    commands.insert_resource(ExtractedCausticsScene(scene.clone()));
}

/// Upload the scene when it changed and a view uses a BVH technique; drop it when none does.
pub fn prepare_trace_scene(
    mut commands: Commands,
    device: Res<RenderDevice>,
    extracted: Option<Res<ExtractedCausticsScene>>,
    buffers: Option<Res<TraceSceneBuffers>>,
    views: Query<&ExtractedCaustics>,
    // The last generation found to have nothing to trace (no light reaches a caster).
    mut idle: Local<Option<u64>>,
) {
    let wanted = views.iter().any(|c| uses_bvh(c.technique));
    let Some(extracted) = extracted.filter(|_| wanted) else {
        if buffers.is_some() {
            commands.remove_resource::<TraceSceneBuffers>();
        }
        *idle = None;
        return;
    };
    // Everything below runs once per scene generation, not per frame.
    let generation = extracted.0.generation;
    if buffers.as_ref().is_some_and(|b| b.generation == generation) || *idle == Some(generation) {
        return;
    }
    match TraceSceneBuffers::upload(&device, &extracted.0) {
        Some(b) => {
            commands.insert_resource(b);
            *idle = None;
        }
        None => {
            if buffers.is_some() {
                commands.remove_resource::<TraceSceneBuffers>();
            }
            *idle = Some(generation);
        }
    }
}

/// Render-app part: the scene's extraction (used by every GPU technique) and upload.
pub(crate) fn build(app: &mut App) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(ExtractSchedule, extract_scene)
        .add_systems(
            Render,
            prepare_trace_scene
                .in_set(RenderSystems::PrepareResources)
                .after(super::prepare_caustics_buffers),
        );
}
