//! The techniques' GPU counters as the headless renderer reports them: AAPS, image space and
//! the photon map (the volumes' are in `volume.rs`), each decoded from the words of a
//! readback.

use bevy::math::Vec3;
use serde::Serialize;

/// The AAPS counters of one frame, read back from the GPU after the render.
#[derive(Clone, Debug, Default, Serialize)]
pub struct AapsCounters {
    /// Photons the task buffer asked for.
    pub tasks: u64,
    /// Photons traced.
    pub photons_emitted: u64,
    /// Splats drawn (both lists).
    pub splats: u64,
    /// Of which small (MSAA) splats.
    pub splats_msaa: u64,
    /// Splats that did not fit in the splat buffer (not drawn).
    pub splat_overflow: u64,
    /// Splats culled: outside the frustum or facing away from the camera.
    pub culled_frustum: u64,
    /// Splats culled above the solid-angle threshold.
    pub culled_size: u64,
    /// Photons whose first hit was not a caster.
    pub dropped: u64,
    /// Splats whose axes were clamped, and differentials parallel to a surface.
    pub clamped: u64,
    /// Non-finite values caught.
    pub nan_guards: u64,
    /// Paths stopped at the maximum number of bounces.
    pub max_depth: u64,
    /// Total internal reflections.
    pub tir: u64,
    /// Photons past the photon capacity.
    pub photon_overflow: u64,
    /// Photons split at a dielectric.
    pub splits: u64,
    /// Luminous flux striking the casters (photons' first hits), lm (or W weighted by
    /// luminance).
    pub flux_on_casters: f64,
    /// Luminous flux reaching diffuse surfaces after a specular path, in view or not, before
    /// any culling.
    pub flux_deposited: f64,
    /// Luminous flux still in flight when a path reached `max_bounces` or the frame's event
    /// budget ran out (`budget_stopped`).
    pub flux_max_depth: f64,
    /// Specular events traced (reflections and refractions, all paths).
    pub events: u64,
    /// Paths stopped because the frame's specular-event budget
    /// ([`crate::AapsSettings::bounce_budget`]) was spent.
    pub budget_stopped: u64,
    /// Non-zero words in the last splat inside the splat buffer's capacity (16 when it holds a
    /// splat).
    pub splat_last_words: u64,
    /// Non-zero words in the splat buffer's guard region past its capacity (written past it).
    pub splat_guard_written: u64,
}

impl AapsCounters {
    /// From a readback: the counter words (`C_*` in src/render/aaps/common.wgsl) and the splat
    /// buffer's tail.
    pub fn from_snapshot(snap: &crate::render::readback::CausticsSnapshot) -> Self {
        let c = |i: usize| snap.counters[i] as u64;
        let nonzero = |w: &[u32]| w.iter().filter(|&&x| x != 0).count() as u64;
        // Four f32 words from `i` (`C_FLUX_*` in common.wgsl), summed.
        let f4 = |i: usize| -> f64 {
            (i..i + 4)
                .map(|k| f32::from_bits(snap.counters[k]) as f64)
                .sum()
        };
        Self {
            tasks: c(0),
            photons_emitted: c(1),
            splats: c(3) + c(4),
            splats_msaa: c(4),
            splat_overflow: c(5),
            culled_frustum: c(6),
            culled_size: c(7),
            dropped: c(8),
            clamped: c(9),
            nan_guards: c(10),
            max_depth: c(11),
            tir: c(13),
            photon_overflow: c(14),
            splits: c(15),
            flux_on_casters: f4(16),
            flux_deposited: f4(20),
            flux_max_depth: f4(24),
            events: c(29),
            budget_stopped: c(30),
            splat_last_words: nonzero(&snap.splat_guard[..16]),
            splat_guard_written: nonzero(&snap.splat_guard[16..]),
        }
    }
}

/// The image-space counters of one frame (`C_*` in src/render/image_space/trace.wgsl), summed
/// over the lights.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ImageSpaceCounters {
    /// Photons traced: samples on a caster texel above the luminance cutoff.
    pub photons_emitted: u64,
    /// Samples on a texel without a caster (not traced).
    pub skipped_empty: u64,
    /// Samples under the luminance cutoff (not traced).
    pub skipped_dim: u64,
    /// Light-space marches that ended on a receiver.
    pub light_hits: u64,
    /// Light-space marches that left the light's map.
    pub light_misses: u64,
    /// Reprojected ends on the camera's surface.
    pub reprojection_plane: u64,
    /// Reprojected ends in front of the camera's surface (marched on).
    pub reprojection_concave: u64,
    /// Reprojected ends hidden behind the camera's surface (lost).
    pub reprojection_convex: u64,
    /// Photons deposited into the photon map.
    pub camera_hits: u64,
    /// Of which straight from the light march (plane case).
    pub direct_hits: u64,
    /// Photons lost off screen or without a surface found in the camera's depth.
    pub misses: u64,
    /// Photons that failed the normal test.
    pub normal_rejects: u64,
    /// Total internal reflections inside a caster (followed, up to
    /// `ImageSpaceSettings::internal_events` reflections per photon).
    pub tir: u64,
    /// Fixed-point words clamped (above 2^32 / 256 lux per photon, or non-finite).
    pub clamped: u64,
    /// Non-finite states caught.
    pub nan_guards: u64,
    /// Photons that landed on a receiver inside a medium.
    pub landed_inside: u64,
    /// Photons inside a caster that were not followed out: still reflecting after
    /// `internal_events` reflections, or crossing a silhouette (or another caster's layers)
    /// where the light's caster layers cannot tell where they meet the glass.
    pub trapped: u64,
    /// Reflections off a further mirror after a reflection off a caster's outside (the light's
    /// caster-front layer marched; at most 4 per photon).
    pub mirror_chain: u64,
    /// Photons that met a fifth mirror in such a chain (dropped).
    pub mirror_cap: u64,
}

impl ImageSpaceCounters {
    /// From the counter words of a readback.
    pub fn from_words(w: &[u32]) -> Self {
        let c = |i: usize| w.get(i).copied().unwrap_or(0) as u64;
        Self {
            photons_emitted: c(0),
            skipped_empty: c(1),
            skipped_dim: c(2),
            light_hits: c(3),
            light_misses: c(4),
            reprojection_plane: c(5),
            reprojection_concave: c(6),
            reprojection_convex: c(7),
            camera_hits: c(8),
            misses: c(9),
            normal_rejects: c(10),
            tir: c(11),
            clamped: c(12),
            nan_guards: c(13),
            landed_inside: c(14),
            direct_hits: c(15),
            trapped: c(16),
            mirror_chain: c(17),
            mirror_cap: c(18),
        }
    }
}

/// The photon-map counters of one frame (`C_*` in src/render/photon_map/photon.wgsl).
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhotonMapCounters {
    /// Photons that left a light with flux.
    pub photons_emitted: u64,
    /// Photons stored (first diffuse hit after a specular one), within the capacity.
    pub photons_stored: u64,
    /// Photons past the capacity (dropped).
    pub overflow: u64,
    /// Photons whose first hit was diffuse (direct light, not a caustic).
    pub direct: u64,
    /// Photons that hit nothing.
    pub missed: u64,
    /// Paths stopped at the bounce limit.
    pub max_depth: u64,
    /// Paths ended by Russian roulette (after `optics::ROULETTE_DEPTH` specular events; their
    /// flux lives on in the survivors').
    pub roulette: u64,
    /// Total internal reflections.
    pub tir: u64,
    /// Non-finite states caught.
    pub nan_guards: u64,
    /// Luminous flux striking the casters (photons' first hits), lm (or W weighted by
    /// luminance).
    pub flux_on_casters: f64,
    /// Luminous flux reaching diffuse surfaces after a specular path, in view or not, stored or
    /// past the capacity.
    pub flux_deposited: f64,
    /// Luminous flux still in flight when a path reached `max_bounces` or the frame's event
    /// budget ran out (`budget_stopped`).
    pub flux_max_depth: f64,
    /// Specular events traced (reflections and refractions, all paths).
    pub events: u64,
    /// Paths stopped because the frame's specular-event budget
    /// ([`crate::PhotonMapSettings::bounce_budget`]) was spent.
    pub budget_stopped: u64,
    /// Grid cells (X·Y·Z) and the grid's dimensions.
    pub grid_cells: u64,
    /// X, Y, Z.
    pub grid_dims: [u64; 3],
    /// Doublings of the cell size the memory budget forced (0: cell = radius).
    pub coarsened: u64,
    /// Pixels gathered.
    pub pixels: u64,
    /// Photons distance-tested per gathered pixel, mean and max.
    pub visited_mean: f64,
    /// See `visited_mean`.
    pub visited_max: u64,
    /// Photons that contributed per gathered pixel, mean and max.
    pub gathered_mean: f64,
    /// See `gathered_mean`.
    pub gathered_max: u64,
    /// Photons within the radius rejected by the normal test.
    pub normal_rejects: u64,
    /// 8x8 tiles gathered through workgroup memory, and tiles that fell back.
    pub shared_tiles: u64,
    /// See `shared_tiles`.
    pub fallback_tiles: u64,
    /// Pixels on mirrors gathered at their reflected point.
    pub mirror_pixels: u64,
    /// Right-eye pixels taken from the left eye, of those considered.
    pub stereo_reused: u64,
    /// See `stereo_reused`.
    pub stereo_pixels: u64,
    /// The progressive frame shown (1 right after a change).
    pub accumulated_frames: u64,
}

impl PhotonMapCounters {
    /// From a readback: the header's first 32 words and its event-budget words.
    pub fn from_snapshot(snap: &crate::render::readback::CausticsSnapshot) -> Self {
        let mut c = Self::from_words(&snap.counters);
        c.events = snap.extra[0] as u64;
        c.budget_stopped = snap.extra[1] as u64;
        c
    }

    /// From the counter words of a readback (the header's first 32 words; the event-budget
    /// counters stay 0).
    pub fn from_words(w: &[u32]) -> Self {
        let c = |i: usize| w.get(i).copied().unwrap_or(0) as u64;
        // A 64-bit fixed-point flux counter from word `i` (`C_FLUX_*` in photon.wgsl), lm.
        let flux = |i: usize| {
            (c(i) as f64 + c(i + 1) as f64 * 4_294_967_296.0)
                / crate::render::photon_map::view::FLUX_SCALE
        };
        let pixels = c(10);
        let per_pixel = |v: u64| {
            if pixels > 0 {
                v as f64 / pixels as f64
            } else {
                0.0
            }
        };
        Self {
            photons_emitted: c(0),
            photons_stored: c(1).saturating_sub(c(4)),
            overflow: c(4),
            direct: c(2),
            missed: c(3),
            max_depth: c(5),
            roulette: c(31),
            tir: c(6),
            nan_guards: c(7),
            flux_on_casters: flux(25),
            flux_deposited: flux(27),
            flux_max_depth: flux(29),
            events: 0,
            budget_stopped: 0,
            grid_cells: c(8),
            grid_dims: [c(21), c(22), c(23)],
            coarsened: c(9),
            pixels,
            visited_mean: per_pixel(c(11)),
            visited_max: c(20),
            gathered_mean: per_pixel(c(12)),
            gathered_max: c(13),
            normal_rejects: c(14),
            shared_tiles: c(15),
            fallback_tiles: c(16),
            mirror_pixels: c(17),
            stereo_reused: c(18),
            stereo_pixels: c(19),
            accumulated_frames: c(24),
        }
    }
}

/// The first `n` 32-byte photon records (`Photon` in src/render/photon_map/photon.wgsl).
pub(super) fn decode_photons(bytes: &[u8], n: usize) -> Vec<crate::optics::StoredPhoton> {
    bytes
        .chunks_exact(crate::optics::PHOTON_BYTES as usize)
        .take(n)
        .map(|r| {
            let w = |i: usize| u32::from_le_bytes(r[4 * i..4 * i + 4].try_into().unwrap());
            let f = |i: usize| f32::from_bits(w(i));
            crate::optics::StoredPhoton {
                position: Vec3::new(f(0), f(1), f(2)),
                flux: Vec3::new(f(4), f(5), f(6)),
                normal: crate::optics::oct_decode(w(7)),
            }
        })
        .collect()
}

impl ImageSpaceCounters {
    /// What image space could not follow in this frame, as one line, or `None` when nothing was
    /// lost: a photon still inside a caster after `internal_events` reflections, or crossing a
    /// silhouette where the light's caster layers cannot follow it, is dropped, and one that
    /// leaves the light's or the camera's view (or finds no surface in the camera's depth) is
    /// lost.
    pub fn lost_summary(&self) -> Option<String> {
        let lost = self.trapped + self.misses;
        (lost > 0 && self.photons_emitted > 0).then(|| {
            format!(
                "bevy_caustics: image space lost {lost} of {} photons ({:.1} %): {} inside a caster not followed out (past internal_events reflections, or across a silhouette), {} off screen or without a surface in the camera's depth",
                self.photons_emitted,
                100.0 * lost as f64 / self.photons_emitted as f64,
                self.trapped,
                self.misses
            )
        })
    }
}

impl PhotonMapCounters {
    /// The flux the photon map's trace dropped at its bounce cap or its event budget, as one
    /// line, or `None` when none was.
    pub fn lost_summary(&self) -> Option<String> {
        (self.max_depth + self.budget_stopped > 0).then(|| {
            format!(
                "bevy_caustics: photon map dropped {:.1} lm ({:.2} % of the {:.1} lm on casters) in {} paths at max_bounces and {} paths stopped by its event budget (bounce_budget)",
                self.flux_max_depth,
                100.0 * self.flux_max_depth / self.flux_on_casters.max(1e-9),
                self.flux_on_casters,
                self.max_depth,
                self.budget_stopped
            )
        })
    }
}

impl AapsCounters {
    /// The paths AAPS ended at its depth cap or its event budget, as one line, or `None` when
    /// none was.
    pub fn lost_summary(&self) -> Option<String> {
        (self.max_depth + self.budget_stopped > 0).then(|| {
            format!(
                "bevy_caustics: AAPS ended {} paths at its specular depth cap and {} paths at its event budget (bounce_budget), {:.1} lm in flight ({:.2} % of the {:.1} lm on casters)",
                self.max_depth,
                self.budget_stopped,
                self.flux_max_depth,
                100.0 * self.flux_max_depth / self.flux_on_casters.max(1e-9),
                self.flux_on_casters
            )
        })
    }
}
