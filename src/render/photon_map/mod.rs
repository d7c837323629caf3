//! The `PhotonMap` technique (seed 001: a hash-grid photon map gathered per pixel) on the GPU
//! without ray-tracing hardware, with progressive radius reduction.
//!
//! Per frame and view (see [`passes`]):
//! 1. **Trace** with the shared tracer (src/render/trace/): photon `k` of each caustic light
//!    starts at R2 point `k` of the light's parameter square (rotated every frame), carries
//!    `power · weight / N`, goes through up to `max_bounces` specular events (dielectrics by
//!    Fresnel probability, flux unchanged) and is stored at its first diffuse hit after a
//!    specular one: position, flux, incoming direction and receiver normal in 32 bytes.
//! 2. **Grid build** (grid.wgsl, the twin of `optics::build_grid`): bounds with integer
//!    atomics, the layout (cell = the first frame's radius, doubled while the grid would pass
//!    its cell budget), count per cell, a two-level prefix sum (workgroup scans of 1024 cells,
//!    then the block sums; no decoupled look-back) and an atomic scatter that leaves each
//!    cell's start (`startIdx`).
//! 3. **Gather** per pixel at the point of the depth prepass with the G-buffer normal: the
//!    3x3x3 cells as 9 row ranges, every photon within `r` whose normal agrees with the
//!    pixel's, the normalised Epanechnikov kernel (`optics::gather_kernel`). On a still view
//!    the frames' results are averaged while `r` shrinks as progressive photon mapping
//!    prescribes (`optics::progressive_radius2`), so the error keeps falling; any change of the
//!    scene, the view, the photon count or the settings starts again.
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

pub mod passes;
pub mod pipelines;
pub mod view;

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

/// Render-app part; called from [`crate::render::build`] when the shared tracer is available.
pub(crate) fn build(app: &mut App) {
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
        .add_systems(RenderStartup, pipelines::init_photon_map_pipelines)
        .add_systems(
            Render,
            view::prepare_photon_map_views
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
