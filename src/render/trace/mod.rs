//! The GPU photon tracer shared by the BVH techniques (AAPS and the photon map): the scene in
//! GPU buffers ([`scene`]: BVH, normals, materials, light table), its extraction and upload,
//! and the WGSL every tracer concatenates (`bvh.wgsl`, `optics.wgsl` and `surface.wgsl`: the
//! scene bindings, the light and material tables, surface normals, guarded reflection and
//! refraction, and photon emission from a light's parameter square).
//!
//! Render world only. The scene is uploaded once per scene generation while a camera uses a
//! BVH technique and dropped when none does.
//!
//! **Specialised tracers.** The trace pipelines are compiled for what the scene holds
//! ([`TraceFeatures`]): without a dielectric, the refraction, Fresnel split and Beer-Lambert
//! code is left out (shader def `TRACE_DIELECTRICS`); without a point or spot light, the
//! equal-area emission (`TRACE_POINT_LIGHTS`). A variant is queued the first time a scene needs
//! it ([`TraceVariants`]). [`TraceSpecialization`] (main world, default on) turns it off, so
//! every scene uses the variant with everything.

pub mod scene;

use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::render_resource::{
    CachedComputePipelineId, ComputePipelineDescriptor, PipelineCache,
};
use bevy::render::renderer::RenderDevice;
use bevy::render::{ExtractSchedule, MainWorld, Render, RenderApp, RenderSystems};
use bevy::shader::ShaderDefVal;

use crate::CausticsTechnique;
use crate::render::ExtractedCaustics;
use crate::scene::CausticsScene;
use scene::{ExtractedCausticsScene, TraceSceneBuffers};

/// The WGSL every photon tracer starts with: BVH traversal over the packed scene (bindings 0
/// to 2: nodes, triangles with normals, instances with materials), the optics twins and the
/// scene's surfaces and lights (binding 8).
pub fn tracer_source() -> String {
    [
        include_str!("../bvh.wgsl"),
        include_str!("../optics.wgsl"),
        include_str!("surface.wgsl"),
    ]
    .join("\n")
}

/// What a scene holds that the tracer's code depends on (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct TraceFeatures {
    /// Some caster is a dielectric: refraction, the Fresnel split, Beer-Lambert.
    pub dielectrics: bool,
    /// Some caustic light is a point or spot light: equal-area emission over the sphere.
    pub point_lights: bool,
    /// A photon reflected off a caster may meet a caster again (two casters, or one whose
    /// shape reflects onto itself: `MeshGeometry::reflects_onto_itself`): image space's trace
    /// then marches the casters' front layer after a reflection (`TRACE_CASTER_CHAINS`). The
    /// BVH tracers follow any chain without it (false in their scene).
    pub caster_chains: bool,
}

impl TraceFeatures {
    /// Everything (the unspecialised tracer).
    pub const ALL: Self = Self {
        dielectrics: true,
        point_lights: true,
        caster_chains: true,
    };

    /// The shader defs of this variant.
    pub fn shader_defs(self) -> Vec<ShaderDefVal> {
        let mut defs = Vec::new();
        if self.dielectrics {
            defs.push("TRACE_DIELECTRICS".into());
        }
        if self.point_lights {
            defs.push("TRACE_POINT_LIGHTS".into());
        }
        if self.caster_chains {
            defs.push("TRACE_CASTER_CHAINS".into());
        }
        defs
    }
}

/// Whether trace pipelines are specialised by the scene's [`TraceFeatures`] (main world;
/// default on). Off, every scene uses the tracer with everything: for measuring what
/// specialisation saves, and as an escape hatch.
#[derive(Resource, ExtractResource, Clone, Copy, Debug, Reflect)]
#[reflect(Resource, Clone)]
pub struct TraceSpecialization(pub bool);

impl Default for TraceSpecialization {
    fn default() -> Self {
        Self(true)
    }
}

/// The trace pipelines of one entry point, one per [`TraceFeatures`] variant a scene needed.
#[derive(Default)]
pub struct TraceVariants(HashMap<TraceFeatures, CachedComputePipelineId>);

impl TraceVariants {
    /// The pipeline for `features`, queued with `descriptor(shader defs)` the first time.
    pub fn get_or_queue(
        &mut self,
        features: TraceFeatures,
        cache: &PipelineCache,
        descriptor: impl FnOnce(Vec<ShaderDefVal>) -> ComputePipelineDescriptor,
    ) -> CachedComputePipelineId {
        *self
            .0
            .entry(features)
            .or_insert_with(|| cache.queue_compute_pipeline(descriptor(features.shader_defs())))
    }

    /// The pipeline for `features`, if queued.
    pub fn get(&self, features: TraceFeatures) -> Option<CachedComputePipelineId> {
        self.0.get(&features).copied()
    }
}

/// The variant the uploaded scene needs (everything when specialisation is off).
pub fn wanted_features(
    scene: &TraceSceneBuffers,
    specialization: Option<&TraceSpecialization>,
) -> TraceFeatures {
    if specialization.is_some_and(|s| !s.0) {
        TraceFeatures::ALL
    } else {
        scene.features
    }
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
    app.init_resource::<TraceSpecialization>()
        .register_type::<TraceSpecialization>()
        .add_plugins(ExtractResourcePlugin::<TraceSpecialization>::default());
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
