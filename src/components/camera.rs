use bevy::camera::Hdr;
use bevy::core_pipeline::prepass::{DeferredPrepass, DepthPrepass};
use bevy::prelude::*;

/// Caustics for this camera: put it on a `Camera3d`.
///
/// It requires [`Hdr`] (the composite adds linear irradiance into the HDR target before
/// tone mapping) and the deferred prepasses (the composite reads the diffuse albedo from the
/// G-buffer). [`crate::CausticsPlugin`] makes deferred the default opaque method; receivers
/// rendered forward get no caustic (one warning each).
///
/// # Usage Notes
/// Views without this component, and shadow views, run no caustics pass at all. A camera
/// with it but a scene without a [`crate::CausticLight`] or without a caster dispatches
/// nothing either.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
#[require(Hdr, DepthPrepass, DeferredPrepass)]
pub struct Caustics {
    /// Which algorithm fills the caustics buffer. Default [`CausticsTechnique::Aaps`] (real
    /// time, on the GPU); `Reference` is the CPU ground truth.
    pub technique: CausticsTechnique,
    /// Quality preset: photons per light for the reference tracer, the photon budget per light
    /// per frame for AAPS. Default `Medium`.
    pub quality: CausticsQuality,
    /// What the composite shows. Default `Off` (normal shading).
    pub debug_view: CausticsDebugView,
    /// Seed of the random streams of stochastic techniques. Default 1. Any value.
    pub seed: u64,
    /// Frames in which the technique ran and nothing the caustics depend on changed (the
    /// scene's lights, casters, receivers and materials, the camera, the size, the settings)
    /// after which the view keeps its caustics buffer and dispatches nothing until something
    /// changes. Frames whose passes could not run (a window's pipelines still compiling) do
    /// not count, so what is kept is always a filled buffer. Default
    /// 16 (AAPS's task buffer has settled by then, so what it keeps is what it would trace
    /// again). 0: every frame runs its technique. Costs nothing; a still frame then costs only
    /// the composite. The photon map's progressive mean freezes by its own `max_frames`.
    #[reflect(@0_u32..=1024_u32)]
    pub settle_frames: u32,
}

impl Default for Caustics {
    fn default() -> Self {
        Self {
            technique: CausticsTechnique::Aaps,
            quality: CausticsQuality::Medium,
            debug_view: CausticsDebugView::Off,
            seed: 1,
            settle_frames: 16,
        }
    }
}

/// The algorithm that computes caustic irradiance.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CausticsTechnique {
    /// The CPU ground-truth light tracer (multi-threaded, deterministic). Renders once per
    /// scene change on a background task and uploads the image; seconds, not milliseconds.
    Reference,
    /// Adaptive anisotropic photon scattering on the GPU (seed 004): compute-shader photon
    /// tracing through the scene BVH with photon differentials, anisotropic splats
    /// rasterised into the caustics buffer, and a task buffer that adapts the photon density
    /// every frame. Milliseconds per frame. Settings: [`crate::AapsSettings`]. The default.
    #[default]
    Aaps,
    /// Caustics volumes (seed 000): photons seeded on each [`crate::CausticsVolume`]'s entry
    /// face, marched slab by slab against rasterised G-buffers (no ray tracing), projected
    /// onto the receivers beyond the exit faces and splatted. Work is redone only when
    /// something inside changes (differential updates); otherwise only the splats are drawn.
    /// Settings: the fields of [`crate::CausticsVolume`]. Without a volume nothing runs.
    Volume,
    /// Cascaded image-space photon tracing (seed 003): photons start on each light's
    /// reflective shadow maps (rasterised by the plugin), are marched through the light's
    /// depth and then the camera's (no BVH, no ray tracing), land in a per-pixel photon map
    /// and are denoised by SVGF. One event on a caster's outside (two refractions through a
    /// closed glass object, with the reflections inside it), then up to 4 further mirrors.
    /// Milliseconds per frame. Settings: [`crate::ImageSpaceSettings`].
    ImageSpace,
    /// Hash-grid photon mapping (seed 001): photons traced through the scene BVH (like AAPS)
    /// and stored at their first diffuse hit after a specular one, sorted into a uniform grid
    /// of cell size r on the GPU, and gathered per pixel within r (the 3x3x3 cells as 9 row
    /// ranges); on a still view the frames accumulate with a shrinking radius (progressive
    /// photon mapping), so the error keeps falling towards the reference. Milliseconds per
    /// frame. Settings: [`crate::PhotonMapSettings`].
    PhotonMap,
}

impl CausticsTechnique {
    /// Name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Reference => "reference",
            Self::Aaps => "aaps",
            Self::Volume => "volume",
            Self::ImageSpace => "image_space",
            Self::PhotonMap => "photon_map",
        }
    }

    /// Parse a command-line name.
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "reference" => Some(Self::Reference),
            "aaps" => Some(Self::Aaps),
            "volume" => Some(Self::Volume),
            "image_space" => Some(Self::ImageSpace),
            "photon_map" => Some(Self::PhotonMap),
            _ => None,
        }
    }
}

/// Quality presets. Cost grows linearly with the photon count.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CausticsQuality {
    /// 65 536 photons per light.
    Low,
    /// 262 144 photons per light.
    #[default]
    Medium,
    /// 1 048 576 photons per light.
    High,
    /// An explicit photon count per light (0 traces nothing).
    Custom {
        /// Photons per light.
        photons: u64,
    },
}

impl CausticsQuality {
    /// Photons per light for the reference tracer.
    pub fn photons_per_light(self) -> u64 {
        match self {
            Self::Low => 1 << 16,
            Self::Medium => 1 << 18,
            Self::High => 1 << 20,
            Self::Custom { photons } => photons,
        }
    }
}

/// Debug output of the composite.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CausticsDebugView {
    /// Normal shading: caustic light added as `albedo / π · E · exposure`.
    #[default]
    Off,
    /// Adds the caustic irradiance as if every surface were white (albedo 1), to see the
    /// caustics buffer itself.
    WhiteAlbedo,
    /// The technique runs but nothing is composited: the frame without caustics, to compare
    /// (the inspector's A/B switch). Costs what `Off` costs, less the composite pass.
    Hidden,
}

/// Which eye of a stereo pair a caustics camera is.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum StereoEye {
    /// Rendered first (give it the lower `Camera::order`); it traces the photons.
    #[default]
    Left,
    /// Rendered second; reuses the left eye's work.
    Right,
}

/// Pairs two caustics cameras as the eyes of one stereo view (a VR headset: two ordinary
/// cameras, one per eye, as `bevy_mod_openxr` spawns them). Put it on both, with the same
/// `pair`, and give the left eye the lower `Camera::order`.
///
/// What is shared:
/// - `PhotonMap`: the photons are traced and the hash grid is built once per frame, by the
///   left eye; the right eye gathers from the left's grid, and takes the left eye's gathered
///   irradiance for every pixel whose point the left eye sees too (the point reprojected into
///   the left view, interpolated over 4 pixels whose points lie within 2 % of its distance),
///   gathering only the rest. Irradiance does not depend on the eye.
/// - `Aaps`: one trace (the left eye's task buffer); each eye rasterises the splats with its own
///   projection and depth.
/// - `Volume`: each volume propagates once per frame for every view; each eye splats it.
/// - `ImageSpace` and `Reference` run per eye.
///
/// Without a left partner, a right eye works alone.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Default, Clone)]
pub struct CausticsStereo {
    /// Which eye.
    pub eye: StereoEye,
    /// The pair's id (any value; both eyes share it).
    pub pair: u32,
}
