//! GPU spans that hold their compute pass's work on every driver.
//!
//! On lavapipe (Mesa's llvmpipe), a timestamp is not written when the command buffer reaches
//! it: it is binned with the pending draws and written when the driver next flushes them, and
//! the driver flushes at every later timestamp or barrier. Compute dispatches, on the other
//! hand, run at once. So in `[begin timestamp, dispatches, end timestamp]` the begin is written
//! when the end flushes, after the dispatches, and the span reports almost nothing of its work
//! (measured: a 2^20-photon photon-map trace of about 1.8 s reported 50 ms). A second
//! timestamp right after the begin (into a one-query scratch set) flushes it before the
//! dispatches, so the span is right: with it, the photon map's spans sum to 1969 ms per frame
//! against 1977 ms of wall clock. Draws are binned at record time too (their vertex stage
//! runs then), so render passes settle the same way. Only on a CPU adapter
//! (`DeviceType::Cpu`) with timestamps inside passes; elsewhere nothing is written.

use bevy::prelude::*;
use bevy::render::render_phase::TrackedRenderPass;
use bevy::render::render_resource::ComputePass;
use bevy::render::renderer::{RenderAdapterInfo, RenderDevice};
use bevy::render::{RenderApp, RenderStartup};
use wgpu::{QuerySet, QuerySetDescriptor, QueryType};

/// The scratch timestamp query of `settle_span` (`None` where it is not needed).
#[derive(Resource, Default)]
pub struct SpanSettle(Option<QuerySet>);

impl SpanSettle {
    /// Call right after `pass_span`: on a CPU driver, the span's begin timestamp is then
    /// written before the pass's work runs.
    pub fn settle(&self, pass: &mut impl SettlePass) {
        if let Some(set) = &self.0 {
            pass.write_scratch_timestamp(set);
        }
    }
}

/// A pass [`SpanSettle::settle`] can write its scratch timestamp into.
pub trait SettlePass {
    /// Write timestamp 0 of `set`.
    fn write_scratch_timestamp(&mut self, set: &QuerySet);
}

impl SettlePass for ComputePass<'_> {
    fn write_scratch_timestamp(&mut self, set: &QuerySet) {
        self.write_timestamp(set, 0);
    }
}

impl SettlePass for TrackedRenderPass<'_> {
    fn write_scratch_timestamp(&mut self, set: &QuerySet) {
        self.wgpu_pass().write_timestamp(set, 0);
    }
}

fn init_span_settle(
    mut commands: Commands,
    device: Res<RenderDevice>,
    info: Res<RenderAdapterInfo>,
) {
    let needed = info.device_type == wgpu::DeviceType::Cpu
        && device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);
    let set = needed.then(|| {
        device.wgpu_device().create_query_set(&QuerySetDescriptor {
            label: Some("caustics_span_settle"),
            ty: QueryType::Timestamp,
            count: 1,
        })
    });
    commands.insert_resource(SpanSettle(set));
}

pub(crate) fn build(app: &mut App) {
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app
            .init_resource::<SpanSettle>()
            .add_systems(RenderStartup, init_span_settle);
    }
}
