//! The headless (or windowed) renderer behind `examples/render.rs`, `examples/showcase.rs`
//! and the GPU tests: load a glTF, render it with a caustics technique on whatever adapter
//! exists (lavapipe on CI), and return the caustic buffer, the frame and the statistics.
//! Nothing is written to disk here; the callers write their outputs only once everything
//! succeeded.

mod adapter;
mod batch;
mod check;
mod counters;
mod job;
mod load_error;
pub mod motion;
mod render_watch;
mod report;
mod stage;
mod volume;

pub use crate::volume::volume_from_extras;
pub use adapter::{adapter_limits, decode_f16_rgba, find_adapter, quiet_headless_environment};
pub use batch::{run, run_all};
pub use check::check_job;
pub use counters::*;
pub use job::*;
pub use load_error::{
    LoaderPanicCapture, load_failure_reason, quiet_reported_load_failures, report_load_failures_of,
    tool_log_plugin, unsupported_extensions,
};
pub use report::RenderReport;
pub use stage::{
    STAGE_EV100, STAGE_FLOOR_ALBEDO, STAGE_FOV_Y, STAGE_SUN_LUX, StageLayout, StagePart,
    build_stage, stage_sun_direction, world_bounds,
};
pub use volume::VolumeCounters;
