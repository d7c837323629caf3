//! The largest values of every setting that sizes memory or work, for one device.
//!
//! A component field above its maximum is clamped with one warning (`components::validate`);
//! the command-line renderer refuses it with one line and exit status 2
//! (`headless::check_job`). Nothing is allocated whose size was not bounded here first.
//!
//! The maxima follow from the device's limits (`RenderDevice::limits()`, which Bevy requests
//! at the adapter's maximum) and, for the CPU reference, from its photon streams and run time.
//! [`CausticsLimits::default`] is the WebGPU default device (128 MiB storage bindings, 256 MiB
//! buffers, 8192² textures), the smallest a Bevy app gets.

use bevy::prelude::*;
use bevy::render::render_resource::WgpuLimits;

use crate::CausticsTechnique;

/// Photons per light the CPU reference traces at most: 2^32. Each photon has its own random
/// stream (`light << 40 ^ index`, so indices below 2^40 never collide); the bound is the run
/// time: about 1 hour 40 minutes per light on 2 cores at the measured 0.75 M photons/s of
/// `glass_sphere`.
pub const MAX_REFERENCE_PHOTONS: u64 = 1 << 32;

/// Frames the headless renderer measures at most: 10 000 (a measurement, not a film; about
/// 40 s at 240 frames/s, minutes on a CPU driver).
pub const MAX_FRAMES: u32 = 10_000;

/// Largest side of the headless renderer's image, whatever the device allows.
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// Bytes per pixel of the largest per-view texture (AAPS's 4x multisampled `Rgba32Float`
/// small-splat target).
pub const VIEW_BYTES_PER_PIXEL: u64 = 4 * 16;

/// Photons per light and frame of the image-space technique: one 2D dispatch of 64-thread
/// workgroups (65 535 x 256 groups) holds more; 2^24 keeps a frame bounded.
pub const MAX_IMAGE_SPACE_PHOTONS: u64 = 1 << 24;

/// Bytes per texel of a volume's G-buffer layer (`Rgba32Float`).
pub const GBUFFER_BYTES_PER_TEXEL: u64 = 16;

/// The maxima of one device. Inserted as a resource when the plugin starts (from the render
/// device's limits); the validation systems clamp against it.
#[derive(Resource, Clone, Debug, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct CausticsLimits {
    /// Largest side of a rendered image, pixels: `max_texture_dimension_2d`, at most 8192.
    pub max_image_side: u32,
    /// Largest pixel count of a caustics view: its largest texture (64 bytes per pixel) must
    /// fit one allocation of `max_texture_bytes`.
    pub max_view_pixels: u64,
    /// Largest single texture or buffer, bytes: the device's `max_buffer_size` (wgpu states no
    /// byte limit for textures; the same bound keeps one allocation below what drivers accept).
    pub max_texture_bytes: u64,
    /// Largest storage binding, bytes: `max_storage_buffer_binding_size` (at most
    /// `max_buffer_size`).
    pub max_binding_bytes: u64,
    /// Photons per light of the reference: [`MAX_REFERENCE_PHOTONS`].
    pub max_reference_photons: u64,
    /// AAPS photon budget per light per frame: the splat capacity the device can bind (each
    /// photon draws at most one splat; a budget above it could not be drawn in one frame).
    pub max_aaps_photons: u64,
    /// AAPS splat buffer capacity, splats: 64 bytes each plus the guard in one storage
    /// binding (`max_storage_buffer_binding_size`, `max_buffer_size`).
    pub max_splat_capacity: u32,
    /// AAPS atlas side (power of two): 1024, less where its per-texel buffers (16 bytes per
    /// texel) would not fit one storage binding.
    pub max_atlas_resolution: u32,
    /// Photons a volume traces at one slab (64 bytes per photon per slab in one storage
    /// binding, and one dispatch of 65 535 workgroups of 64); fewer at more slabs.
    pub max_volume_photons: u32,
    /// Slabs of a volume: 64, and two G-buffer layers per slab within
    /// `max_texture_array_layers`.
    pub max_volume_slabs: u32,
    /// Side of a volume's projector and slab G-buffers: 4096, at most
    /// `max_texture_dimension_2d`; the slab array (side² · 2 · slabs · 16 bytes) must also fit
    /// `max_texture_bytes` ([`CausticsLimits::volume_gbuffer_side`]).
    pub max_volume_resolution: u32,
}

impl Default for CausticsLimits {
    fn default() -> Self {
        Self::new(&WgpuLimits::default())
    }
}

impl CausticsLimits {
    /// The maxima of a device with `limits`.
    pub fn new(limits: &WgpuLimits) -> Self {
        let binding = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let max_texture_bytes = limits.max_buffer_size;
        let max_image_side = limits.max_texture_dimension_2d.clamp(1, MAX_IMAGE_SIDE);
        let splats = crate::render::aaps::view::splat_capacity(u32::MAX, limits);
        let mut atlas = 1024u32;
        while atlas > 8 && (atlas as u64).pow(2) * 16 > binding {
            atlas /= 2;
        }
        Self {
            max_image_side,
            max_view_pixels: (max_texture_bytes / VIEW_BYTES_PER_PIXEL).max(1),
            max_texture_bytes,
            max_binding_bytes: binding,
            max_reference_photons: MAX_REFERENCE_PHOTONS,
            max_aaps_photons: splats as u64,
            max_splat_capacity: splats,
            max_atlas_resolution: atlas,
            max_volume_photons: crate::render::volume::view::photon_capacity(i32::MAX, 1, binding),
            max_volume_slabs: (limits.max_texture_array_layers / 2).clamp(1, 64),
            max_volume_resolution: limits.max_texture_dimension_2d.clamp(16, 4096),
        }
    }

    /// Photons per light a camera of `technique` may ask for (its `CausticsQuality`): the
    /// reference's photons, AAPS's per-frame budget. The volume technique takes its photons
    /// from each `CausticsVolume`; its quality is bounded like the reference's.
    pub fn max_photons(&self, technique: CausticsTechnique) -> u64 {
        match technique {
            CausticsTechnique::Aaps => self.max_aaps_photons,
            // One 2D dispatch of 64-thread workgroups per light (65 535 x 256 groups).
            CausticsTechnique::ImageSpace => MAX_IMAGE_SPACE_PHOTONS,
            // Every light's photons in one binding of 32-byte photons.
            CausticsTechnique::PhotonMap => {
                MAX_IMAGE_SPACE_PHOTONS.min(self.max_binding_bytes / crate::optics::PHOTON_BYTES)
            }
            CausticsTechnique::Reference | CausticsTechnique::Volume => self.max_reference_photons,
        }
    }

    /// Photons a volume of `slabs` slabs traces at most (its photon levels in one binding,
    /// one dispatch).
    pub fn volume_photons(&self, slabs: u32) -> u32 {
        crate::render::volume::view::photon_capacity(i32::MAX, slabs, self.max_binding_bytes)
    }

    /// The largest slab G-buffer side at most `side` (and [`Self::max_volume_resolution`])
    /// whose array of `2 · slabs` `Rgba32Float` layers fits `max_texture_bytes`; at least 16.
    pub fn volume_gbuffer_side(&self, side: u32, slabs: u32) -> u32 {
        self.layered_side(side, 2 * slabs.max(1))
    }

    /// The largest projector side at most `side` whose six `Rgba32Float` layers fit
    /// `max_texture_bytes`; at least 16.
    pub fn volume_projector_side(&self, side: u32) -> u32 {
        self.layered_side(side, 6)
    }

    /// The largest reflective-shadow-map side at most `side` whose three `Rgba32Float` layers
    /// fit `max_texture_bytes` (at most `max_volume_resolution`); at least 64.
    pub fn rsm_side(&self, side: u32) -> u32 {
        self.layered_side(side, 3)
            .max(64.min(self.max_volume_resolution))
    }

    fn layered_side(&self, side: u32, layers: u32) -> u32 {
        let texels = self.max_texture_bytes / (layers as u64 * GBUFFER_BYTES_PER_TEXEL);
        let fit = (texels as f64).sqrt().floor() as u64;
        (side as u64)
            .min(self.max_volume_resolution as u64)
            .min(fit)
            .max(16) as u32
    }
}
