//! The `PhotonMap` technique (seed 001: a hash-grid photon map gathered per pixel) on the GPU
//! without ray-tracing hardware, with progressive radius reduction.
//!
//! Per frame and view (see [`passes`]):
//! 1. **Trace** with the shared tracer (src/render/trace/): photon `k` of each caustic light
//!    starts at R2 point `k` of the light's parameter square (rotated every frame), carries
//!    `power · weight / N`, goes through up to `max_bounces` (64) specular events
//!    (dielectrics by Fresnel probability, flux unchanged; after `optics::ROULETTE_DEPTH`
//!    events Russian roulette by `optics::roulette_survival`, as the reference tracer; the flux
//!    in flight at the limit is counted) and is stored at its first diffuse hit after a
//!    specular one: position, flux, incoming direction and receiver normal in 32 bytes. The
//!    luminous flux striking the casters, deposited and in flight at the limit is summed per
//!    workgroup into 64-bit fixed-point header words (`view::FLUX_SCALE`), for the energy
//!    checks (`tests/gpu/energy.rs`).
//! 2. **Grid build** (grid.wgsl, the twin of `optics::build_grid`): bounds with integer
//!    atomics, the layout (cell = the first frame's radius, doubled while the grid would pass
//!    its cell budget), count per cell, a two-level prefix sum (workgroup scans of 1024 cells,
//!    then the block sums; no decoupled look-back) and an atomic scatter that leaves each
//!    cell's start (`startIdx`).
//! 3. **Gather** per pixel at the point of the depth prepass with the G-buffer normal: the
//!    3x3x3 cells as 9 row ranges (up to 9x9x9 as 81 rows where the pixel's footprint is wider
//!    than a cell, `optics::gather_reach`), every photon within `r` whose normal agrees with the
//!    pixel's, the normalised Epanechnikov kernel (`optics::gather_kernel`). On a still view
//!    the frames' results are averaged while `r` shrinks as progressive photon mapping
//!    prescribes (`optics::progressive_radius2`), so the error keeps falling; a change of the
//!    view, the photon count or the settings starts again, and so does a change of the scene
//!    that can change a caustic (`scene::change`). A receiver moved out of the caustic light's
//!    reach restarts only the pixels whose eye distance changed by more than 2 % (each pixel
//!    counts its own frames in the second half of the `accum` buffer, 32 bytes per pixel in
//!    all), and a frozen mean goes on tracing while that happens.
//!
//! 4. **Caustics seen in mirrors** (`mirrors`): a pixel whose camera ray first meets a mirror
//!    follows the reflection through the BVH to the diffuse point it shows and gathers there
//!    with the whole path's footprint; the composite adds `F · albedo / π · E` (the caustics
//!    buffer's alpha −1 marks the pixel). Caustics seen through glass reach the image through
//!    Bevy's screen-space transmission, as for every technique, since the composite runs
//!    before it.
//! 5. **Stereo** ([`crate::CausticsStereo`]): the right eye of a pair skips the trace and the
//!    grid build and gathers from its left eye's, taking the left eye's gathered irradiance
//!    where the left eye sees the same point (reprojection into the left view, distances from
//!    the left eye within 1 %). The seed's section 3.3 scatters the left eye's final colour
//!    after a visibility ray; we reuse irradiance (view-independent) by a gather-style test, so
//!    there is no write race, no hole and no extra ray.
//!
//! Measured on lavapipe (128², `tests/gpu/photon_map.rs` and the command-line renderer):
//! - The default radius, 0.02 of the casters' radius: of 0.01, 0.02 and 0.03 at 2^16 photons,
//!   RMSE after 64 progressive frames 78.6, 70.7, 113 lx on `ring` and 71.4, 70.2, 62.6 lx on
//!   `glass_sphere`.
//! - The footprint floor of the radius (`optics::gather_radius`): on `ring` at radius 0.01,
//!   RMSE after 64 frames 125 lx without it (the point estimate at a caustic curve's peak is
//!   not the pixel's mean) and 78.6 lx with it. Capped at one cell it left the pixels whose
//!   footprint is wider point estimates: `mirror_wall`'s mirrored rectangle stayed at 64 lx
//!   RMSE from 2^16 to 2^20 photons (its edges sampled at the pixel centres). Reaching up to
//!   4 cells (the report's sweep, 2^16 / 2^18 / 2^20, 8 frames): `mirror_wall` 65.0, 63.7,
//!   63.4 -> 42.3, 41.9, 41.7 lx; `glass_slab` 92.6, 85.3, 82.8 -> 64.7, 60.2, 58.4 lx; energy
//!   errors within 0.1 point of before; `glass_sphere`, `pool` and `ring` unchanged (their
//!   footprints are within the cell). Gather on `mirror_wall`: 84 -> 126 photons visited per
//!   pixel.
//! - GPU spans: on lavapipe a compute pass's span only holds its work with the plugin's span
//!   settling (`render/span.rs`). Before it, a 2^20-photon frame on `glass_sphere` cost 1.9 s of
//!   wall clock while its spans added up to 50 ms; with it, the spans add up to 1969 ms against
//!   1977 ms of wall clock per frame. The table below was measured by wall clock before that;
//!   REPORT.md now times every technique by its spans.
//!
//! - Three quality levels (2^16, 2^18, 2^20 photons per light and frame; 128², seed 2, 12
//!   progressive frames, `mirrors` off as the reference has none; wall-clock ms per frame, a
//!   frame without caustics costing 45; RMSE lx / FLIP / energy against the converged
//!   references):
//!
//!   | scene | 2^16 | 2^18 | 2^20 |
//!   | --- | --- | --- | --- |
//!   | `mirror_wall` | 95 ms, 65.4 / 0.0052 / −0.21 % | 232 ms, 63.9 / 0.0052 / −0.21 % | 723 ms, 63.4 / 0.0052 / −0.20 % |
//!   | `glass_slab` | 163 ms, 96.8 / 0.0067 / +0.17 % | 406 ms, 86.8 / 0.0063 / +0.05 % | 1464 ms, 83.5 / 0.0061 / +0.05 % |
//!   | `glass_sphere` | 211 ms, 110.9 / 0.0467 / −0.02 % | 590 ms, 66.7 / 0.0298 / −0.01 % | 2061 ms, 52.7 / 0.0220 / −0.01 % |
//!   | `pool` | 187 ms, 391.4 / 0.0427 / −0.30 % | 435 ms, 376.2 / 0.0374 / −0.27 % | 1624 ms, 372.6 / 0.0356 / −0.25 % |
//!   | `ring` | 105 ms, 90.3 / 0.0375 / −2.53 % | 216 ms, 88.8 / 0.0314 / −2.67 % | 598 ms, 88.7 / 0.0305 / −2.64 % |
//!
//! Readings of the seed we chose (each in the doc of the code that implements it):
//! - The radius is relative to the casters' bounding sphere ([`crate::PhotonMapSettings`]),
//!   so one default fits a 2 cm ball and a 20 m pool.
//! - The grid's memory is bounded: past the budget the cell size doubles (the seed's grid
//!   has no bound; `optics::GridLayout::fit`).
//! - Epanechnikov instead of the seed's uniform kernel (formula 1): the same normalisation,
//!   sharper caustics at the same radius.
//! - Photons are not culled by the view: the map is view-independent, so a stereo pair or a
//!   mirror can gather from it.
//! - The seed's algorithm 1 (a block whose pixels fall in one cell loads its photons into
//!   shared memory) runs on 8x8 tiles whose pixels share the centre cell of their
//!   neighbourhood; other tiles gather pixel by pixel (`shared_memory`, off by default).
//! - Photon order within a cell is whatever the atomic scatter gives; sums differ in the last
//!   bits between runs, the grid's layout and `startIdx` do not (tested exactly).
//!
//! **Work follows change** (`render::settle`; the dispatch log of each row is checked by
//! `tests/gpu/change.rs`):
//!
//! | what changed | what re-runs |
//! | --- | --- |
//! | nothing | progressive mode: trace, grid and gather each frame until `max_frames`, then one gather copies the frozen mean, then nothing; without it, nothing after `Caustics::settle_frames` frames |
//! | the camera moved | trace, grid, gather (the progressive mean starts again) |
//! | a light moved | trace, grid, gather |
//! | a caster moved | trace, grid, gather |
//! | a receiver moved | trace, grid, gather |
//! | a material changed | trace, grid, gather |

pub mod passes;
pub mod pipelines;
pub mod view;

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderSystems};
use bevy::shader::Shader;

/// Render-app part; called from [`crate::render::build`] when the shared tracer is available.
pub(crate) fn build(app: &mut App) {
    super::losses::register(
        app,
        &[
            super::losses::LossCounter {
                path: "render/caustics/photon_map/budget_stopped",
                what: "photon-map paths stopped in a frame by the per-frame event budget (PhotonMapSettings::bounce_budget): their light is missing from the caustic; raise the budget or lower the photon count",
                share_of: None,
            },
            super::losses::LossCounter {
                path: "render/caustics/photon_map/max_depth",
                what: "photon-map paths ended in a frame at PhotonMapSettings::max_bounces specular events (their flux is counted as lost)",
                share_of: None,
            },
        ],
    );
    let shaders = {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        pipelines::PhotonMapShaders {
            compute: shaders.add(Shader::from_wgsl(
                pipelines::compute_source(),
                "bevy_caustics/photon_map_compute.wgsl",
            )),
            grid: shaders.add(Shader::from_wgsl(
                pipelines::grid_source(),
                "bevy_caustics/photon_map_grid.wgsl",
            )),
        }
    };
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(shaders)
        .add_systems(
            Render,
            (
                pipelines::queue_photon_map_pipelines,
                pipelines::queue_photon_map_trace_variant,
                view::prepare_photon_map_views,
            )
                .chain()
                .in_set(RenderSystems::PrepareResources)
                .after(super::trace::prepare_trace_scene),
        )
        .add_systems(
            Core3d,
            passes::photon_map_passes
                .in_set(Core3dSystems::MainPass)
                .after(deferred_lighting)
                .before(super::composite::composite_caustics),
        );
}
