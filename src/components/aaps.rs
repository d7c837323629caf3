use bevy::prelude::*;

/// Settings of the [`crate::CausticsTechnique::Aaps`] technique (adaptive anisotropic photon
/// scattering, seed 004). Put it on the camera next to [`crate::Caustics`]; without it the
/// defaults below are used. Defaults follow the thesis where it gives a value (sections 3.2
/// and 4.3) and are marked "ours" where it does not.
///
/// The photon budget comes from [`crate::Caustics::quality`]: `photons_per_light` times the
/// number of caustic lights bounds the photons emitted per frame.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
pub struct AapsSettings {
    /// Side of each light's ray-density texture in the atlas, texels. Default 128 (the
    /// original authors'; the thesis used 256). Power of two in [8, 1024]; other values are
    /// rounded to the nearest power of two. Cost: the task-buffer update scales with its
    /// square, and the minimum photon count is `4 · side²` per light.
    #[reflect(@8_u32..=1024_u32)]
    pub atlas_resolution: u32,
    /// Screen-space splat area the density update aims for, pixels. Default 19 (the thesis's
    /// best RMSE on its Pool scene, section 4.3). Smaller: more photons, sharper, slower.
    #[reflect(@0.01_f32..=1.0e4_f32)]
    pub target_area: f32,
    /// Variance gain `g` of `D' = D A / A_t + v g`: photons added per unit of relative
    /// temporal variance. Default 4 (ours). 0 switches the variance term off.
    #[reflect(@0.0_f32..=1.0e3_f32)]
    pub variance_gain: f32,
    /// Temporal weight `w_t` of the density blend (section 3.1.5): 1 keeps only the new
    /// suggestion, 0 only the neighbours' previous values. Default 0.5 (ours).
    #[reflect(@0.0_f32..=1.0_f32)]
    pub temporal_weight: f32,
    /// Minimum ray density per texel. Default 4 (section 3.2.2). At least 1.
    #[reflect(@1.0_f32..=1.0e6_f32)]
    pub min_density: f32,
    /// Maximum ray density per texel; 0 means none. Default 0 (the thesis's experiments).
    #[reflect(@0.0_f32..=1.0e6_f32)]
    pub max_density: f32,
    /// Large-splat threshold (section 3.3.5): the solid angle of a splat seen from its last
    /// specular interaction, `area / distance²`, in steradians. Splats above it do not steer
    /// the density (a grazing photon would otherwise ask for unbounded photons), and with
    /// `drop_large_splats` they are culled. Default 0.05 sr (ours; the thesis's lowest tried
    /// value was 0.0014). 0 disables both.
    #[reflect(@0.0_f32..=12.57_f32)]
    pub cull_solid_angle: f32,
    /// Cull the splats above `cull_solid_angle` (the thesis's performance culling). Default
    /// false: culled splats take their energy with them (22 % of the `ring` scene's caustic
    /// at 0.05 sr), so the default keeps them and stays energy-conserving. Cost when false:
    /// fill rate of the few very large splats.
    pub drop_large_splats: bool,
    /// Small-splat MSAA (section 5.1.3): splats whose screen area is under this many pixels
    /// are drawn into a 4x multisampled target with per-sample shading, then resolved and
    /// added. Default 4 px (ours). 0 switches it off. Cost: one resolve per frame.
    #[reflect(@0.0_f32..=64.0_f32)]
    pub msaa_threshold: f32,
    /// Size of a splat relative to its photon's footprint: the ellipse's semi-axes are this
    /// times the singular values of the two differential offsets (which span the sample
    /// spacing of the photon's texel). The thesis leaves it open. Default 1.5 (ours: on the test scenes
    /// at 128², 1.0 leaves sub-pixel gaps, RMSE 321 on `glass_sphere`; 1.5 gives 164, 2.5 gives
    /// 102 but blurs, FLIP 0.029 → 0.032 and 0.049 → 0.089 on `ring`). Range [0.1, 16].
    #[reflect(@0.1_f32..=16.0_f32)]
    pub splat_scale: f32,
    /// Largest ratio of a splat's axes (section 3.1.2: "anisotropy is limited"). Default 16
    /// (ours). At least 1.
    #[reflect(@1.0_f32..=1.0e4_f32)]
    pub max_anisotropy: f32,
    /// Specular interactions followed per photon before it is dropped (its flux is counted as
    /// in flight at the cap). Default 64 (ours: a brilliant-cut IOR 2.4 gem in a closed room of
    /// receivers keeps all but 0.7 % of the power that strikes it; the reference tracer loses
    /// 5.9 % at 16). Range [1, 128]. Cost: only the paths that bounce that often pay for it.
    #[reflect(@1_u32..=128_u32)]
    pub max_bounces: u32,
    /// Capacity of the splat buffer, splats (64 bytes each). Default 2 097 148: 2^21 less the
    /// 4-splat guard region, so the buffer fits a 128 MiB storage binding (WebGPU's default).
    /// At most what one storage binding of the GPU holds
    /// ([`crate::limits::CausticsLimits::max_splat_capacity`]), clamped with a warning.
    /// Splats past it are counted as overflow and not drawn. The buffer holds no more than
    /// twice the photons the view can trace (a photon splits once), so at the default budgets
    /// it is far smaller.
    #[reflect(@1_u32..=16_777_216_u32)]
    pub splat_capacity: u32,
    /// Share of the frame's photon budget spread evenly over the texels whose photons reached
    /// a visible receiver last frame (ours, [`crate::optics::budget_split`]); the rest follows
    /// the thesis's `D' = D A / A_t`. A focus has sub-pixel splats, so `D'` alone leaves it at
    /// the minimum density at every budget and its error stops falling; the floor grows with
    /// the budget. Default 0.5. Range [0, 1]; 0 is the thesis's rule.
    #[reflect(@0.0_f32..=1.0_f32)]
    pub budget_floor_share: f32,
    /// Point splats (ours): a splat whose projected area is under this many pixels is drawn
    /// into the one pixel holding its centre with its whole flux (`E · area_px`), as the
    /// reference bins photons. Drawn as a tiny ellipse it would cover 0 or 1 of 4 MSAA
    /// samples by chance, and that quantisation, not the photon count, set the error at a
    /// focus. Default 1 px. 0 switches it off. Cost: none (one-pixel quads).
    #[reflect(@0.0_f32..=16.0_f32)]
    pub point_splat_area: f32,
    /// Per-frame budget of specular events (reflections and refractions, summed over every
    /// path), as a multiple of the frame's photon budget: the trace casts at most
    /// `photons · (1 + bounce_budget)` rays whatever the scene (issue 32: a glass asset whose
    /// light runs through long chains of interfaces made the trace follow those chains, not
    /// the photon count). Default 8 (ours: the brilliant-cut gem room uses 4.2 events per
    /// photon and the budget never binds on the test scenes). Paths in flight when the budget
    /// is spent stop there, counted as `budget_stopped` with their flux in `flux_max_depth`
    /// (energy is accounted, not lost unseen); the dispatch's later photons stop first, so a
    /// binding budget darkens part of the caustic: raise it or lower the photon count.
    /// Range [0.05, 128]; at 128 no path can run out before `max_bounces`.
    #[reflect(@0.05_f32..=128.0_f32)]
    pub bounce_budget: f32,
    /// Frames in the running mean of the shared temporal stage (`render::temporal`): each frame
    /// traces a freshly rotated sample pattern, so the mean gathers independent photons and a
    /// still view settles on it rather than on one frame's grain. Default 32 (ours). 1 shows
    /// each frame alone. Range [1, 1024]. Cost: 48 bytes per pixel and one full-screen pass.
    /// A moving camera reprojects it (by each pixel's surface); a changed scene keeps it where
    /// the caustic did not change (`history_clamp`).
    #[reflect(@1_u32..=1024_u32)]
    pub history_frames: u32,
    /// On a frame in which the scene changed, a pixel's history is dropped where its luminance
    /// lies outside the current frame's 3x3 luminance mean ± this many standard errors of that
    /// mean (a moved caustic leaves no ghost). Default 1 (ours: the ball of `glass_sphere`
    /// sliding 1 cm a frame, RMSE against each frame's reference 261 lx at 2, 210 at 1, 200 at
    /// 0.5; a lower value keeps less history of caustics that did not change while another
    /// moves). Range [0, 100]; 0 drops it wherever it differs from that mean.
    #[reflect(@0.0_f32..=100.0_f32)]
    pub history_clamp: f32,
    /// Adapt the density every frame. Default true. `false` freezes it at the uniform
    /// density the budget allows (for comparisons).
    pub adaptive: bool,
}

impl Default for AapsSettings {
    fn default() -> Self {
        Self {
            atlas_resolution: 128,
            target_area: 19.0,
            variance_gain: 4.0,
            temporal_weight: 0.5,
            min_density: 4.0,
            max_density: 0.0,
            cull_solid_angle: 0.05,
            drop_large_splats: false,
            msaa_threshold: 4.0,
            splat_scale: 1.5,
            max_anisotropy: 16.0,
            max_bounces: 64,
            splat_capacity: (1 << 21) - crate::render::aaps::view::SPLAT_GUARD_SPLATS as u32,
            budget_floor_share: 0.5,
            point_splat_area: 1.0,
            bounce_budget: 8.0,
            history_frames: 32,
            history_clamp: 1.0,
            adaptive: true,
        }
    }
}

impl AapsSettings {
    /// A copy with every field in range (what the GPU passes use).
    pub fn sanitized(&self) -> Self {
        let finite = |x: f32, d: f32| if x.is_finite() { x } else { d };
        let res = self.atlas_resolution.clamp(8, 1024);
        let res = if res.is_power_of_two() {
            res
        } else {
            let up = res.next_power_of_two();
            if up - res <= res - up / 2 { up } else { up / 2 }
        };
        Self {
            atlas_resolution: res.clamp(8, 1024),
            target_area: finite(self.target_area, 19.0).max(0.01),
            variance_gain: finite(self.variance_gain, 0.0).max(0.0),
            temporal_weight: finite(self.temporal_weight, 0.5).clamp(0.0, 1.0),
            min_density: finite(self.min_density, 4.0).clamp(1.0, 1.0e6),
            max_density: finite(self.max_density, 0.0).max(0.0),
            cull_solid_angle: finite(self.cull_solid_angle, 0.0).max(0.0),
            drop_large_splats: self.drop_large_splats,
            msaa_threshold: finite(self.msaa_threshold, 0.0).max(0.0),
            splat_scale: finite(self.splat_scale, 1.5).clamp(0.1, 16.0),
            max_anisotropy: finite(self.max_anisotropy, 16.0).max(1.0),
            max_bounces: self.max_bounces.clamp(1, 128),
            splat_capacity: self.splat_capacity.clamp(1, 1 << 24),
            budget_floor_share: finite(self.budget_floor_share, 0.5).clamp(0.0, 1.0),
            point_splat_area: finite(self.point_splat_area, 1.0).clamp(0.0, 16.0),
            bounce_budget: finite(self.bounce_budget, 8.0).clamp(0.05, 128.0),
            history_frames: self.history_frames.clamp(1, 1024),
            history_clamp: finite(self.history_clamp, 2.0).clamp(0.0, 100.0),
            adaptive: self.adaptive,
        }
    }

    /// [`Self::sanitized`], then the sizes bounded by the device: the atlas side by
    /// `max_atlas_resolution`, the splat capacity by `max_splat_capacity`.
    pub fn sanitized_for(&self, limits: &crate::limits::CausticsLimits) -> Self {
        let mut s = self.sanitized();
        s.atlas_resolution = s.atlas_resolution.min(limits.max_atlas_resolution);
        s.splat_capacity = s.splat_capacity.min(limits.max_splat_capacity);
        s
    }
}
