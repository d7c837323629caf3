//! The photon map's pipelines: the tracer module (the shared tracer's WGSL, photon.wgsl,
//! trace.wgsl, the G-buffer decoder and gather.wgsl: entry points `pm_trace` and `pm_gather`) and the grid module (photon.wgsl + grid.wgsl), queued when a camera first uses
//! the technique.

use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedComputePipelineId,
    ComputePipelineDescriptor, PipelineCache, ShaderStages, StorageTextureAccess,
    TextureSampleType, binding_types,
};
use bevy::shader::Shader;

use crate::optics::SCAN_BLOCK;
use crate::render::CAUSTICS_BUFFER_FORMAT;
use crate::render::photon_groups;

/// The WGSL of the tracer module (trace and gather).
pub fn compute_source() -> String {
    [
        crate::render::trace::tracer_source().as_str(),
        include_str!("photon.wgsl"),
        include_str!("trace.wgsl"),
        include_str!("../gbuffer.wgsl"),
        include_str!("gather.wgsl"),
    ]
    .join("\n")
}

/// The WGSL of the grid-build module.
pub fn grid_source() -> String {
    [include_str!("photon.wgsl"), include_str!("grid.wgsl")].join("\n")
}

/// The grid build's entry points, in the order they run.
pub const GRID_ENTRIES: [&str; 7] = [
    "grid_bounds",
    "grid_setup",
    "grid_count",
    "grid_scan_blocks",
    "grid_scan_top",
    "grid_scan_add",
    "grid_scatter",
];

/// The workgroups of each [`GRID_ENTRIES`] dispatch for a photon buffer of `capacity` and a
/// cell array of `cell_words` words (the budget + 1). Shared by the plugin and the exactness
/// test, so both run the same build.
pub fn grid_dispatches(capacity: u32, cell_words: u32) -> [[u32; 3]; 7] {
    let photons = photon_groups(capacity);
    let blocks = cell_words.div_ceil(SCAN_BLOCK).max(1);
    [
        photons,
        [1, 1, 1],
        photons,
        [blocks, 1, 1],
        [1, 1, 1],
        [blocks, 1, 1],
        photons,
    ]
}

/// Shader handles, added to `Assets<Shader>` by the plugin.
#[derive(Resource, Clone)]
pub struct PhotonMapShaders {
    /// Trace and gather.
    pub compute: Handle<Shader>,
    /// Grid build.
    pub grid: Handle<Shader>,
}

/// Layouts and pipeline ids.
#[derive(Resource)]
pub struct PhotonMapPipelines {
    /// Group 0 of `pm_trace`.
    pub trace_layout: BindGroupLayoutDescriptor,
    /// Group 0 of `pm_gather`.
    pub gather_layout: BindGroupLayoutDescriptor,
    /// Group 0 of the grid build.
    pub grid_layout: BindGroupLayoutDescriptor,
    /// `pm_trace`, specialised by the scene's features (`render::trace`), queued by
    /// `queue_photon_map_trace_variant`.
    pub trace: crate::render::trace::TraceVariants,
    /// `pm_gather`.
    pub gather: CachedComputePipelineId,
    /// The grid build, in [`GRID_ENTRIES`] order.
    pub grid: [CachedComputePipelineId; 7],
}

/// Queue the pipelines the first time a camera uses the photon map (in `PrepareResources`):
/// an app that never does compiles none of them (lavapipe's compiler takes seconds for the
/// tracer module, and every app start paid it before).
pub(crate) fn queue_photon_map_pipelines(
    mut commands: Commands,
    shaders: Res<PhotonMapShaders>,
    cache: Res<PipelineCache>,
    existing: Option<Res<PhotonMapPipelines>>,
    views: Query<&crate::render::ExtractedCaustics>,
) {
    if existing.is_some()
        || !views
            .iter()
            .any(|c| c.technique == crate::CausticsTechnique::PhotonMap)
    {
        return;
    }
    use binding_types::*;
    let ro = || storage_buffer_read_only_sized(false, None);
    let rw = || storage_buffer_sized(false, None);
    // Two layouts of at most 8 storage buffers (WebGPU's default per stage): the trace binds
    // the packed scene with its lights and writes the photons; the gather binds the scene
    // without lights (it follows mirror reflections) and the grid.
    let trace_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:photon_map_trace",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, ro()),
                (1, ro()),
                (2, ro()),
                (8, ro()),
                (9, uniform_buffer_sized(false, None)),
                (10, rw()),
                (11, rw()),
            ),
        ),
    );
    let gather_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:photon_map_gather",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, ro()),
                (1, ro()),
                (2, ro()),
                (9, uniform_buffer_sized(false, None)),
                (11, rw()),
                (12, ro()),
                (13, ro()),
                (14, rw()),
                (15, texture_depth_2d()),
                (16, texture_2d(TextureSampleType::Uint)),
                (
                    17,
                    texture_storage_2d(CAUSTICS_BUFFER_FORMAT, StorageTextureAccess::WriteOnly),
                ),
                (18, ro()),
            ),
        ),
    );
    let grid_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:photon_map_grid",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, None),
                ro(),
                rw(),
                rw(),
                rw(),
                rw(),
                rw(),
            ),
        ),
    );
    let queue =
        |entry: &'static str, layout: &BindGroupLayoutDescriptor, shader: &Handle<Shader>| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(format!("caustics:pipeline:photon_map_{entry}").into()),
                layout: vec![layout.clone()],
                shader: shader.clone(),
                entry_point: Some(entry.into()),
                ..default()
            })
        };
    let gather = queue("pm_gather", &gather_layout, &shaders.compute);
    let grid = GRID_ENTRIES.map(|e| queue(e, &grid_layout, &shaders.grid));
    commands.insert_resource(PhotonMapPipelines {
        trace_layout,
        gather_layout,
        grid_layout,
        trace: Default::default(),
        gather,
        grid,
    });
}

/// Queue the `pm_trace` variant the uploaded scene needs (in `PrepareResources`).
pub(crate) fn queue_photon_map_trace_variant(
    pipelines: Option<ResMut<PhotonMapPipelines>>,
    shaders: Res<PhotonMapShaders>,
    cache: Res<PipelineCache>,
    scene: Option<Res<crate::render::trace::scene::TraceSceneBuffers>>,
    specialization: Option<Res<crate::render::trace::TraceSpecialization>>,
) {
    let (Some(mut pipelines), Some(scene)) = (pipelines, scene) else {
        return;
    };
    let features = crate::render::trace::wanted_features(&scene, specialization.as_deref());
    let layout = pipelines.trace_layout.clone();
    pipelines
        .trace
        .get_or_queue(features, &cache, |shader_defs| ComputePipelineDescriptor {
            label: Some("caustics:pipeline:photon_map_pm_trace".into()),
            layout: vec![layout],
            shader: shaders.compute.clone(),
            shader_defs,
            entry_point: Some("pm_trace".into()),
            ..default()
        });
}
