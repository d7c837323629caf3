use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponent;

/// A caustics volume: an oriented box (its `Transform` places, rotates and scales the unit box
/// times [`CausticsVolume::size`]) inside which caustics are computed by slab propagation
/// (seed 000) for cameras whose technique is [`crate::CausticsTechnique::Volume`]. Photons
/// enter through `entry` from every [`crate::CausticLight`], are marched slab by slab against
/// rasterised G-buffers, and those that leave through an `exit` face after a specular event are
/// projected onto the receivers beyond it and splatted. A face in neither list culls.
///
/// A volume lights only the part of a caster inside it: for a caster that moves, size the box
/// for its path or move the volume with it (for example as a child of an entity that follows
/// the caster's translation; a volume that turns with a spinning caster turns its entry face
/// away from the light). The headless renderer's fitted volumes are fitted again whenever the
/// casters' bounds change.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
#[require(Transform)]
pub struct CausticsVolume {
    /// Box size in local units before the Transform's scale. Default (1, 1, 1). Every
    /// component must be > 0: zero, negative or non-finite components are clamped to 1e-3 with
    /// a warning.
    pub size: Vec3,
    /// Slabs parallel to the entry face. Default 3. Range [1, 64]; 0 is clamped to 1 and
    /// values above 64 to 64, with a warning. Cost: one propagation pass per slab.
    #[reflect(@1_u32..=64_u32)]
    pub slabs: u32,
    /// Photon budget per update. Default 80 000 (the sweep behind the defaults, in CHANGELOG.md:
    /// FLIP against the reference at 128², glass_slab / glass_sphere, 0.029 / 0.078 with the
    /// old 20 000 photons, 200² projectors and blur 2, 0.025 / 0.070 with these; on lavapipe a
    /// full update costs about 4x). Range [0, 16 777 216]; negative values are
    /// clamped to 0 (a volume that traces nothing) with a warning. Signed so that a negative
    /// value from an editor or a script is reported instead of wrapping. Cost: linear. At most
    /// 4 194 240 are traced (one dispatch), fewer where the GPU's storage bindings are smaller
    /// (64 bytes per photon per slab); the entry face is divided among the photons traced, so
    /// the energy is the same.
    #[reflect(@0_i32..=16777216_i32)]
    pub photons: i32,
    /// Face photons enter through. Default `PosY` (the top).
    pub entry: VolumeFace,
    /// Faces whose projectors splat photons onto receivers. Default the face opposite entry.
    pub exit: Vec<VolumeFace>,
    /// Faces that terminate photons. Default none.
    pub culling: Vec<VolumeFace>,
    /// Side of each projector's square G-buffer, pixels. Default 400. Range [16, 4096],
    /// clamped with a warning. Cost: quadratic.
    #[reflect(@16_u32..=4096_u32)]
    pub projector_resolution: u32,
    /// Side of each slab's square G_near / G_far, pixels (`G_dims`). Default 200 (400 is
    /// sharper, FLIP 0.016 / 0.060 on glass_slab / glass_sphere, but the energy moves: -2.4 %
    /// on the slab, -8.6 % on an open brilliant against -1.7 % at 200). Measured causes, all
    /// of a texel's size: a photon inside glass that crosses a surface within about a texel of
    /// an inner slab boundary is found by neither slab and leaves the volume inside the medium
    /// (`left_inside` halves as the side doubles; on the brilliant this leaked light is 39 % of
    /// the floor caustic at 200 and 22 % at 800, so 200's figure is partly leak); photons that
    /// hop between slabs more than `4 · slabs + 4` times are dropped (counted as
    /// `step_limit`, their flux as `hop_limit_lm`); and a box aligned with the texel grid rounds its outline to whole
    /// texels (glass_slab: +0.8 % of the photons at 200, -0.76 % at 400, exact at 300 and 800).
    /// Range [16, 4096], clamped with a warning. Cost: two rasterisations per slab, quadratic.
    #[reflect(@16_u32..=4096_u32)]
    pub gbuffer_resolution: u32,
    /// Side of the coarsest density tile, in projector texels (section 3.4's grid). The tiles
    /// are adaptive: finer levels of `tile_size / 2`, `/ 4`, .. down to one texel are counted
    /// too, and each splat takes its density from the finest tile holding at least
    /// [`Self::density_photons`] photons, so a bright focus is sized from its own texels and a
    /// dim area from the whole tile. Default 16 (was a fixed grid of 4: with 16, splat overlap
    /// 16 and density photons 16, FLIP over the caustic against the reference fell on
    /// glass_sphere from 0.102 to 0.088 at 128², 0.161 to 0.115 at 320x240, on pool from 0.190
    /// to 0.155, on the gem room from 0.403 to 0.369 at 320x240; glass_slab and mirror_wall
    /// unchanged). Range [1, 64], clamped with a warning. Larger: smoother dim areas. Cost: one
    /// counter per texel at each level (`4 · 7 · Σ (max G-buffer side / level side)²` bytes:
    /// 6.0 MB at 400² projectors) and one atomic add per level per photon.
    #[reflect(@1_u32..=64_u32)]
    pub tile_size: u32,
    /// Photons a density tile must hold for a splat to take its density from it (the finest
    /// such tile wins; see [`Self::tile_size`]). Default 16 (a density within about 25 %).
    /// Range [1, 65 536], clamped with a warning. Smaller: sharper, noisier foci; 65 536 (no
    /// tile holds more) is the seed's fixed grid of `tile_size`. Energy does not depend on it.
    #[reflect(@1_u32..=65536_u32)]
    pub density_photons: u32,
    /// Photons a splat overlaps (`π r² = overlap · area per photon`, the area per photon from
    /// the density tiles). Default 16 (was 4; see [`Self::tile_size`]). Range [0.25, 64],
    /// clamped with a warning. Energy does not depend on it. Cost: the splat pass's fragments
    /// grow with it (on lavapipe at 320x240 the splat pass took 147 ms at 16, 77 at 4).
    #[reflect(@0.25_f32..=64.0_f32)]
    pub splat_overlap: f32,
    /// Radius of the depth- and normal-aware Gaussian applied to the volumes' contribution,
    /// camera pixels (sigma half of it). Default 1 (2 blurs a slab's sharp caustic edge: FLIP
    /// 0.016 -> 0.026 on glass_slab at 400² G-buffers); 0 turns the blur off. Range [0, 8], clamped with a warning.
    #[reflect(@0_u32..=8_u32)]
    pub blur_radius: u32,
    /// Slab level of detail (section 3.5): beyond this distance from the nearest camera, in
    /// volume diagonals, the slab count halves for every doubling of the distance. Default 8;
    /// 0 turns LOD off. Negative or non-finite values are clamped to 0 with a warning.
    #[reflect(@0.0_f32..=1.0e3_f32)]
    pub lod_distance: f32,
    /// Differential updates (section 3.5): a change inside slab k re-runs slab k onwards and
    /// the projectors only, reusing the stored photon states of the earlier slabs. Default on.
    pub differential: bool,
    /// A volume outside every caustics camera's frustum runs nothing (section 3.5). Default
    /// off: a volume's caustics usually land outside it (a mirror out of view lighting a wall
    /// in view, `mirror_wall`), and the paper's rule would drop them. Turn it on for volumes
    /// whose receivers are inside them or next to them.
    pub frustum_cull: bool,
    /// Progressive mode (section 3.5): photons traced per frame, the pool (`photons`) being
    /// the maximum; each frame's batch accumulates with the earlier ones (flux scaled by
    /// photons / traced, so every frame is an estimate of the full result) until the whole
    /// pool is traced, then nothing runs until something changes. A change inside the volume
    /// restarts the accumulation from the first slab. Default 0 (off: the whole pool per
    /// update); a value at least `photons` is the same as off. Cost per frame: linear in it.
    #[reflect(@0_u32..=16_777_216_u32)]
    pub progressive: u32,
    /// The one light this volume carries. Default `None`: every caustic light, the photon
    /// pool split equally between them (seed 000 section 3.4). A volume turned to one light
    /// ([`Self::fit`], [`Self::fit_point`]) should carry that light only: another light's rays
    /// enter through other faces, and a second volume around the same casters would count
    /// every light twice (the CLI fits one volume per light, each with its light here). A
    /// light that is not a caustic light leaves the volume dark, with a warning.
    pub light: Option<Entity>,
}

impl Default for CausticsVolume {
    fn default() -> Self {
        Self {
            size: Vec3::ONE,
            slabs: 3,
            photons: 80_000,
            entry: VolumeFace::PosY,
            exit: vec![VolumeFace::NegY],
            culling: vec![],
            projector_resolution: 400,
            gbuffer_resolution: 200,
            tile_size: 16,
            density_photons: 16,
            splat_overlap: 16.0,
            blur_radius: 1,
            lod_distance: 8.0,
            differential: true,
            frustum_cull: false,
            progressive: 0,
            light: None,
        }
    }
}

impl CausticsVolume {
    /// A volume around casters for one light (seed 000 §3.4: photons enter through the entry
    /// face "seeded with the current direction of the light"): the box's local +Y (the entry
    /// face `PosY`) points against `light_travel` (for a point or spot light, the direction
    /// from the light to the casters), the exit face is `NegY`, and the box holds the world
    /// AABB `casters` (min, max) grown by `margin` (a fraction of each extent, at least 1 mm).
    /// Every face but the entry is an exit, so light a mirror sends sideways or back up is
    /// projected too; no extent is below a quarter of the largest, so flat casters (a mirror)
    /// still get projectors with usable fields of view.
    ///
    /// Guards: a zero or non-finite direction is taken as straight down; a non-finite AABB
    /// gives a 1 m box at the origin; every extent is at least 1e-3 m (the validator's floor).
    pub fn fit(casters: (Vec3, Vec3), light_travel: Vec3, margin: f32) -> (Self, Transform) {
        let dir = light_travel.try_normalize().unwrap_or(Vec3::NEG_Y);
        let (lo, hi) = if casters.0.is_finite() && casters.1.is_finite() {
            (casters.0.min(casters.1), casters.0.max(casters.1))
        } else {
            (Vec3::splat(-0.5), Vec3::splat(0.5))
        };
        let rotation = Quat::from_rotation_arc(Vec3::Y, -dir);
        let center = (lo + hi) * 0.5;
        let inv = rotation.inverse();
        let mut local_half = Vec3::ZERO;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            local_half = local_half.max((inv * (corner - center)).abs());
        }
        let margin = if margin.is_finite() {
            margin.max(0.0)
        } else {
            0.0
        };
        let size = (local_half * 2.0 * (1.0 + margin) + Vec3::splat(2e-3)).max(Vec3::splat(1e-3));
        let size = size.max(Vec3::splat(size.max_element() * 0.25));
        (
            Self {
                size,
                exit: VolumeFace::ALL.to_vec(),
                ..Default::default()
            },
            Transform {
                translation: center,
                rotation,
                scale: Vec3::ONE,
            },
        )
    }

    /// A volume around casters for a point or spot light at `light` (see [`Self::fit`]): the
    /// light must lie beyond the entry face, over it (its foot on the face), or none of its light
    /// enters. The box faces the light when that holds (a light far from the casters); when
    /// it does not (a bulb beside or over a wide caster), its entry is turned from the light
    /// towards a world axis by a third, two thirds or all the way, the least turn for which
    /// it holds (the `ring` scene's bulb: two thirds towards +Y). In every case the entry face
    /// lies at the casters' margin and `fit`'s floor on the extents grows the box away from
    /// the light. `None` when no such box exists (the light inside the casters' box grown by
    /// `margin`).
    pub fn fit_point(casters: (Vec3, Vec3), light: Vec3, margin: f32) -> Option<(Self, Transform)> {
        let centre = (casters.0 + casters.1) * 0.5;
        let towards = (light - centre).try_normalize().unwrap_or(Vec3::Y);
        let mut axes = VolumeFace::ALL.map(VolumeFace::normal);
        axes.sort_by(|a, b| b.dot(towards).total_cmp(&a.dot(towards)));
        // The entry turned from the light towards each axis by a third, two thirds, all the
        // way: the least turn that leaves the light over the entry wins (a box turned only
        // part way still sees walls that an axis-aligned one would see edge on).
        let turned = [1.0 / 3.0, 2.0 / 3.0, 1.0].into_iter().flat_map(move |f| {
            axes.into_iter()
                .filter_map(move |a| towards.lerp(a, f).try_normalize())
        });
        std::iter::once(towards)
            .chain(turned)
            .map(|n| Self::fit_entry_tight(casters, n, margin))
            .find(|(v, t)| v.light_over_entry(t, light))
    }

    /// [`Self::fit`] with the entry face's outward normal `n`, the box moved away from the
    /// entry so that face lies at the casters' margin: `fit`'s floor of a quarter of the
    /// largest extent grows the box on the far side only (a bulb just over a flat caster stays
    /// over the entry face).
    fn fit_entry_tight(casters: (Vec3, Vec3), n: Vec3, margin: f32) -> (Self, Transform) {
        let (v, mut t) = Self::fit(casters, -n, margin);
        let up = t.rotation * Vec3::Y;
        let (lo, hi) = (casters.0.min(casters.1), casters.0.max(casters.1));
        let reach = (hi - lo).abs().dot(up.abs()) * 0.5;
        let tight = reach * (1.0 + margin.max(0.0)) + 1e-3;
        let slack = v.size.y * 0.5 - tight;
        if slack.is_finite() && slack > 0.0 {
            t.translation -= up * slack;
        }
        (v, t)
    }

    /// `light` lies beyond this volume's entry face and over it: every ray from it into the box
    /// crosses the entry face first.
    pub fn light_over_entry(&self, transform: &Transform, light: Vec3) -> bool {
        let local = transform.compute_affine().inverse().transform_point3(light);
        let n = self.entry.normal();
        let half = self.size * 0.5;
        let beyond = local.dot(n) > half.dot(n.abs());
        let across = (local - n * local.dot(n)).abs();
        let face = half - half * n.abs();
        beyond && across.cmple(face + Vec3::splat(1e-6)).all()
    }
}

/// A face of a volume's box, by the local axis of its outward normal.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VolumeFace {
    /// +X.
    PosX,
    /// -X.
    NegX,
    /// +Y.
    #[default]
    PosY,
    /// -Y.
    NegY,
    /// +Z.
    PosZ,
    /// -Z.
    NegZ,
}

impl VolumeFace {
    /// The six faces, in face-code order (+X, -X, +Y, -Y, +Z, -Z).
    pub const ALL: [VolumeFace; 6] = [
        Self::PosX,
        Self::NegX,
        Self::PosY,
        Self::NegY,
        Self::PosZ,
        Self::NegZ,
    ];

    /// Outward unit normal in the volume's local space.
    pub fn normal(self) -> Vec3 {
        match self {
            Self::PosX => Vec3::X,
            Self::NegX => Vec3::NEG_X,
            Self::PosY => Vec3::Y,
            Self::NegY => Vec3::NEG_Y,
            Self::PosZ => Vec3::Z,
            Self::NegZ => Vec3::NEG_Z,
        }
    }
}

/// Draws every [`CausticsVolume`] into this camera's image as lines (a debug view): the entry
/// face with a cross, exit faces, culling faces and the planes between slabs, each in its own
/// colour (the lines of [`crate::volume::volume_gizmo_segments`]). Put it on a camera with
/// [`crate::Caustics`]. The lines are drawn after tone mapping, so the colours appear as
/// given, whatever the exposure. Without this component, or without a volume, nothing is
/// drawn and no pass runs.
///
/// Cost: one line-list draw per camera, 8 to 14 lines per face set plus 4 per slab plane.
#[derive(Component, Reflect, Clone, Debug, PartialEq, ExtractComponent)]
#[reflect(Component, Default, Clone)]
#[extract_component_filter(With<Camera>)]
#[extract_component_sync_target((Self, crate::render::volume::gizmo::VolumeGizmoView))]
pub struct CausticsVolumeGizmos {
    /// Entry face. Default yellow (1, 1, 0).
    pub entry: Color,
    /// Exit faces. Default green (0, 1, 0).
    pub exit: Color,
    /// Culling faces. Default red (1, 0, 0).
    pub culling: Color,
    /// Planes between slabs. Default cyan (0, 1, 1).
    pub slab_planes: Color,
    /// Draw the planes between slabs. Default on.
    pub show_slab_planes: bool,
    /// Hide lines behind the scene's geometry (against the depth prepass, 0.5 % of the
    /// distance as margin). Default on.
    pub depth_test: bool,
    /// Face outlines are inset towards the face centre by this fraction of the face's
    /// extents, so neighbouring faces stay apart. Default 0.02. Range [0, 0.45] (clamped
    /// where used).
    #[reflect(@0.0_f32..=0.45_f32)]
    pub inset: f32,
}

impl Default for CausticsVolumeGizmos {
    fn default() -> Self {
        Self {
            entry: Color::srgb(1.0, 1.0, 0.0),
            exit: Color::srgb(0.0, 1.0, 0.0),
            culling: Color::srgb(1.0, 0.0, 0.0),
            slab_planes: Color::srgb(0.0, 1.0, 1.0),
            show_slab_planes: true,
            depth_test: true,
            inset: 0.02,
        }
    }
}

impl CausticsVolumeGizmos {
    /// The colour of a line of `kind`.
    pub fn colour(&self, kind: crate::volume::VolumeGizmoKind) -> Color {
        use crate::volume::VolumeGizmoKind as K;
        match kind {
            K::Entry => self.entry,
            K::Exit => self.exit,
            K::Culling => self.culling,
            K::SlabPlane => self.slab_planes,
        }
    }
}
