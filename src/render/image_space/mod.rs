//! The `ImageSpace` technique (seed 003, cascaded image-space photon tracing, Meenrattanakorn
//! and Lambers 2022) on the GPU: no BVH, no volume, only rasterised views.
//!
//! Per frame and view (see [`passes`]):
//! 1. **Reflective shadow maps** per caustic light, rasterised by the plugin from the scene's
//!    world-space triangles (Bevy's shadow pass is depth only): an opaque layer (receivers),
//!    a caster-front layer (depth, normal, instance → material) and a **caster-back layer**
//!    (the nearest caster surface facing away from the light), so a photon refracted into a
//!    closed glass object leaves it through a second refraction. Directional lights get an
//!    orthographic map fitted to the casters; point and spot lights the cone holding the
//!    casters' bounding sphere.
//! 2. **Photons** at R2 low-discrepancy points over the map, rotated every frame; flux =
//!    texel flux × texels / photons; reflect or refract by the exact Fresnel factor against a
//!    uniform number (Russian roulette, flux unchanged); at the back face the transmitted
//!    share `1 − F` is kept and total internal reflection drops the photon (counted); Beer-Lambert
//!    inside media.
//! 3. **Cascaded march**: a perspective-correct DDA through the light's opaque depth, the exact
//!    termination of eq. 2, the end reprojected into the camera (plane: a hit; concave: march
//!    on; convex: lost), a second-chance march in the camera's depth, the normal test
//!    `<−d, n> ≥ 0`. Every outcome is counted.
//! 4. **Irradiance** `E = Φ / A_p` with the exact pixel footprint, added into a per-pixel
//!    photon map in 64-bit fixed point (1/256 lux, stochastic rounding: integer sums, so the
//!    map is the same whatever order the photons land in).
//! 5. **SVGF** into the caustics buffer, the history dropped when the scene's caustics change.
//!
//! Measured on lavapipe (128², 2^16 photons per light, 256² maps, `tests/gpu/image_space.rs`):
//! - history reset on change against keeping it, the sun turned back by 8 degrees at frame 12
//!   on `glass_sphere` (settled RMSE 249 lx): with the reset 523, 577, 627, then 266, 252 ...
//!   lx; kept, 1700, 1450, 1268, ... 771 lx after 8 frames. A-SVGF gradients or history
//!   clamping were not built: the reset is exact for the cause we know (the scene changed) and
//!   costs nothing when nothing changes.
//! - Hi-Z against the linear march (so Hi-Z is the default): at 1024² maps and 2^18 photons
//!   the trace pass with the pyramids is 4.9x (`glass_sphere`, 853 → 175 ms) and 6x
//!   (`mirror_wall`, 688 → 114 ms) faster for the same error; at 256² maps 2.6x, 1.8x and
//!   1.9x (`ring`), energy within 1 %, RMSE on `glass_sphere` 227 against 169 lx.
//! - Symmetric à-trous luminance weights against SVGF's own (the centre pixel's deviation):
//!   energy on `ring` −7.7 % against −30 %, RMSE on `glass_sphere` 169 against 242 lx.
//! - One à-trous iteration on a history under 4 frames, against all of them: the ball of
//!   `glass_sphere` sliding 1 cm a frame (each move a reset, so every pixel's history is one
//!   frame), RMSE 148.2 against 466.0 lx (`motion::a_moving_caster_leaves_no_trail`); a still
//!   caustic's error is the same (the report's still sweep unchanged).
//!
//! Readings of the paper we chose (each in the doc of the code that implements it):
//! - Casters are invisible to the marches (the opaque layers hold receivers only), as the
//!   paper's opaque-only depth buffers hold no refractive surface; mirrors are casters too.
//! - Footprint: the paper's on-axis `A_p` times `<−d, n>` is replaced by the exact off-axis
//!   footprint (`optics::pixel_footprint_area`), which keeps the corners' energy.
//! - The luminance cutoff is relative to the light's brightest texel.
//! - The denoiser reprojects each pixel's world position with the camera's previous
//!   `clip_from_world`, not with Bevy's motion vectors. Caustic irradiance belongs to a place
//!   in the world (it moves only when a light or caster does), not to the receiver's surface:
//!   motion vectors follow the surface, so on a floor sliding under a still glass ball they
//!   would drag the caustic's history along with the floor. A camera-only move gives the same
//!   history either way (measured: RMSE 520.0 lx at the same frame with either, on
//!   `glass_sphere` with the camera orbiting), and a receiver moved in the caustic light's
//!   reach changes the scene's caustic generation (`scene::change`), which drops the history
//!   anyway; one moved elsewhere keeps it, and the per-pixel validity drops what it covers.
//! - Casters are ideal specular ([`crate::CausticMaterial`] has no roughness; a
//!   `StandardMaterial` mirror rougher than 0.2 is already a receiver), so the paper's
//!   roughness cutoff of 0.3 never applies.
//!
//! **Work follows change** (`render::settle`; the dispatch log of each row is checked by
//! `tests/gpu/change.rs`):
//!
//! | what changed | what re-runs |
//! | --- | --- |
//! | nothing, for `Caustics::settle_frames` frames | nothing: the caustics buffer keeps the denoised result |
//! | the camera moved | Hi-Z, trace, resolve, SVGF (temporal, variance, à-trous); the RSMs are kept (they depend on the lights and the geometry only) |
//! | a light moved | RSMs and everything after them |
//! | a caster moved | RSMs and everything after them |
//! | a receiver moved | RSMs and everything after them |
//! | a material changed | RSMs and everything after them |

pub mod passes;
pub mod pipelines;
pub mod rsm_view;
pub mod view;

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

/// Render-app part; called from [`crate::render::build`] when AAPS (whose scene extraction it
/// shares) is available.
pub(crate) fn build(app: &mut App) {
    super::losses::register(
        app,
        &[super::losses::LossCounter {
            path: "render/caustics/image_space/trapped",
            what: "image-space photons in a frame were dropped inside a caster (still reflecting after ImageSpaceSettings::internal_events, or crossing a silhouette the light's caster layers cannot follow): over 20 % of the light is lost; Aaps or PhotonMap follow light that reflects inside glass to the end",
            share_of: Some(("render/caustics/image_space/emitted", 0.2)),
        }],
    );
    let shaders = {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        pipelines::ImageSpaceShaders {
            compute: shaders.add(Shader::from_wgsl(
                pipelines::compute_source(),
                "bevy_caustics/image_space_compute.wgsl",
            )),
            rsm: shaders.add(Shader::from_wgsl(
                pipelines::rsm_source(),
                "bevy_caustics/image_space_rsm.wgsl",
            )),
        }
    };
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(shaders)
        .add_systems(RenderStartup, pipelines::init_image_space_pipelines)
        .add_systems(
            Render,
            (
                view::prepare_image_space_scene,
                pipelines::queue_image_space_trace_variant,
                view::prepare_image_space_views,
            )
                .chain()
                .in_set(RenderSystems::PrepareResources)
                .after(super::prepare_caustics_buffers),
        )
        .add_systems(
            Core3d,
            passes::image_space_passes
                .in_set(Core3dSystems::MainPass)
                .after(deferred_lighting)
                .before(super::composite::composite_caustics),
        );
}
