use bevy::prelude::*;

/// Settings of the [`crate::CausticsTechnique::ImageSpace`] technique (cascaded image-space
/// photon tracing with an SVGF denoiser, seed 003). Put it on the camera next to
/// [`crate::Caustics`]; without it the defaults below are used. Defaults are the paper's where
/// it gives a value (section 3.1, the SVGF paper for the denoiser) and marked "ours" where not.
///
/// The photon count per light and frame comes from [`crate::Caustics::quality`].
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
pub struct ImageSpaceSettings {
    /// Side of each light's reflective shadow maps (opaque depth, caster front, caster back),
    /// texels. Default 1024 (section 4 used 2048 for 2 M photons). Range [64, 4096]. Cost:
    /// three raster passes of the scene per light, `48 · side²` bytes per light, and the
    /// light-space march takes up to `side · √2` steps.
    #[reflect(@64_u32..=4096_u32)]
    pub rsm_resolution: u32,
    /// Photons are not started from texels whose flux luminance is below this fraction of the
    /// light's brightest texel (a spot light's cone edge, the far side of a point light's
    /// cone). Default 0.04 (the paper's luminance cutoff, which it applies to the RSM's
    /// normalised flux; ours relative to the brightest texel so it does not depend on the
    /// light's units). Range [0, 1]; 0 keeps every texel. Cost: none.
    #[reflect(@0.0_f32..=1.0_f32)]
    pub luminance_cutoff: f32,
    /// Texels per step of both marches (the paper steps one texel). Default 1. Range [1, 16].
    /// Cost: the marches' time falls about linearly with it; thin receivers may be stepped over.
    #[reflect(@1_u32..=16_u32)]
    pub stride: u32,
    /// March through nearest-depth pyramids (Hi-Z) of the light's layers and the camera's
    /// depth instead of texel by texel: cells whose nearest surface lies behind the ray are
    /// skipped whole. Default true: at the default 1024² maps on lavapipe the trace pass is
    /// 4.9x (`glass_sphere`) and 6x (`mirror_wall`) faster with it, pyramids included, for
    /// the same error (RMSE 123 against 121 lx, energy within 0.2 %); at 256² maps it is 1.8x
    /// to 2.6x faster and flat cells cost some precision (RMSE 227 against 169 lx). Cost: one pyramid build per plane and frame (a third of a full-screen
    /// pass); the marches take O(log n) steps over empty space instead of O(n).
    pub hi_z: bool,
    /// Thickness assumed behind every depth sample, as a fraction of its depth: a march step
    /// that ends further behind a surface than this passed behind it and goes on. It is also
    /// the tolerance of the reprojection's "plane" case. Default 0.02 (ours). Range [1e-4, 1].
    #[reflect(@1.0e-4_f32..=1.0_f32)]
    pub thickness: f32,
    /// Reflections a photon may take inside a closed caster before it must leave (ours, past
    /// the seed's one interface plus the exit): where it meets the glass again is found by
    /// marching between the light's caster-front and caster-back layers, and each meeting
    /// refracts out with probability `1 - F` or reflects (always on total internal reflection).
    /// A photon still inside after these, or one that crosses a silhouette where the layers
    /// cannot follow it, is dropped and counted (`caustics/image_space/trapped`); when that is
    /// over 20 % of the photons traced the plugin names a better technique once in a `warn!`.
    /// Default 64 (ours; the brilliant-cut IOR 2.4 gem in a closed room at 1024² maps: the
    /// caustic energy in view within 5.0 % of the reference's, 1.8 % of the photons left
    /// inside; 0 loses 75 %). Range [0, 256]; 0 drops every photon the exit reflects. Cost: one
    /// light-space march per reflection, only for the photons that reflect inside (the gem's
    /// trace pass takes 4.2x as long as with 0 on lavapipe).
    #[reflect(@0_u32..=256_u32)]
    pub internal_events: u32,
    /// Denoise the photon map with SVGF. Default true. `false` writes the raw photon map.
    /// Cost: one temporal pass, one variance pass and `atrous_iterations` filter passes per
    /// frame at the view's resolution.
    pub denoise: bool,
    /// SVGF's colour blend factor: the weight of the new frame in the temporal average while
    /// the camera moves and for the `(2 - a) / a` frames after a reset. Default 0.2 (the SVGF
    /// paper). Range [0.01, 1]. Once the camera and the caustics have stood longer, the average
    /// is the plain mean of up to `history_cap` unfiltered frames (ours: the caustics reset the
    /// history when they change, so an unchanged caustic under a still camera has no reason to
    /// keep alpha's noise; with a cube circling elsewhere the caustic's frame-to-frame change
    /// fell from 0.0165 to 0.0050 and its RMSE from 172 to 138 lx on `glass_sphere`).
    #[reflect(@0.01_f32..=1.0_f32)]
    pub alpha_color: f32,
    /// SVGF's blend factor of the luminance moments. Default 0.2. Range [0.01, 1].
    #[reflect(@0.01_f32..=1.0_f32)]
    pub alpha_moments: f32,
    /// Frames of history kept at most (the blend factor never falls below its inverse).
    /// Default 32 (Falcor, birt). Range [1, 256].
    #[reflect(@1_u32..=256_u32)]
    pub history_cap: u32,
    /// À-trous iterations (5×5 kernel, step `2^i`). Default 5 (the SVGF paper: a 65 px
    /// footprint). Range [0, 8]. Cost: one full-screen pass each. A pixel whose history holds
    /// under 4 frames (after a reset: a caster moving every frame resets it every frame) gets
    /// the first iteration only: its variance is a spatial estimate that holds the caustic's
    /// own contrast, and the wide ones would spread the caustic.
    #[reflect(@0_u32..=8_u32)]
    pub atrous_iterations: u32,
    /// Depth edge-stopping `σ_z`. Default 1. Range [0.01, 100].
    #[reflect(@0.01_f32..=100.0_f32)]
    pub sigma_depth: f32,
    /// Normal edge-stopping exponent `σ_n`. Default 128. Range [1, 1024].
    #[reflect(@1.0_f32..=1024.0_f32)]
    pub sigma_normal: f32,
    /// Luminance edge-stopping `σ_l`. Default 4. Range [0.1, 1000].
    #[reflect(@0.1_f32..=1000.0_f32)]
    pub sigma_luminance: f32,
    /// Drop the denoiser's history when the scene's caustics can change (a caster changed, a
    /// light drifted past its tolerance, a receiver moved in the caustic light's reach:
    /// `scene::change`; a mover elsewhere keeps it): motion vectors are zero where a caustic moves over a still
    /// floor, so history would smear it. Default true (ours; measured in the module doc of
    /// `render::image_space`: within 7 % of the settled error 4 frames after the sun turns,
    /// where the kept history is still 3x above it after 8).
    pub reset_on_change: bool,
}

impl Default for ImageSpaceSettings {
    fn default() -> Self {
        Self {
            rsm_resolution: 1024,
            luminance_cutoff: 0.04,
            stride: 1,
            hi_z: true,
            thickness: 0.02,
            internal_events: 64,
            denoise: true,
            alpha_color: 0.2,
            alpha_moments: 0.2,
            history_cap: 32,
            atrous_iterations: 5,
            sigma_depth: 1.0,
            sigma_normal: 128.0,
            sigma_luminance: 4.0,
            reset_on_change: true,
        }
    }
}

impl ImageSpaceSettings {
    /// A copy with every field in range (what the GPU passes use); non-finite values become
    /// the defaults.
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let f = |x: f32, d: f32, lo: f32, hi: f32| if x.is_finite() { x.clamp(lo, hi) } else { d };
        Self {
            rsm_resolution: self.rsm_resolution.clamp(64, 4096),
            luminance_cutoff: f(self.luminance_cutoff, d.luminance_cutoff, 0.0, 1.0),
            stride: self.stride.clamp(1, 16),
            hi_z: self.hi_z,
            thickness: f(self.thickness, d.thickness, 1e-4, 1.0),
            internal_events: self.internal_events.min(256),
            denoise: self.denoise,
            alpha_color: f(self.alpha_color, d.alpha_color, 0.01, 1.0),
            alpha_moments: f(self.alpha_moments, d.alpha_moments, 0.01, 1.0),
            history_cap: self.history_cap.clamp(1, 256),
            atrous_iterations: self.atrous_iterations.min(8),
            sigma_depth: f(self.sigma_depth, d.sigma_depth, 0.01, 100.0),
            sigma_normal: f(self.sigma_normal, d.sigma_normal, 1.0, 1024.0),
            sigma_luminance: f(self.sigma_luminance, d.sigma_luminance, 0.1, 1000.0),
            reset_on_change: self.reset_on_change,
        }
    }

    /// [`Self::sanitized`], with the RSM side bounded by the device
    /// ([`crate::limits::CausticsLimits::rsm_side`]).
    pub fn sanitized_for(&self, limits: &crate::limits::CausticsLimits) -> Self {
        let mut s = self.sanitized();
        s.rsm_resolution = limits.rsm_side(s.rsm_resolution);
        s
    }
}
