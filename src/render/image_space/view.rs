//! Image-space state (render world): the scene's triangles and each caustic light's RSM view
//! (rebuilt per scene generation), and per view the RSM array, the photon map, the
//! denoiser's textures and the uniforms of the frame.

use std::sync::Arc;

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferUsages, Extent3d, Texture, TextureDescriptor, TextureDimension,
    TextureUsages, TextureView, TextureViewDescriptor, TextureViewDimension,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::ExtractedView;

use super::pipelines::{RSM_DEPTH_FORMAT, RSM_FORMAT};
use crate::components::{CausticsTechnique, ImageSpaceSettings};
use crate::render::temporal::TemporalAccumulation;

use crate::render::trace::scene::{ExtractedCausticsScene, GpuLight, caster_sphere, gpu_lights};
use crate::render::volume::gpu::VolumeScene;
use crate::render::{ExtractedCaustics, view_texture};
use crate::scene::bvh::MeshGeometry;

pub use super::rsm_view::{MAX_CONE_HALF_ANGLE, RsmLight, rsm_light, rsm_sources};

/// Bytes between two lights' `IsLight` uniforms (dynamic offsets).
pub const LIGHT_STRIDE: u64 = 512;
/// Bytes between two `RsmView` uniforms and between two filter-step uniforms.
pub const SMALL_STRIDE: u64 = 256;
/// Counter words (`C_*` in trace.wgsl).
pub const COUNTER_WORDS: u64 = 32;
/// Filter-step uniforms: the variance pass and at most 8 à-trous iterations; then
/// [`MAX_MIPS`] Hi-Z build steps per plane.
pub const STEPS: u64 = 9;
/// Most levels of a Hi-Z pyramid (a 32 768² view).
pub const MAX_MIPS: usize = 16;

/// The levels of a nearest-depth pyramid over `size`: their count and word offsets, and the
/// words of the whole pyramid. Level L is `ceil(size / 2^L)`, down to 1x1.
pub fn hiz_levels(size: UVec2) -> (u32, [u32; MAX_MIPS], u32) {
    let mut offsets = [0u32; MAX_MIPS];
    let mut words = 0u32;
    let mut n = 0;
    let mut s = size.max(UVec2::ONE);
    loop {
        offsets[n] = words;
        words += s.x * s.y;
        n += 1;
        if (s.x == 1 && s.y == 1) || n == MAX_MIPS {
            break;
        }
        s = (s + UVec2::ONE) / 2;
    }
    (n as u32, offsets, words)
}

/// Where the Hi-Z pyramids live in their buffer (plane 0 the camera's, then per light view
/// its opaque and caster-back layers').
#[derive(Clone, Copy, Debug)]
pub struct HizLayout {
    /// Camera levels and offsets.
    pub camera: (u32, [u32; MAX_MIPS]),
    /// RSM levels and offsets within a plane.
    pub rsm: (u32, [u32; MAX_MIPS]),
    /// Words per RSM plane.
    pub plane_words: u32,
    /// First RSM plane's word.
    pub rsm_base: u32,
    /// Planes (1 + 2 per light view).
    pub planes: u32,
}

impl HizLayout {
    /// The layout for `key`.
    pub fn new(key: &ImageSpaceKey) -> Self {
        let (cl, co, cw) = hiz_levels(key.size);
        let (rl, ro, rw) = hiz_levels(UVec2::splat(key.rsm));
        Self {
            camera: (cl, co),
            rsm: (rl, ro),
            plane_words: rw,
            rsm_base: cw,
            planes: 1 + 2 * key.lights,
        }
    }

    /// Words of the buffer.
    pub fn words(&self) -> u64 {
        self.rsm_base as u64 + (self.planes as u64 - 1) * self.plane_words as u64
    }

    /// Levels of `plane`.
    pub fn levels(&self, plane: u32) -> u32 {
        if plane == 0 {
            self.camera.0
        } else {
            self.rsm.0
        }
    }

    /// Index of the steps-buffer entry of (`plane`, `level`).
    pub fn step(plane: u32, level: u32) -> u64 {
        STEPS + plane as u64 * MAX_MIPS as u64 + level as u64
    }
}

/// A view of the scene from a light or the camera, as `SpaceView` in trace.wgsl.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpaceView {
    /// Projection.
    pub clip_from_view: Mat4,
    /// View from world.
    pub view_from_world: Mat4,
    /// Width and height (pixels or texels), focal lengths in pixels.
    pub size: Vec4,
    /// Eye (an orthographic view's origin) and the near distance (0: orthographic).
    pub eye: Vec4,
}

impl SpaceView {
    /// The 288 bytes of the GPU layout.
    pub fn bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(288);
        for m in [
            self.clip_from_view,
            self.clip_from_view.inverse(),
            self.view_from_world,
            self.view_from_world.inverse(),
        ] {
            push(&mut b, &m.to_cols_array());
        }
        push(&mut b, &self.size.to_array());
        push(&mut b, &self.eye.to_array());
        b
    }
}

pub(super) fn push(b: &mut Vec<u8>, v: &[f32]) {
    b.extend(v.iter().flat_map(|x| x.to_le_bytes()));
}

/// The scene for the image-space technique: world-space triangles and materials (the same
/// buffers the volumes rasterise) and the lights that reach a caster.
#[derive(Resource)]
pub struct ImageSpaceScene {
    /// Triangles, materials, bounds, scale.
    pub scene: VolumeScene,
    /// The RSM views: lights that reach a caster, in the AAPS light order, with their cube
    /// face ([`rsm_sources`]).
    pub lights: Vec<(GpuLight, Option<u8>)>,
    /// Casters' bounding sphere.
    pub casters: (Vec3, f32),
    /// The scene's bounding sphere.
    pub bounds: (Vec3, f32),
    /// Some caster is a dielectric (the trace's variant, `render::trace::TraceFeatures`).
    pub dielectrics: bool,
    /// A reflected photon may meet a caster again: two casters or more, or one whose shape
    /// reflects onto itself ([`crate::scene::bvh::MeshGeometry::reflects_onto_itself`]; a
    /// ring, not a ball or a wall). The trace variant then marches the casters' front layer
    /// after a reflection (`render::trace::TraceFeatures::caster_chains`).
    pub mirror_chains: bool,
}

/// Build [`ImageSpaceScene`] when the gathered scene changes and a camera uses the technique;
/// none when no caustic light reaches a caster.
pub fn prepare_image_space_scene(
    mut commands: Commands,
    device: Res<RenderDevice>,
    extracted: Option<Res<ExtractedCausticsScene>>,
    current: Option<Res<ImageSpaceScene>>,
    views: Query<&ExtractedCaustics>,
    mut idle: Local<Option<u64>>,
    mut shapes: Local<ShapeCache>,
) {
    let wanted = views
        .iter()
        .any(|c| c.technique == CausticsTechnique::ImageSpace);
    let Some(extracted) = extracted.filter(|_| wanted) else {
        if current.is_some() {
            commands.remove_resource::<ImageSpaceScene>();
        }
        *idle = None;
        return;
    };
    let generation = extracted.0.generation;
    if current
        .as_ref()
        .is_some_and(|c| c.scene.generation == generation)
        || *idle == Some(generation)
    {
        return;
    }
    let tlas = &extracted.0.tlas;
    let lights: Vec<GpuLight> = gpu_lights(tlas, &extracted.0.lights)
        .into_iter()
        .map(|(_, l)| l)
        .collect();
    let casters = caster_sphere(tlas);
    let (Some(casters), false) = (casters, lights.is_empty()) else {
        if current.is_some() {
            commands.remove_resource::<ImageSpaceScene>();
        }
        *idle = Some(generation);
        return;
    };
    let bounds = tlas.bounds_where(|_| true).map_or(casters, |(lo, hi)| {
        ((lo + hi) * 0.5, ((hi - lo) * 0.5).length())
    });
    commands.insert_resource(ImageSpaceScene {
        scene: VolumeScene::build(&device, &extracted.0),
        lights: rsm_sources(&lights, casters),
        casters,
        bounds,
        dielectrics: tlas
            .instances
            .iter()
            .any(|i| matches!(i.surface, crate::scene::Surface::Dielectric { .. })),
        mirror_chains: mirror_chains(tlas, &mut shapes),
    });
    *idle = None;
}

/// The last single caster's mesh and its answer (a moving scene rebuilds the image-space
/// scene every frame; the test is O(triangles x vertices)).
type ShapeCache = Option<(Arc<MeshGeometry>, bool)>;

/// Whether a photon reflected off a caster may meet a caster again (see
/// [`ImageSpaceScene::mirror_chains`]).
fn mirror_chains(tlas: &crate::scene::bvh::Tlas, cache: &mut ShapeCache) -> bool {
    let mut casters = tlas
        .instances
        .iter()
        .filter(|i| !matches!(i.surface, crate::scene::Surface::Diffuse { .. }));
    let one = match (casters.next(), casters.next()) {
        (Some(one), None) => &one.blas.geometry,
        (Some(_), Some(_)) => return true,
        _ => return false,
    };
    match cache {
        Some((mesh, answer)) if Arc::ptr_eq(mesh, one) => *answer,
        _ => {
            let answer = one.reflects_onto_itself();
            *cache = Some((one.clone(), answer));
            answer
        }
    }
}

/// What forces a view's state to be rebuilt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageSpaceKey {
    /// Viewport.
    pub size: UVec2,
    /// RSM side.
    pub rsm: u32,
    /// Lights.
    pub lights: u32,
}

/// A view-sized texture with its default view.
pub type Tex = (Texture, TextureView);

/// Per-view state of the image-space technique.
#[derive(Component)]
pub struct ImageSpaceViewState {
    /// Layout key.
    pub key: ImageSpaceKey,
    /// RSM array (3 layers per light: opaque, caster front, caster back) and its array view.
    pub rsm: (Texture, TextureView),
    /// One 2D view per RSM layer (render attachments).
    pub rsm_layers: Vec<TextureView>,
    /// RSM depth attachment.
    pub rsm_depth: TextureView,
    /// Photon map: 64-bit fixed point per channel (6 words per pixel).
    pub map: Buffer,
    /// Counters.
    pub counters: Buffer,
    /// This frame's raw photon map (lux).
    pub raw: Tex,
    /// Filter ping-pong (the temporal result lives here too).
    pub filter: [Tex; 2],
    /// View depth and normal, this frame's and last frame's (by parity).
    pub zn: [Tex; 2],
    /// Colour history (rgb, history length) by parity.
    pub history: [Tex; 2],
    /// Luminance moments (m1, m2, history length) by parity.
    pub moments: [Tex; 2],
    /// Per-pixel à-trous data from the prep pass: (0, luminance deviation, depth gradient).
    pub aux: Tex,
    /// 1x1 placeholders for unused texture slots: one sampled, three storage.
    pub dummy_in: TextureView,
    /// See `dummy_in`.
    pub dummy_out: [TextureView; 3],
    /// Hi-Z pyramids (f32 words, [`HizLayout`]).
    pub hiz: Buffer,
    /// Their layout.
    pub hiz_layout: HizLayout,
    /// `IsParams`.
    pub params: Buffer,
    /// `IsLight` per light, [`LIGHT_STRIDE`] apart.
    pub lights: Buffer,
    /// `RsmView` per light, [`SMALL_STRIDE`] apart.
    pub rsm_views: Buffer,
    /// Filter steps, [`SMALL_STRIDE`] apart.
    pub steps: Buffer,
    /// Frames traced so far.
    pub frame: u32,
    /// The scene's caustic generation of the last frame (`scene::change`: a change that can
    /// change a caustic resets the history; others keep it).
    pub generation: Option<u64>,
    /// Frames since the SVGF history was last reset (the shared temporal stage's `frames`).
    pub since_reset: u32,
    /// The previous frame's `clip_from_world`.
    pub prev_clip_from_world: Option<Mat4>,
    /// The view and its caustics stand this frame ([`FLAG_STILL_VIEW`]).
    pub still_view: bool,
    /// Sanitised settings of this frame.
    pub settings: ImageSpaceSettings,
    /// Photons per light this frame.
    pub photons: u32,
    /// The scene generation the RSMs were last drawn for (`u64::MAX`: never): they depend on
    /// the lights and the geometry only, so a camera move does not redraw them.
    pub rsm_drawn: std::sync::atomic::AtomicU64,
}

impl ImageSpaceViewState {
    /// GPU bytes held (`render::memory`): every texture once (the layer views share theirs).
    pub fn gpu_bytes(&self) -> u64 {
        use crate::render::memory::{buffer_bytes, texture_bytes};
        let pairs = [&self.raw, &self.aux]
            .into_iter()
            .chain(&self.filter)
            .chain(&self.zn)
            .chain(&self.history)
            .chain(&self.moments);
        let textures = pairs.map(|t| &*t.0).chain([&*self.rsm.0]);
        let views = [&self.rsm_depth, &self.dummy_in]
            .into_iter()
            .chain(&self.dummy_out)
            .map(|v| v.texture());
        textures.chain(views).map(texture_bytes).sum::<u64>()
            + buffer_bytes([
                &self.map,
                &self.counters,
                &self.hiz,
                &self.params,
                &self.lights,
                &self.rsm_views,
                &self.steps,
            ])
    }
}

/// Marks a view whose image-space passes run this frame.
#[derive(Component)]
pub struct ImageSpaceFrame;

fn texture(
    device: &RenderDevice,
    label: &'static str,
    size: UVec2,
    layers: u32,
    format: bevy::render::render_resource::TextureFormat,
    usage: TextureUsages,
) -> Texture {
    device.create_texture(&TextureDescriptor {
        label: Some(label),
        size: Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

fn uniform(device: &RenderDevice, label: &'static str, size: u64) -> Buffer {
    device.create_buffer(&BufferDescriptor {
        label: Some(label),
        size,
        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl ImageSpaceViewState {
    fn new(device: &RenderDevice, key: ImageSpaceKey, settings: ImageSpaceSettings) -> Self {
        let layers = 3 * key.lights.max(1);
        let rsm = texture(
            device,
            "caustics:image_space:rsm",
            UVec2::splat(key.rsm),
            layers,
            RSM_FORMAT,
            TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING,
        );
        let rsm_view = rsm.create_view(&TextureViewDescriptor {
            dimension: Some(TextureViewDimension::D2Array),
            ..default()
        });
        let rsm_layers = (0..layers)
            .map(|l| {
                rsm.create_view(&TextureViewDescriptor {
                    dimension: Some(TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..default()
                })
            })
            .collect();
        let rsm_depth = texture(
            device,
            "caustics:image_space:rsm_depth",
            UVec2::splat(key.rsm),
            1,
            RSM_DEPTH_FORMAT,
            TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&TextureViewDescriptor::default());
        let pixels = key.size.x as u64 * key.size.y as u64;
        let storage = |label: &'static str, size: u64| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: BufferUsages::STORAGE | BufferUsages::COPY_DST | BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let usage = TextureUsages::TEXTURE_BINDING | TextureUsages::STORAGE_BINDING;
        let view_tex = |label| {
            let t = view_texture(device, label, key.size, usage);
            let v = t.create_view(&TextureViewDescriptor::default());
            (t, v)
        };
        let one = |label| {
            view_texture(device, label, UVec2::ONE, usage)
                .create_view(&TextureViewDescriptor::default())
        };
        Self {
            rsm_drawn: std::sync::atomic::AtomicU64::new(u64::MAX),
            key,
            rsm: (rsm, rsm_view),
            rsm_layers,
            rsm_depth,
            map: storage("caustics:image_space:photon_map", pixels * 24),
            counters: storage("caustics:image_space:counters", COUNTER_WORDS * 4),
            raw: view_tex("caustics:image_space:raw"),
            filter: [
                view_tex("caustics:image_space:filter0"),
                view_tex("caustics:image_space:filter1"),
            ],
            zn: [
                view_tex("caustics:image_space:zn0"),
                view_tex("caustics:image_space:zn1"),
            ],
            history: [
                view_tex("caustics:image_space:history0"),
                view_tex("caustics:image_space:history1"),
            ],
            moments: [
                view_tex("caustics:image_space:moments0"),
                view_tex("caustics:image_space:moments1"),
            ],
            aux: view_tex("caustics:image_space:atrous_aux"),
            dummy_in: one("caustics:image_space:dummy_in"),
            dummy_out: [
                one("caustics:image_space:dummy_out0"),
                one("caustics:image_space:dummy_out1"),
                one("caustics:image_space:dummy_out2"),
            ],
            hiz: storage("caustics:image_space:hiz", HizLayout::new(&key).words() * 4),
            hiz_layout: HizLayout::new(&key),
            params: uniform(device, "caustics:image_space:params", 1024),
            // Also read whole by the trace (`faces`: a mirror chain crosses a cube's faces).
            lights: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:image_space:lights"),
                size: LIGHT_STRIDE * key.lights.max(1) as u64,
                usage: BufferUsages::UNIFORM | BufferUsages::STORAGE | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            rsm_views: uniform(
                device,
                "caustics:image_space:rsm_views",
                SMALL_STRIDE * key.lights.max(1) as u64,
            ),
            steps: uniform(
                device,
                "caustics:image_space:steps",
                SMALL_STRIDE * HizLayout::step(1 + 2 * key.lights.max(1), 0),
            ),
            frame: 0,
            generation: None,
            since_reset: 0,
            prev_clip_from_world: None,
            still_view: false,
            settings,
            photons: 0,
        }
    }
}

/// The camera's `SpaceView`: Bevy's projection (infinite reverse-Z perspective or
/// orthographic) and the focal lengths `f = P00 w / 2`, `P11 h / 2` in pixels.
pub fn camera_space_view(view: &ExtractedView, size: UVec2) -> SpaceView {
    let p = view.clip_from_view;
    let world_from_view = view.world_from_view.to_matrix();
    let perspective = p.w_axis.w == 0.0;
    let near = if perspective {
        p.w_axis.z.abs().max(1e-6)
    } else {
        0.0
    };
    SpaceView {
        clip_from_view: p,
        view_from_world: world_from_view.inverse(),
        size: Vec4::new(
            size.x as f32,
            size.y as f32,
            0.5 * size.x as f32 * p.x_axis.x,
            0.5 * size.y as f32 * p.y_axis.y,
        ),
        eye: view.world_from_view.translation().extend(near),
    }
}

/// Flags of `IsParams.frame.w` (`FLAG_*` in trace.wgsl).
pub const FLAG_DENOISE: u32 = 1;
/// See [`FLAG_DENOISE`].
pub const FLAG_RESET: u32 = 2;
/// Step flag: the pass writes the colour history.
pub const FLAG_HISTORY: u32 = 4;
/// Step flag: the pass writes the caustics buffer.
pub const FLAG_LAST: u32 = 8;
/// The marches use the Hi-Z pyramids.
pub const FLAG_HIZ: u32 = 16;
/// The camera is where it was last frame and the caustics have not changed for more frames
/// than SVGF's mean is worth (`IsParams.frame.w`): SVGF's colour history is a plain mean of up
/// to `history_cap` frames (no `alpha_color` floor) of the unfiltered photon map
/// ([`history_step`]).
pub const FLAG_STILL_VIEW: u32 = 32;

/// The SVGF step that writes the colour history (0 the variance pass, `1 + i` à-trous
/// iteration `i`): SVGF's first iteration's output while the camera moves (reprojection needs
/// the quieter history), the unfiltered temporal mean while it stands (a plain mean of
/// filtered frames would blur the caustic a little more with every frame it keeps), and the
/// variance pass's output without iterations.
pub fn history_step(atrous_iterations: u32, still_view: bool) -> u32 {
    if atrous_iterations == 0 || still_view {
        0
    } else {
        1
    }
}

/// Create or resize each image-space view's state and write the frame's uniforms.
#[allow(clippy::type_complexity)]
pub fn prepare_image_space_views(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    scene: Option<Res<ImageSpaceScene>>,
    limits: Option<Res<crate::limits::CausticsLimits>>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&mut ImageSpaceViewState>,
        Option<&crate::render::settle::ViewSettle>,
    )>,
) {
    let limits = limits.map(|l| l.clone()).unwrap_or_default();
    for (entity, caustics, camera, view, state, settle) in &mut views {
        let size = camera.physical_viewport_size.unwrap_or_default();
        let active = caustics.technique == CausticsTechnique::ImageSpace
            && size.x > 0
            && size.y > 0
            && scene.is_some();
        if !active {
            commands.entity(entity).remove::<ImageSpaceFrame>();
            if caustics.technique == CausticsTechnique::ImageSpace {
                commands.entity(entity).remove::<TemporalAccumulation>();
            }
            if state.is_some() && caustics.technique != CausticsTechnique::ImageSpace {
                commands.entity(entity).remove::<ImageSpaceViewState>();
            }
            continue;
        }
        // Nothing changed for `settle_frames` frames: keep the denoised result
        // (`render::settle`).
        if state.is_some() && crate::render::settle::keeps(settle) {
            commands.entity(entity).remove::<ImageSpaceFrame>();
            continue;
        }
        let scene = scene.as_ref().unwrap();
        let settings = caustics.image_space.sanitized_for(&limits);
        let key = ImageSpaceKey {
            size,
            rsm: settings.rsm_resolution,
            lights: scene.lights.len() as u32,
        };
        let mut fresh = None;
        let state = match state {
            Some(s) if s.key == key => s.into_inner(),
            _ => {
                fresh = Some(ImageSpaceViewState::new(&device, key, settings.clone()));
                fresh.as_mut().unwrap()
            }
        };
        state.settings = settings.clone();
        let photons = caustics
            .photons_per_light
            .min(crate::limits::MAX_IMAGE_SPACE_PHOTONS) as u32;
        state.photons = photons;
        write_uniforms(&queue, state, scene, view, photons);
        let temporal = temporal_request(state);
        if let Some(s) = fresh.take() {
            commands.entity(entity).insert(s);
        }
        match temporal {
            Some(t) => commands.entity(entity).insert(t),
            None => commands.entity(entity).remove::<TemporalAccumulation>(),
        };
        if photons > 0 {
            commands.entity(entity).insert(ImageSpaceFrame);
        } else {
            commands.entity(entity).remove::<ImageSpaceFrame>();
        }
    }
}

/// The frames SVGF's exponential mean of weight `alpha_color` is worth once its history is
/// that long: `(2 - a) / a` (9 at the default 0.2).
fn svgf_worth(s: &ImageSpaceSettings) -> u32 {
    let a = s.alpha_color.clamp(0.01, 1.0);
    ((2.0 - a) / a).ceil() as u32
}

/// What image space asks of the shared temporal stage (`render::temporal`) with SVGF on: its
/// output is worth [`svgf_worth`] frames (a longer plain mean once the view stands is not
/// counted: the stage's prior then only matters through a reset, when SVGF is SVGF again), so
/// the stage keeps a history of as many frames. On a still view it only passes SVGF's output
/// on; through a change of the scene, which resets SVGF, it keeps a running mean where the
/// caustic did not change.
fn temporal_request(state: &ImageSpaceViewState) -> Option<TemporalAccumulation> {
    let s = &state.settings;
    let worth = svgf_worth(s);
    s.denoise.then_some(TemporalAccumulation {
        owner: CausticsTechnique::ImageSpace,
        max_history: worth,
        clamp_sigma: crate::render::temporal::DEFAULT_CLAMP_SIGMA,
        frames: state.since_reset.clamp(1, worth),
        // SVGF's own à-trous has filtered the estimate.
        spatial_passes: 0,
    })
}

fn write_uniforms(
    queue: &RenderQueue,
    state: &mut ImageSpaceViewState,
    scene: &ImageSpaceScene,
    view: &ExtractedView,
    photons: u32,
) {
    let s = &state.settings;
    let res = state.key.rsm;
    let mut lights = Vec::new();
    let mut rsm_views = Vec::new();
    for (i, (l, face)) in scene.lights.iter().enumerate() {
        let r = rsm_light(l, *face, scene.casters, scene.bounds, res);
        // A cube's faces share the light's photons.
        let n = if face.is_some() {
            photons.div_ceil(6)
        } else {
            photons
        };
        lights.extend(r.uniform(n, res, 3 * i as u32));
        rsm_views.extend(r.raster_uniform());
    }
    queue.write_buffer(&state.lights, 0, &lights);
    queue.write_buffer(&state.rsm_views, 0, &rsm_views);
    let camera = camera_space_view(view, state.key.size);
    let clip_from_world = crate::render::clip_from_world(view);
    let caustic = scene.scene.caustic_generation;
    let reset = s.reset_on_change && state.generation != Some(caustic);
    state.generation = Some(caustic);
    state.since_reset = if reset {
        1
    } else {
        state.since_reset.saturating_add(1)
    };
    let prev = state.prev_clip_from_world.unwrap_or(clip_from_world);
    state.prev_clip_from_world = Some(clip_from_world);
    // SVGF's own blend for as many frames as its mean is worth after a reset (a fresh caustic
    // converges as the paper's does), the plain mean of unfiltered frames after that.
    let still_view = prev == clip_from_world && state.since_reset > svgf_worth(s);
    state.still_view = still_view;
    let frame = state.frame;
    state.frame = state.frame.wrapping_add(1);
    let rot = [
        crate::optics::pcg_hash(frame.wrapping_mul(2) ^ 0x5bd1_e995),
        crate::optics::pcg_hash(frame.wrapping_mul(2) + 1),
    ];
    let flags = (if s.denoise { FLAG_DENOISE } else { 0 })
        | (if reset { FLAG_RESET } else { 0 })
        | (if s.hi_z { FLAG_HIZ } else { 0 })
        | (if still_view { FLAG_STILL_VIEW } else { 0 });
    let mut b = camera.bytes();
    push(&mut b, &prev.to_cols_array());
    b.extend(
        [frame, rot[0], rot[1], flags]
            .iter()
            .flat_map(|x| x.to_le_bytes()),
    );
    push(
        &mut b,
        &[
            s.thickness,
            s.luminance_cutoff,
            scene.scene.scale,
            s.stride as f32,
        ],
    );
    push(
        &mut b,
        &[
            s.alpha_color,
            s.alpha_moments,
            s.history_cap as f32,
            s.sigma_depth,
        ],
    );
    push(
        &mut b,
        &[
            s.sigma_normal,
            s.sigma_luminance,
            s.internal_events as f32,
            0.0,
        ],
    );
    let h = state.hiz_layout;
    let words = [h.camera.0, h.rsm.0, h.plane_words, h.rsm_base]
        .into_iter()
        .chain(h.camera.1)
        .chain(h.rsm.1);
    b.extend(words.flat_map(|x| x.to_le_bytes()));
    b.resize(1024, 0);
    queue.write_buffer(&state.params, 0, &b);
    // Steps: 0 the variance pass, 1 + i the à-trous iteration i.
    let n = s.atrous_iterations;
    let entries = HizLayout::step(state.hiz_layout.planes, 0);
    let mut steps = vec![0u8; (SMALL_STRIDE * entries) as usize];
    for plane in 0..state.hiz_layout.planes {
        for level in 0..MAX_MIPS as u32 {
            let at = (HizLayout::step(plane, level) * SMALL_STRIDE) as usize;
            for (i, v) in [level, plane, 0, 0].iter().enumerate() {
                steps[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    for k in 0..STEPS as u32 {
        let mut flags = 0;
        if k == n {
            flags |= FLAG_LAST;
        }
        if k == history_step(n, state.still_view) {
            flags |= FLAG_HISTORY;
        }
        let step = if k == 0 { 0 } else { 1u32 << (k - 1) };
        let at = (k as u64 * SMALL_STRIDE) as usize;
        for (i, v) in [step, flags, k, 0].iter().enumerate() {
            steps[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    queue.write_buffer(&state.steps, 0, &steps);
}
