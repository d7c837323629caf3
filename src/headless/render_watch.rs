//! What the job watches in the render world: the adapter it runs on (for the report), and
//! pipelines that cannot be built. Bevy logs a shader that does not compile (a WGSL error, a
//! bad import) and renders on without the pipeline; a headless render then finished with
//! empty caustics and exit status 0. [`fail_on_pipeline_errors`] turns the first such error
//! into the job's error, and the main world's driver stops the app.

use bevy::prelude::*;
use bevy::render::render_resource::{CachedPipelineState, PipelineCache, PipelineDescriptor};
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::{Render, RenderApp, RenderStartup};
use bevy::shader::ShaderCacheError;

use super::job::Shared;

/// Record the adapter in the job's report and fail the job on a pipeline error.
pub(super) fn watch_render_world(app: &mut App, shared: &Shared) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(shared.clone())
        .add_systems(Render, fail_on_pipeline_errors);
    let s = shared.clone();
    render_app.add_systems(RenderStartup, move |info: Res<RenderAdapterInfo>| {
        if let Ok(mut o) = s.0.lock() {
            o.report.adapter = format!("{} ({:?})", info.name, info.backend);
            o.report.driver = format!(
                "{} {} ({:?})",
                info.driver, info.driver_info, info.device_type
            );
        }
    });
}

/// The first pipeline whose shader could not be processed or compiled, as the job's error (a
/// shader not loaded yet, or an import not yet available, is retried by Bevy: not an error).
fn fail_on_pipeline_errors(cache: Res<PipelineCache>, shared: Res<Shared>) {
    let failed = cache.pipelines().find_map(|p| match &p.state {
        CachedPipelineState::Err(
            e @ (ShaderCacheError::ProcessShaderError(_) | ShaderCacheError::CreateShaderModule(_)),
        ) => Some((label(&p.descriptor), e.to_string())),
        _ => None,
    });
    let Some((label, error)) = failed else {
        return;
    };
    if let Ok(mut o) = shared.0.lock() {
        let first_line = error.lines().next().unwrap_or("").to_string();
        o.error.get_or_insert(format!(
            "pipeline {label} could not be built: {first_line} (the log above has the whole error)"
        ));
    }
}

fn label(d: &PipelineDescriptor) -> String {
    let l = match d {
        PipelineDescriptor::RenderPipelineDescriptor(d) => d.label.as_deref(),
        PipelineDescriptor::ComputePipelineDescriptor(d) => d.label.as_deref(),
    };
    l.unwrap_or("(unlabelled)").to_string()
}
