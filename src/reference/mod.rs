//! The CPU ground truth: a deterministic multi-threaded light tracer, the caustic image type
//! and the metrics every technique is judged by.

pub mod cache;
pub mod curve;
mod exr;
pub mod metrics;
pub mod technique;
pub mod tracer;

pub use crate::render::image::CausticImage;
pub use metrics::{ImageMetrics, compare, plane_region_mean};
pub use technique::{CausticsReferenceImage, ReferenceProgress, ReferenceStatus};
pub use tracer::{TraceOutput, TraceSettings, TraceStats, trace};
