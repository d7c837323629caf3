//! Live images for the inspector: a small compute pass colour-maps the inspected camera's
//! caustics buffer (`Rgba32Float`, which egui cannot sample), the fields of its AAPS task
//! buffer atlas and its photon map (storage buffers) into `Rgba16Float` `Image` assets that
//! egui shows. It runs
//! only for the images the panel shows, after the composite, and records a GPU span
//! (`caustics/inspector`).

use bevy::asset::{RenderAssetUsages, embedded_asset, load_embedded_asset};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::image::ImageSampler;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer, BufferDescriptor,
    BufferInitDescriptor, BufferUsages, CachedComputePipelineId, ComputePassDescriptor,
    ComputePipelineDescriptor, Extent3d, PipelineCache, ShaderStages, StorageTextureAccess,
    TextureDimension, TextureFormat, TextureSampleType, TextureUsages, binding_types,
};
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};
use bevy::render::sync_world::MainEntity;
use bevy::render::texture::GpuImage;
use bevy::render::{RenderApp, RenderStartup};

use crate::render::aaps::view::AapsViewState;
use crate::render::image_space::view::ImageSpaceViewState;
use crate::render::photon_map::view::PhotonMapViewState;
use crate::render::volume::gpu::tile_set_words;
use crate::render::volume::view::VolumeStore;
use crate::render::{ExtractedCaustics, ViewCausticsBuffer};

/// GPU time span of the colour-mapping pass.
pub const INSPECTOR_PASS: &str = "caustics/inspector";

/// Side of the task-buffer images and width of the caustics image, pixels.
pub const IMAGE_SIDE: u32 = 256;

/// What a live image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LiveKind {
    /// The caustics buffer (luminance of the irradiance).
    Caustics,
    /// AAPS: photons per atlas texel (the task buffer's density).
    Density,
    /// AAPS: mean projected splat area per accepted photon, pixels.
    Area,
    /// AAPS: the per-texel variance estimate.
    Variance,
    /// Volume: one slab G-buffer layer (G_near of slab k is layer 2k, G_far 2k + 1), its
    /// normals as colours, black where empty.
    SlabGBuffer,
    /// Volume: photons per density tile of one exit face's projector.
    ProjectorTiles,
    /// Image space: one RSM layer (opaque, caster front, caster back of light view k are
    /// 3k, 3k + 1, 3k + 2), its normals as colours, black where empty.
    RsmLayer,
    /// Image space: this frame's raw photon map (lux), before the denoiser.
    PhotonMap,
    /// Image space: the denoiser's colour history (lux).
    SvgfHistory,
    /// Photon map: the gathered irradiance, the progressive mean (lux).
    PhotonMapGathered,
    /// Photon map: the grid's occupancy seen from above, photons per column of cells (x, z).
    GridOccupancy,
}

impl LiveKind {
    /// All kinds, in the panel's order.
    pub const ALL: [LiveKind; 11] = [
        Self::Caustics,
        Self::Density,
        Self::Area,
        Self::Variance,
        Self::SlabGBuffer,
        Self::ProjectorTiles,
        Self::RsmLayer,
        Self::PhotonMap,
        Self::SvgfHistory,
        Self::PhotonMapGathered,
        Self::GridOccupancy,
    ];

    /// Label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Caustics => "caustics buffer",
            Self::Density => "AAPS density (photons / texel)",
            Self::Area => "AAPS projected area (px / splat)",
            Self::Variance => "AAPS variance",
            Self::SlabGBuffer => "volume slab G-buffer (normals)",
            Self::ProjectorTiles => "volume projector density tiles",
            Self::RsmLayer => "image-space RSM layer (normals)",
            Self::PhotonMap => "image-space raw photon map",
            Self::SvgfHistory => "image-space SVGF history",
            Self::PhotonMapGathered => "photon-map gathered irradiance",
            Self::GridOccupancy => "photon-map grid occupancy (top view)",
        }
    }

    /// Unit of the legend.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Caustics | Self::PhotonMap | Self::SvgfHistory | Self::PhotonMapGathered => "lx",
            Self::Density | Self::GridOccupancy => "photons",
            Self::Area => "px",
            Self::Variance | Self::SlabGBuffer | Self::RsmLayer => "",
            Self::ProjectorTiles => "photons",
        }
    }

    /// The legend's default range (log scale).
    pub fn default_range(self) -> (f32, f32) {
        match self {
            Self::Caustics | Self::PhotonMap | Self::SvgfHistory | Self::PhotonMapGathered => {
                (100.0, 1.0e6)
            }
            Self::GridOccupancy => (0.5, 1.0e4),
            Self::RsmLayer => (1.0, 2.0),
            Self::Density => (0.1, 1.0e3),
            Self::Area => (0.01, 100.0),
            Self::Variance => (1.0e-4, 10.0),
            Self::SlabGBuffer => (1.0, 2.0),
            Self::ProjectorTiles => (0.5, 1.0e3),
        }
    }

    /// The shader's path: 0 a texture's luminance, 1 to 3 AAPS fields, 4 a G-buffer layer's
    /// normals, 5 density tiles, 6 a per-pixel vec4 buffer's luminance, 7 grid occupancy.
    fn code(self) -> u32 {
        match self {
            Self::Caustics | Self::PhotonMap | Self::SvgfHistory => 0,
            Self::Density => 1,
            Self::Area => 2,
            Self::Variance => 3,
            Self::SlabGBuffer | Self::RsmLayer => 4,
            Self::ProjectorTiles => 5,
            Self::PhotonMapGathered => 6,
            Self::GridOccupancy => 7,
        }
    }

    /// Whether the image shows a G-buffer layer's normals (no legend).
    pub fn is_normals(self) -> bool {
        self.code() == 4
    }
}

/// One live image.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveImage {
    /// What it shows.
    pub kind: LiveKind,
    /// The `Rgba16Float` image egui samples.
    pub image: Handle<Image>,
    /// Shown in the panel (the pass runs only for shown images).
    pub shown: bool,
    /// Legend range, low and high (log scale).
    pub range: (f32, f32),
}

/// The inspector's live images and the camera they show.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct InspectorImages {
    /// The panel is open: while it is closed no image is drawn, whatever `shown` says.
    pub open: bool,
    /// The camera whose buffers are shown (main-world entity).
    pub camera: Option<Entity>,
    /// The images.
    pub images: Vec<LiveImage>,
    /// The volume whose buffers are shown (main-world entity; None: the first).
    pub volume: Option<Entity>,
    /// The slab G-buffer layer shown (G_near of slab k is 2k, G_far 2k + 1).
    pub slab_layer: u32,
    /// The exit face whose projector tiles are shown (`volume::frame::face_code`).
    pub face: u32,
    /// The image-space RSM layer shown (3k + 0 opaque, 1 caster front, 2 caster back).
    pub rsm_layer: u32,
}

impl ExtractResource for InspectorImages {
    type Source = InspectorImages;
    fn extract_resource(source: &Self::Source) -> Self {
        source.clone()
    }
}

fn create_images(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let live = LiveKind::ALL
        .iter()
        .map(|&kind| {
            let height = if kind == LiveKind::Caustics {
                IMAGE_SIDE * 9 / 16
            } else {
                IMAGE_SIDE
            };
            let mut image = Image::new_fill(
                Extent3d {
                    width: IMAGE_SIDE,
                    height,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                &[0u8; 8],
                TextureFormat::Rgba16Float,
                RenderAssetUsages::RENDER_WORLD,
            );
            image.texture_descriptor.usage = TextureUsages::STORAGE_BINDING
                | TextureUsages::TEXTURE_BINDING
                | TextureUsages::COPY_DST
                | TextureUsages::COPY_SRC;
            image.sampler = ImageSampler::nearest();
            LiveImage {
                kind,
                image: images.add(image),
                shown: false,
                range: kind.default_range(),
            }
        })
        .collect();
    commands.insert_resource(InspectorImages {
        images: live,
        face: 3,
        ..default()
    });
}

#[derive(Resource)]
struct InspectPipeline {
    layout: BindGroupLayoutDescriptor,
    id: CachedComputePipelineId,
    /// Bound in place of the AAPS buffers when the view has none.
    empty: Buffer,
}

fn init_pipeline(
    mut commands: Commands,
    cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    asset_server: Res<AssetServer>,
) {
    let layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:inspector",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                binding_types::texture_2d(TextureSampleType::Float { filterable: false }),
                binding_types::storage_buffer_read_only_sized(false, None),
                binding_types::storage_buffer_read_only_sized(false, None),
                binding_types::uniform_buffer_sized(false, None),
                binding_types::texture_storage_2d(
                    TextureFormat::Rgba16Float,
                    StorageTextureAccess::WriteOnly,
                ),
            ),
        ),
    );
    let id = cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("caustics:pipeline:inspector".into()),
        layout: vec![layout.clone()],
        shader: load_embedded_asset!(asset_server.as_ref(), "images.wgsl"),
        entry_point: Some("colour_map".into()),
        ..default()
    });
    let empty = device.create_buffer(&BufferDescriptor {
        label: Some("caustics:buffer:inspector_empty"),
        size: 256,
        usage: BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    commands.insert_resource(InspectPipeline { layout, id, empty });
}

/// Colour-map the shown images of the inspected view.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn colour_map_pass(
    view: ViewQuery<(
        &MainEntity,
        &ViewCausticsBuffer,
        &ExtractedCaustics,
        Option<&AapsViewState>,
        Option<&ImageSpaceViewState>,
        Option<&PhotonMapViewState>,
    )>,
    volumes: Option<Res<VolumeStore>>,
    images: Option<Res<InspectorImages>>,
    pipeline: Option<Res<InspectPipeline>>,
    cache: Res<PipelineCache>,
    gpu_images: Res<RenderAssets<GpuImage>>,
    settle: Res<crate::render::span::SpanSettle>,
    mut ctx: RenderContext,
) {
    let (main, buffer, _, aaps, image_space, photon_map) = view.into_inner();
    let (Some(images), Some(pipeline)) = (images, pipeline) else {
        return;
    };
    if !images.open || images.camera != Some(main.id()) || !images.images.iter().any(|i| i.shown) {
        return;
    }
    let Some(compute) = cache.get_compute_pipeline(pipeline.id) else {
        return;
    };
    let layout = cache.get_bind_group_layout(&pipeline.layout);
    let volume = volumes.as_deref().and_then(|store| {
        store
            .volumes
            .iter()
            .find(|v| Some(v.entity) == images.volume)
            .or(store.volumes.first())
    });
    let mut work = Vec::new();
    for live in images.images.iter().filter(|i| i.shown) {
        let Some(target) = gpu_images.get(live.image.id()) else {
            continue;
        };
        // Per kind: the texture and the two buffers bound, the grid side, the source size and
        // the first word of the tile set.
        let empty = &pipeline.empty;
        let (texture, density, accum, side, size, offset) = match live.kind {
            LiveKind::Caustics => (&buffer.view, empty, empty, 0, buffer.size, 0),
            LiveKind::Density | LiveKind::Area | LiveKind::Variance => {
                let Some(a) = aaps else { continue };
                let side = a.key.atlas[0];
                (&buffer.view, &a.density[0], &a.accum, side, buffer.size, 0)
            }
            LiveKind::SlabGBuffer => {
                let Some(v) = volume else { continue };
                let Some(layer) = v
                    .slab_layers
                    .get(images.slab_layer as usize)
                    .or(v.slab_layers.last())
                else {
                    continue;
                };
                (layer, empty, empty, 0, UVec2::splat(v.key.gbuffer), 0)
            }
            LiveKind::ProjectorTiles => {
                let Some(v) = volume else { continue };
                let side = v.key.projector.div_ceil(v.key.tile.max(1));
                let offset = images.face.min(5) as u64 * tile_set_words(&v.key);
                (&buffer.view, &v.tiles, empty, side, buffer.size, offset)
            }
            LiveKind::RsmLayer => {
                let Some(s) = image_space else { continue };
                let Some(layer) = s
                    .rsm_layers
                    .get(images.rsm_layer as usize)
                    .or(s.rsm_layers.last())
                else {
                    continue;
                };
                (layer, empty, empty, 0, UVec2::splat(s.key.rsm), 0)
            }
            LiveKind::PhotonMap => {
                let Some(s) = image_space else { continue };
                (&s.raw.1, empty, empty, 0, s.key.size, 0)
            }
            LiveKind::SvgfHistory => {
                let Some(s) = image_space else { continue };
                // Written this frame, at the parity the passes used (`frame & 1`).
                let cur = (s.frame & 1) as usize;
                (&s.history[cur].1, empty, empty, 0, s.key.size, 0)
            }
            LiveKind::PhotonMapGathered => {
                let Some(s) = photon_map else { continue };
                (&buffer.view, &s.accum, empty, 0, s.key.size, 0)
            }
            LiveKind::GridOccupancy => {
                // The header (dims) as `density`, startIdx as `accum`.
                let Some(s) = photon_map else { continue };
                (&buffer.view, &s.header, &s.cells, 0, s.key.size, 0)
            }
        };
        let mut params = [0u8; 32];
        params[0..4].copy_from_slice(&live.range.0.max(1e-30).to_le_bytes());
        params[4..8].copy_from_slice(&live.range.1.max(live.range.0 * 1.001).to_le_bytes());
        params[8..12].copy_from_slice(&(offset as f32).to_le_bytes());
        for (i, w) in [live.kind.code(), side, size.x, size.y]
            .into_iter()
            .enumerate()
        {
            params[16 + 4 * i..20 + 4 * i].copy_from_slice(&w.to_le_bytes());
        }
        let uniform = ctx
            .render_device()
            .create_buffer_with_data(&BufferInitDescriptor {
                label: Some("caustics:buffer:inspector_params"),
                contents: &params,
                usage: BufferUsages::UNIFORM,
            });
        let bind_group = ctx.render_device().create_bind_group(
            "caustics:bind_group:inspector",
            &layout,
            &BindGroupEntries::sequential((
                texture,
                density.as_entire_binding(),
                accum.as_entire_binding(),
                uniform.as_entire_binding(),
                &target.texture_view,
            )),
        );
        work.push((bind_group, target.texture_descriptor.size));
    }
    if work.is_empty() {
        return;
    }
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx
        .command_encoder()
        .begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_inspector"),
            timestamp_writes: None,
        });
    let span = diagnostics.pass_span(&mut pass, INSPECTOR_PASS);
    settle.settle(&mut pass);
    pass.set_pipeline(compute);
    for (bind_group, size) in &work {
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(size.width.div_ceil(8), size.height.div_ceil(8), 1);
    }
    span.end(&mut pass);
}

pub(super) fn build(app: &mut App) {
    embedded_asset!(app, "images.wgsl");
    app.add_systems(Startup, create_images)
        .add_plugins(ExtractResourcePlugin::<InspectorImages>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(RenderStartup, init_pipeline)
        .add_systems(
            Core3d,
            colour_map_pass
                .in_set(Core3dSystems::MainPass)
                .after(crate::render::composite::composite_caustics),
        );
}
