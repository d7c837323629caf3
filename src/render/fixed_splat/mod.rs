//! Additive splats without float blending, shared by AAPS and the volumes.
//!
//! Both techniques add their splats into an `Rgba32Float` target with additive blending, which
//! needs the optional feature `FLOAT32_BLENDABLE` (absent on some WebGPU adapters). Without it
//! they fall back to this: the splat's fragment adds its irradiance to a per-pixel 64-bit
//! fixed-point accumulator with `u32` atomics (`fixed_splat.wgsl`, group 1 of the splat
//! pipeline, fragment stage), and one compute pass (`resolve.wgsl`) writes the sums back over
//! the target as floats. The words are image space's photon-map words
//! ([`crate::optics::fixed_point_word`] at
//! [`crate::optics::FIXED_POINT_SCALE`], rounded to nearest; the sum's value is
//! [`crate::optics::fixed_point_value`]). Integer sums are exact and independent
//! of the order fragments run in; the only error is each fragment's rounding to 1/512 lux. A
//! fragment above 1.7e7 lux is clamped there.
//!
//! Cost: 24 bytes per pixel for the accumulator, a buffer clear and one resolve dispatch per
//! frame, and an atomic add per channel and fragment instead of a blend.

use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer,
    BufferDescriptor, BufferUsages, CachedComputePipelineId, ComputePassDescriptor,
    ComputePipelineDescriptor, PipelineCache, ShaderStages, StorageTextureAccess, TextureView,
    WgpuFeatures, binding_types,
};
use bevy::render::renderer::{RenderContext, RenderDevice};
use bevy::render::{RenderApp, RenderStartup};
use bevy::shader::Shader;

use crate::render::CAUSTICS_BUFFER_FORMAT;

/// Bytes of the accumulator per pixel: a low and a high `u32` word per channel.
pub const FIXED_BYTES_PER_PIXEL: u64 = 24;

/// Whether the splats of this device use fixed-point atomics (render world): true when the
/// device lacks `FLOAT32_BLENDABLE`.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FixedSplats(pub bool);

/// The fallback's layouts and resolve pipeline (render world, only when [`FixedSplats`] is on).
#[derive(Resource)]
pub struct FixedSplatPipelines {
    /// Group 1 of a fixed-point splat pipeline: the accumulator, fragment stage.
    pub fragment_layout: BindGroupLayoutDescriptor,
    /// The resolve's group 0.
    pub resolve_layout: BindGroupLayoutDescriptor,
    /// The resolve pipeline.
    pub resolve: CachedComputePipelineId,
}

/// The WGSL a splat module concatenates (after optics.wgsl) for its fixed-point entry points.
pub fn fragment_source() -> &'static str {
    include_str!("fixed_splat.wgsl")
}

/// Decide whether the device needs the fallback; when it does, compile the resolve at
/// `RenderStartup`. Called from [`crate::render::build`] before the techniques.
pub(crate) fn build(app: &mut App) {
    let Some(render_app) = app.get_sub_app(RenderApp) else {
        return;
    };
    let Some(device) = render_app.world().get_resource::<RenderDevice>() else {
        return;
    };
    let fixed = !device.features().contains(WgpuFeatures::FLOAT32_BLENDABLE);
    if fixed {
        warn!(
            "bevy_caustics: the GPU lacks Features::FLOAT32_BLENDABLE; AAPS and volume splats add into fixed-point atomics instead of blending (same result, 24 bytes per pixel more)"
        );
    }
    let shader = app
        .world_mut()
        .resource_mut::<Assets<Shader>>()
        .add(Shader::from_wgsl(
            [include_str!("../optics.wgsl"), include_str!("resolve.wgsl")].join("\n"),
            "bevy_caustics/fixed_splat_resolve.wgsl",
        ));
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app.insert_resource(FixedSplats(fixed));
    if fixed {
        render_app.add_systems(
            RenderStartup,
            move |mut commands: Commands, cache: Res<PipelineCache>| {
                commands.insert_resource(init_pipelines(&cache, shader.clone()));
            },
        );
    }
}

/// Group 1 of a fixed-point splat pipeline: the accumulator, read-write in the fragment stage.
pub fn fragment_layout() -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:fixed_splat",
        &BindGroupLayoutEntries::single(
            ShaderStages::FRAGMENT,
            binding_types::storage_buffer_sized(false, None),
        ),
    )
}

fn init_pipelines(cache: &PipelineCache, shader: Handle<Shader>) -> FixedSplatPipelines {
    use binding_types::*;
    let fragment_layout = fragment_layout();
    let resolve_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:fixed_splat_resolve",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                storage_buffer_read_only_sized(false, None),
                texture_storage_2d(CAUSTICS_BUFFER_FORMAT, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let resolve = cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("caustics:pipeline:fixed_splat_resolve".into()),
        layout: vec![resolve_layout.clone()],
        shader,
        entry_point: Some("resolve".into()),
        ..default()
    });
    FixedSplatPipelines {
        fragment_layout,
        resolve_layout,
        resolve,
    }
}

/// A view's accumulator (`size` pixels, [`FIXED_BYTES_PER_PIXEL`] each).
pub fn accumulator(device: &RenderDevice, label: &'static str, size: UVec2) -> Buffer {
    device.create_buffer(&BufferDescriptor {
        label: Some(label),
        size: (size.x as u64 * size.y as u64 * FIXED_BYTES_PER_PIXEL).max(16),
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Group 1 of a fixed-point splat pass.
pub fn fragment_group(
    device: &RenderDevice,
    cache: &PipelineCache,
    pipelines: &FixedSplatPipelines,
    accumulator: &Buffer,
) -> BindGroup {
    device.create_bind_group(
        "caustics:bind_group:fixed_splat",
        &cache.get_bind_group_layout(&pipelines.fragment_layout),
        &BindGroupEntries::single(accumulator.as_entire_binding()),
    )
}

/// Write the sums of `accumulator` over `target` (a view-sized `Rgba32Float` storage
/// texture of `size` pixels). Does nothing while the resolve compiles.
pub fn resolve(
    ctx: &mut RenderContext,
    cache: &PipelineCache,
    pipelines: &FixedSplatPipelines,
    accumulator: &Buffer,
    target: &TextureView,
    size: UVec2,
) {
    let Some(pipeline) = cache.get_compute_pipeline(pipelines.resolve) else {
        return;
    };
    let group = ctx.render_device().create_bind_group(
        "caustics:bind_group:fixed_splat_resolve",
        &cache.get_bind_group_layout(&pipelines.resolve_layout),
        &BindGroupEntries::sequential((accumulator.as_entire_binding(), target)),
    );
    let mut pass = ctx
        .command_encoder()
        .begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_fixed_splat_resolve"),
            timestamp_writes: None,
        });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.dispatch_workgroups(size.x.div_ceil(8), size.y.div_ceil(8), 1);
}
