//! What a render produced ([`RenderReport`]) and the per-frame sampling of its pass times.

use std::collections::BTreeMap;

use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore};
use serde::Serialize;

use super::counters::{AapsCounters, ImageSpaceCounters, PhotonMapCounters};
use crate::reference::{CausticImage, ImageMetrics};
use crate::render::composite::COMPOSITE_PASS;

/// What a render produced.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RenderReport {
    /// Adapter name (and backend).
    pub adapter: String,
    /// The adapter's driver and driver version, as wgpu reports them (`AdapterInfo::driver`,
    /// `driver_info`), and its device type (`Cpu` for lavapipe).
    pub driver: String,
    /// Technique name.
    pub technique: String,
    /// Width, height.
    pub size: [u32; 2],
    /// Median GPU milliseconds per caustics pass over the measured frames (CPU ms where the
    /// adapter has no timestamp queries; see `timing`).
    pub pass_ms: BTreeMap<String, f64>,
    /// "gpu" or "cpu": which clock `pass_ms` comes from.
    pub timing: String,
    /// The caustics passes' summed time of every measured frame whose diagnostics arrived,
    /// in order, ms, on the clock of `timing` (its median is the frame's total; the sum of
    /// the per-pass medians need not be).
    pub frame_ms: Vec<f64>,
    /// Photons traced (emitted) for the caustics buffer.
    pub photons_traced: u64,
    /// Photons that reached a visible pixel.
    pub photons_in_view: u64,
    /// Wall-clock seconds of the reference trace.
    pub reference_seconds: f64,
    /// The reference trace's counters (technique `reference` only): its flux on the casters,
    /// deposited, escaped, absorbed, at the cap and taken by roulette, which balance.
    #[serde(skip)]
    pub reference_stats: Option<crate::reference::TraceStats>,
    /// Distinct caustics passes dispatched while measuring, in order of first dispatch.
    pub passes: Vec<String>,
    /// Invalid-input warnings logged.
    pub warnings: Vec<String>,
    /// Lost-light warnings logged (`render::losses`: paths at a bounce cap or an event budget,
    /// photons a technique cannot follow), at most one per counter.
    pub loss_warnings: Vec<String>,
    /// Metrics against `--compare`, filled by the caller.
    pub metrics: Option<ImageMetrics>,
    /// Caustic irradiance (lux), zero where no caustic lands.
    #[serde(skip)]
    pub caustics: Option<CausticImage>,
    /// The final frame, RGBA8 sRGB, tone mapped.
    #[serde(skip)]
    pub frame_rgba8: Vec<u8>,
    /// With `linear`: the linear HDR frame with and without caustics, RGBA f32.
    #[serde(skip)]
    pub linear_with: Vec<[f32; 4]>,
    /// See `linear_with`.
    #[serde(skip)]
    pub linear_without: Vec<[f32; 4]>,
    /// With `every_frame`: the caustics buffer of every frame of the camera, in order: the
    /// camera's first two frames, then measured frame `n` at index `n + 2` (its state after
    /// [`crate::headless::RenderJob::per_frame`]`(n)`), the last measured frame last.
    #[serde(skip)]
    pub frame_caustics: Vec<CausticImage>,
    /// With `every_frame`: the counter words read back with each of `frame_caustics`.
    #[serde(skip)]
    pub frame_counters: Vec<Vec<u32>>,
    /// With `linear`: the camera's exposure.
    pub exposure: f32,
    /// AAPS counters of the last frame (technique `aaps` only).
    pub aaps: Option<AapsCounters>,
    /// Image-space counters of the last frame (technique `image_space` only).
    pub image_space: Option<ImageSpaceCounters>,
    /// Photon-map counters of the last frame (technique `photon_map` only).
    pub photon_map: Option<PhotonMapCounters>,
    /// With `read_photons`: the last frame's stored photons (technique `photon_map`).
    #[serde(skip)]
    pub photon_map_photons: Vec<crate::optics::StoredPhoton>,
    /// The caustics buffer's alpha per pixel of the last frame (the photon map marks pixels
    /// showing a mirror with -1).
    #[serde(skip)]
    pub caustics_alpha: Vec<f32>,
    /// Counters of the first visible volume (technique `volume` only).
    pub volume: Option<super::volume::VolumeCounters>,
    /// GPU bytes each technique held at the last measured frame (`render::memory`).
    pub gpu_bytes: BTreeMap<String, u64>,
    /// The same at every measured frame, in order.
    #[serde(skip)]
    pub frame_gpu_bytes: Vec<BTreeMap<String, u64>>,
    /// The caustics passes dispatched in each measured frame: list `n` holds what the render
    /// world ran for measured frame `n - 1` (the headless renderer runs frame by frame, without
    /// pipelined rendering); the first holds every frame since the camera spawned.
    pub frame_passes: Vec<Vec<String>>,
}

/// The GPU and CPU time of every caustics pass in the newest frame's render diagnostics,
/// appended to `samples.passes` under `"{pass}@gpu"` / `"{pass}@cpu"`, with the frame's sum
/// per clock in `samples.frame_totals`. Spans of one name in one frame (a volume slab's near
/// and far G-buffers) are summed. A pass that did not run in that frame adds nothing, and
/// neither does a call before the next frame's diagnostics arrived (rather than repeating the
/// last values).
pub(super) fn sample_pass_times(diagnostics: &DiagnosticsStore, samples: &mut PassSamples) {
    let mut found = Vec::new();
    for pass in [COMPOSITE_PASS, crate::render::temporal::TEMPORAL_PASS]
        .into_iter()
        .chain(crate::render::aaps::passes::ALL_PASSES)
        .chain(crate::render::volume::passes::all_passes())
        .chain(crate::render::image_space::passes::ALL_PASSES)
        .chain(crate::render::photon_map::passes::ALL_PASSES)
    {
        for (clock, name) in [("gpu", "elapsed_gpu"), ("cpu", "elapsed_cpu")] {
            let path = DiagnosticPath::new(format!("render/{pass}/{name}"));
            if let Some((d, time)) = diagnostics
                .get(&path)
                .and_then(|d| d.measurement().map(|m| (d, m.time)))
            {
                found.push((pass, clock, d, time));
            }
        }
    }
    // One sync stamps all of a frame's diagnostics with the same time.
    let Some(newest) = found.iter().map(|f| f.3).max() else {
        return;
    };
    if samples.last.is_some_and(|t| newest <= t) {
        return;
    }
    samples.last = Some(newest);
    let mut totals: BTreeMap<&str, f64> = BTreeMap::new();
    for (pass, clock, d, _) in found.into_iter().filter(|f| f.3 == newest) {
        let ms: f64 = d
            .measurements()
            .filter(|m| m.time == newest)
            .map(|m| m.value)
            .sum();
        samples
            .passes
            .entry(format!("{pass}@{clock}"))
            .or_default()
            .push(ms);
        *totals.entry(clock).or_default() += ms;
    }
    for (clock, ms) in totals {
        samples
            .frame_totals
            .entry(clock.to_string())
            .or_default()
            .push(ms);
    }
}

/// Pass times gathered over the measured frames ([`sample_pass_times`]).
#[derive(Default)]
pub(super) struct PassSamples {
    /// Per `"{pass}@{clock}"`, one value per frame the pass ran in, ms.
    pub(super) passes: BTreeMap<String, Vec<f64>>,
    /// Per clock, the sum over the passes of every sampled frame, ms.
    pub(super) frame_totals: BTreeMap<String, Vec<f64>>,
    /// When the newest diagnostics sampled were synced.
    pub(super) last: Option<bevy::platform::time::Instant>,
}
