//! The headless (or windowed) renderer behind `examples/render.rs`, `examples/showcase.rs`
//! and the GPU tests: load a glTF, render it with a caustics technique on whatever adapter
//! exists (lavapipe on CI), and return the caustic buffer, the frame and the statistics.
//! Nothing is written to disk here; the callers write their outputs only once everything
//! succeeded.

mod job;
mod volume;

pub use crate::volume::volume_from_extras;
pub use job::*;
pub use volume::VolumeCounters;
