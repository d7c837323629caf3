//! The AAPS pipelines: one compute module (the shared tracer's WGSL, quadtree, trace and
//! task-buffer entry points, concatenated from the WGSL files beside this one and in
//! `src/render/`) and
//! the splat raster module; created in `RenderStartup`.

use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, BlendComponent, BlendFactor, BlendOperation,
    BlendState, CachedComputePipelineId, CachedRenderPipelineId, ColorTargetState, ColorWrites,
    ComputePipelineDescriptor, FragmentState, MultisampleState, PipelineCache,
    RenderPipelineDescriptor, ShaderStages, TextureSampleType, VertexState, binding_types,
};
use bevy::shader::Shader;

use crate::render::CAUSTICS_BUFFER_FORMAT;

/// The WGSL of the compute module.
pub fn compute_source() -> String {
    [
        crate::render::trace::tracer_source().as_str(),
        include_str!("../quadtree.wgsl"),
        include_str!("params.wgsl"),
        include_str!("common.wgsl"),
        include_str!("trace.wgsl"),
        include_str!("task.wgsl"),
    ]
    .join("\n")
}

/// The WGSL of the splat module (with the fixed-point fallback's entry point).
pub fn splat_source() -> String {
    [
        include_str!("params.wgsl"),
        include_str!("../optics.wgsl"),
        crate::render::fixed_splat::fragment_source(),
        include_str!("splat.wgsl"),
    ]
    .join("\n")
}

/// Shader handles, added to `Assets<Shader>` by the plugin.
#[derive(Resource, Clone)]
pub struct AapsShaders {
    /// Compute module.
    pub compute: Handle<Shader>,
    /// Splat module.
    pub splat: Handle<Shader>,
}

/// Layouts and pipeline ids.
#[derive(Resource)]
pub struct AapsPipelines {
    /// Group 0 of the compute passes but the trace (no scene).
    pub compute_layout: BindGroupLayoutDescriptor,
    /// Group 0 of the trace: the packed scene, the quadtree, the splats and the counters (7
    /// storage buffers).
    pub trace_layout: BindGroupLayoutDescriptor,
    /// Group 1 (indirect arguments) of the argument writers.
    pub args_layout: BindGroupLayoutDescriptor,
    /// Group 0 of the splat passes.
    pub splat_layout: BindGroupLayoutDescriptor,
    /// [`COMPUTE_ENTRIES`], in order.
    pub compute: [CachedComputePipelineId; 7],
    /// Plain splats.
    pub splat: CachedRenderPipelineId,
    /// Small splats, 4x MSAA, per-sample shading (when the adapter can multisample and
    /// resolve `Rgba32Float`).
    pub splat_msaa: Option<CachedRenderPipelineId>,
    /// `trace`, specialised by the scene's features (`render::trace`), queued by
    /// `queue_aaps_trace_variant` the first time a scene needs the variant (no frame traces
    /// before it is compiled).
    pub trace: crate::render::trace::TraceVariants,
}

/// The `trace` pipeline for `features`.
pub fn trace_descriptor(
    layout: &BindGroupLayoutDescriptor,
    shader: &Handle<Shader>,
    shader_defs: Vec<bevy::shader::ShaderDefVal>,
) -> ComputePipelineDescriptor {
    ComputePipelineDescriptor {
        label: Some("caustics:pipeline:aaps_trace".into()),
        layout: vec![layout.clone()],
        shader: shader.clone(),
        shader_defs,
        entry_point: Some("trace".into()),
        ..default()
    }
}

/// Queue the `trace` variant the uploaded scene needs (in `PrepareResources`).
pub(crate) fn queue_aaps_trace_variant(
    mut pipelines: ResMut<AapsPipelines>,
    shaders: Res<AapsShaders>,
    cache: Res<PipelineCache>,
    scene: Option<Res<crate::render::trace::scene::TraceSceneBuffers>>,
    specialization: Option<Res<crate::render::trace::TraceSpecialization>>,
) {
    let Some(scene) = scene else {
        return;
    };
    let features = crate::render::trace::wanted_features(&scene, specialization.as_deref());
    let layout = pipelines.trace_layout.clone();
    pipelines.trace.get_or_queue(features, &cache, |defs| {
        trace_descriptor(&layout, &shaders.compute, defs)
    });
}

/// Entry points of [`AapsPipelines::compute`], in order.
pub const COMPUTE_ENTRIES: [&str; 7] = [
    "qt_leaves",
    "qt_reduce",
    "write_trace_args",
    "write_draw_args",
    "variance",
    "density_update",
    "density_scale",
];

pub(super) fn init_aaps_pipelines(
    mut commands: Commands,
    shaders: Res<AapsShaders>,
    cache: Res<PipelineCache>,
    support: Res<super::AapsSupport>,
) {
    use binding_types::*;
    let ro = || storage_buffer_read_only_sized(false, None);
    let rw = || storage_buffer_sized(false, None);
    let tex = || texture_2d(TextureSampleType::Float { filterable: false });
    // Two layouts, so every pipeline binds at most 8 storage buffers per stage (WebGPU's
    // default): the task buffer, variance and density passes bind no scene; the trace binds
    // the scene and what it writes.
    let compute_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:aaps",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (7, rw()),
                (9, uniform_buffer_sized(false, None)),
                (10, rw()),
                (11, rw()),
                (12, rw()),
                (13, rw()),
                (14, tex()),
                (15, tex()),
                (16, uniform_buffer_sized(true, None)),
            ),
        ),
    );
    let trace_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:aaps_trace",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, ro()),
                (1, ro()),
                (2, ro()),
                (7, rw()),
                (8, ro()),
                (9, uniform_buffer_sized(false, None)),
                (10, rw()),
                (11, rw()),
            ),
        ),
    );
    let args_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:aaps_args",
        &BindGroupLayoutEntries::sequential(ShaderStages::COMPUTE, (rw(),)),
    );
    let splat_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:aaps_splat",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer_sized(false, None),
                ro(),
                texture_depth_2d(),
                uniform_buffer_sized(false, None),
            ),
        ),
    );
    let compute = COMPUTE_ENTRIES.map(|entry| {
        let mut layout = vec![compute_layout.clone()];
        if entry.starts_with("write_") {
            layout.push(args_layout.clone());
        }
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(format!("caustics:pipeline:aaps_{entry}").into()),
            layout,
            shader: shaders.compute.clone(),
            entry_point: Some(entry.into()),
            ..default()
        })
    });
    let add = BlendComponent {
        src_factor: BlendFactor::One,
        dst_factor: BlendFactor::One,
        operation: BlendOperation::Add,
    };
    // Without FLOAT32_BLENDABLE the plain splats add into fixed-point atomics (group 1) and
    // write nothing to the target (`render::fixed_splat`).
    let (layout, blend, write_mask) = if support.fixed {
        (
            vec![
                splat_layout.clone(),
                crate::render::fixed_splat::fragment_layout(),
            ],
            None,
            ColorWrites::empty(),
        )
    } else {
        (
            vec![splat_layout.clone()],
            Some(BlendState {
                color: add,
                alpha: add,
            }),
            ColorWrites::ALL,
        )
    };
    let raster = |label: &'static str, vs: &'static str, fs: &'static str, samples: u32| {
        cache.queue_render_pipeline(RenderPipelineDescriptor {
            label: Some(label.into()),
            layout: layout.clone(),
            vertex: VertexState {
                shader: shaders.splat.clone(),
                entry_point: Some(vs.into()),
                ..default()
            },
            fragment: Some(FragmentState {
                shader: shaders.splat.clone(),
                entry_point: Some(fs.into()),
                targets: vec![Some(ColorTargetState {
                    format: CAUSTICS_BUFFER_FORMAT,
                    blend,
                    write_mask,
                })],
                ..default()
            }),
            multisample: MultisampleState {
                count: samples,
                ..default()
            },
            ..default()
        })
    };
    let fs_big = if support.fixed {
        "fs_big_fixed"
    } else {
        "fs_big"
    };
    let splat = raster("caustics:pipeline:aaps_splat", "vs_big", fs_big, 1);
    let splat_msaa = support.msaa.then(|| {
        raster(
            "caustics:pipeline:aaps_splat_msaa",
            "vs_small",
            "fs_small",
            4,
        )
    });
    commands.insert_resource(AapsPipelines {
        compute_layout,
        trace_layout,
        args_layout,
        splat_layout,
        compute,
        splat,
        splat_msaa,
        trace: Default::default(),
    });
}
