use bevy::prelude::*;

/// Settings of the [`crate::CausticsTechnique::PhotonMap`] technique (a hash-grid photon map
/// gathered per pixel, seed 001, with progressive radius reduction). Put it on the camera next
/// to [`crate::Caustics`]; without it the defaults below are used. Defaults are the seed's or
/// the progressive photon mapping papers' where they give a value and marked "ours" where not.
///
/// The photon count per light and frame comes from [`crate::Caustics::quality`].
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
pub struct PhotonMapSettings {
    /// Gather radius of the first frame, as a fraction of the radius of the casters' bounding
    /// sphere (so it scales with the scene: a 2 cm glass ball and a 20 m pool get the same
    /// look). It is also the grid's cell size. A pixel never gathers with less than its own
    /// footprint (`optics::gather_radius`). Default 0.02 (ours: on `ring` and `glass_sphere`
    /// the lowest error after 64 progressive frames of 0.01, 0.02 and 0.03, see the module doc
    /// of `render::photon_map`). Range [1e-4, 1]. Cost:
    /// each pixel visits the photons of 27 cells, so the gather's time grows with `r³` of
    /// photon density; a small radius is noisier.
    #[reflect(@1.0e-4_f32..=1.0_f32)]
    pub radius: f32,
    /// Specular events a photon may go through before it is dropped (counted, with the flux
    /// it still carries, as `flux_max_depth`). After 8 events
    /// ([`crate::optics::ROULETTE_DEPTH`], as the reference tracer) Russian roulette ends
    /// paths whose flux the chain has reduced (metals, absorbing media; unbiased, the
    /// survivors carry it), so the limit only binds light trapped in clear glass. Default 64
    /// (as `AapsSettings::max_bounces`: a brilliant-cut IOR 2.4 gem in a closed room of
    /// receivers keeps all but 0.7 % of the power that strikes it; the reference tracer loses
    /// 5.9 % at 16). Range [1, 128]. Also the most mirrors a pixel's ray follows with
    /// `mirrors`. Cost: only the paths that bounce that often pay for it.
    #[reflect(@1_u32..=128_u32)]
    pub max_bounces: u32,
    /// The grid's memory budget in cells (4 bytes each; the grid also keeps one scan word per
    /// 1024 cells). When the photons' bounds would need more cells at the gather radius, the
    /// cell size doubles until they fit (counted as `coarsened`): the gather stays exact
    /// (cells at least as large as the radius), each pixel only visits more photons. Default
    /// 2^20 (4 MiB, ours). Range [2^12, 2^20]. Cost: the prefix sum runs over the whole
    /// budget every frame.
    #[reflect(@4096_u32..=1048576_u32)]
    pub max_grid_cells: u32,
    /// Accumulate frames while nothing changes (progressive photon mapping in the memoryless
    /// form of Knaus and Zwicker 2011): frame `i` gathers with `r_i² = r_{i−1}² (i − 1 + α) /
    /// i` and the caustics buffer shows the mean of the frames, so the error keeps falling
    /// towards the reference. A change of the view or these settings starts again, and so does
    /// a change of the scene that can change a caustic (`scene::change`; a receiver moved
    /// elsewhere restarts only the pixels whose surface moved). Default true. `false` shows each frame's own gather at `radius`.
    pub progressive: bool,
    /// Progressive photon mapping's α, the share of photons kept per frame: the radius falls
    /// as `i^((α−1)/2)`. Default 0.7 (Hachisuka and Jensen). Range [0.05, 1].
    #[reflect(@0.05_f32..=1.0_f32)]
    pub alpha: f32,
    /// Frames accumulated at most; after it the image stays (nothing is traced until
    /// something changes). Default 1024 (ours). Range [1, 65 536].
    #[reflect(@1_u32..=65536_u32)]
    pub max_frames: u32,
    /// A photon counts at a pixel only if the cosine between its surface normal and the
    /// pixel's is at least this (no light leaking through thin walls or round corners).
    /// Default 0.7 (ours, 45.6°). Range [-1, 1]; -1 turns the test off.
    #[reflect(@-1.0_f32..=1.0_f32)]
    pub normal_threshold: f32,
    /// Algorithm 1 of the seed: an 8x8 tile of pixels whose points all fall into one grid
    /// cell loads that cell's neighbourhood into workgroup memory together (tiles whose cells
    /// differ gather pixel by pixel, counted). Default false: the seed measured it marginal
    /// (table 4), and so did we on lavapipe (see the closing note of the issue and the
    /// bench). Cost: one workgroup-wide reduction per tile.
    pub shared_memory: bool,
    /// Caustics seen in mirrors: a pixel showing a mirror (a conductor the camera ray hits
    /// first) follows the reflected ray through the BVH (up to `max_bounces` mirrors) to the
    /// diffuse point it shows, gathers there and shows `F · albedo / π · E`. Default true.
    /// Cost: one BVH ray per pixel while the scene holds a mirror; nothing otherwise.
    pub mirrors: bool,
    /// The right eye of a [`crate::CausticsStereo`] pair takes the left eye's gathered
    /// irradiance where both eyes see the same point. Default true. `false` makes the right
    /// eye gather every pixel itself (it still shares the left eye's photons and grid).
    pub stereo_reuse: bool,
    /// Per-frame budget of specular events (reflections and refractions, summed over every
    /// photon's path), as a multiple of the photons the frame emits: the trace casts at most
    /// `photons · (1 + bounce_budget)` rays whatever the scene. Roulette ends paths whose
    /// flux a chain has reduced, but clear glass keeps a path's throughput at 1, so without
    /// it a glass asset that traps light in internal reflections makes every photon run to
    /// `max_bounces`. Default 8 (as `AapsSettings::bounce_budget`; the gem room uses under 5
    /// per photon). Paths in flight when the budget is spent stop there, counted as
    /// `budget_stopped` with their flux in `flux_max_depth`; the dispatch's later photons
    /// (the last lights') stop first. Range [0.05, 128].
    #[reflect(@0.05_f32..=128.0_f32)]
    pub bounce_budget: f32,
    /// Photons a pixel's gather aims to hold per frame, or 0 for every pixel at the view's
    /// radius. Once the view has gathered a frame, each pixel's radius is that of the disc
    /// holding this many photons of the density its earlier frames found there
    /// (`optics::density_radius`, the k-nearest-neighbour radius of a balloon estimator),
    /// between a quarter and twice the radius it would have had: a dim area is smoothed and a
    /// bright focus narrows. The density comes from earlier frames, never from the photons the
    /// frame gathers, so each frame stays a kernel estimate; it is kept through a change of
    /// the scene (a moving caster's next frame is sized too) and dropped when the camera, the
    /// viewport or these settings change. Default 0 (off, ours): it helps where the error is
    /// noise and hurts where it is the blur of a sharp caustic curve. Measured at 64 (report
    /// sweep, 8 frames, 2^16 photons per light): RMSE on `mirror_wall` -35 %, `glass_slab`
    /// -13 %, `glass_sphere` -23 %, `pool` -11 %, but `ring` (a point light's nephroid) +33 %
    /// with its FLIP 0.040 -> 0.053; on `glass_sphere` at frames 17 to 24 (128², 2^16) RMSE
    /// 76.0 -> 63.3 lx, flicker 0.0158 -> 0.0099, a sliding ball 130.5 -> 108.6 lx (see
    /// `docs/photon-map.md`). Range [0, 4096]. Cost: none to the gather (one more float per
    /// pixel read and written; the per-pixel buffer already held it).
    #[reflect(@0.0_f32..=4096.0_f32)]
    pub gather_photons: f32,
}

impl Default for PhotonMapSettings {
    fn default() -> Self {
        Self {
            radius: 0.02,
            max_bounces: 64,
            max_grid_cells: 1 << 20,
            progressive: true,
            alpha: 0.7,
            max_frames: 1024,
            normal_threshold: 0.7,
            shared_memory: false,
            mirrors: true,
            stereo_reuse: true,
            bounce_budget: 8.0,
            gather_photons: 0.0,
        }
    }
}

impl PhotonMapSettings {
    /// A copy with every field in range (what the GPU passes use); non-finite values become
    /// the defaults.
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let f = |x: f32, d: f32, lo: f32, hi: f32| if x.is_finite() { x.clamp(lo, hi) } else { d };
        Self {
            radius: f(self.radius, d.radius, 1e-4, 1.0),
            max_bounces: self.max_bounces.clamp(1, 128),
            max_grid_cells: self.max_grid_cells.clamp(1 << 12, 1 << 20),
            progressive: self.progressive,
            alpha: f(self.alpha, d.alpha, 0.05, 1.0),
            max_frames: self.max_frames.clamp(1, 65_536),
            normal_threshold: f(self.normal_threshold, d.normal_threshold, -1.0, 1.0),
            shared_memory: self.shared_memory,
            mirrors: self.mirrors,
            stereo_reuse: self.stereo_reuse,
            bounce_budget: f(self.bounce_budget, d.bounce_budget, 0.05, 128.0),
            gather_photons: f(self.gather_photons, d.gather_photons, 0.0, 4096.0),
        }
    }
}
