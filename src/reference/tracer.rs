//! The CPU ground-truth light tracer (the `Reference` technique).
//!
//! Photons leave each light (directional: uniform over a disc perpendicular to the light that
//! covers the casters' bounding sphere; point: uniform over the sphere, restricted to the cone
//! that holds the casters when the light is outside their bounding sphere, which is exact
//! because a photon outside that cone cannot start a specular path; spot: uniform inside the
//! outer cone, weighted by Bevy's falloff), follow any number of specular events
//! (conductors weight by Schlick's reflectance; dielectrics choose reflection with probability
//! equal to the exact Fresnel reflectance, which is unbiased and keeps the flux; media
//! attenuate by Beer-Lambert), and stop at the first diffuse surface. A photon whose first
//! hit is diffuse is direct light, not a caustic, and is dropped.
//!
//! Long specular chains (a brilliant-cut gem traps light for dozens of internal reflections)
//! are followed up to [`TraceSettings::max_specular_events`] (default 256); after
//! [`TraceSettings::roulette_depth`] events each photon survives the next event with
//! probability `q = clamp(max(flux / emitted flux), 0.05, 1)` and carries `flux / q` when it
//! does (Russian roulette, unbiased: the expected flux is unchanged). Flux still in flight at
//! the cap is counted in [`TraceStats::flux_max_depth`], never silently dropped, so the energy
//! balance `flux_on_casters = flux_deposited + flux_escaped + flux_max_depth + absorbed` can
//! be checked (`tests/cpu.rs`, the closed box). At a diffuse hit seen by the
//! camera the photon adds `E = Φ / A_p` to that pixel, `A_p` the pixel's exact footprint on the
//! surface ([`crate::optics::pixel_footprint_area`]). No blur kernel: the estimate converges to
//! the pixel-averaged caustic irradiance as photons grow.
//!
//! Visibility matches Bevy's deferred G-buffer: transmissive materials are forward-rendered and
//! absent from it, so the camera "sees through" dielectric casters to the diffuse surface
//! behind them; mirrors are in the G-buffer and occlude.
//!
//! Deterministic for a seed: every photon draws from its own random stream, work is split in
//! fixed chunks, and chunk results are summed in order.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::optics::{self, Pcg32, PixelFocal};
use crate::scene::{CameraProjection, Surface, Tlas, TraceCamera, TraceLight};

use super::CausticImage;

/// Photons per work chunk (fixed, so results do not depend on the thread count).
const CHUNK: u64 = 4096;
/// Chunks traced in parallel before their deposits are added to the image (bounds memory:
/// at most 256 · 4096 photons' deposits at once).
const BATCH_CHUNKS: u64 = 256;

/// Settings of one reference render.
#[derive(Clone, Copy, Debug)]
pub struct TraceSettings {
    /// Photons per light.
    pub photons_per_light: u64,
    /// Seed of the random streams.
    pub seed: u64,
    /// Longest specular chain followed before a photon is dropped; its flux is counted in
    /// [`TraceStats::flux_max_depth`]. Default 256: a brilliant-cut IOR 2.4 gem in a closed
    /// room of receivers (`scenes::closed::gem_room`) keeps all but 0.001 % of the power that
    /// strikes it there, against 0.11 % lost at 128, 0.74 % at 64 and 5.9 % at 16
    /// (`tests/cpu/energy.rs`). Cost: only the paths that long pay for it (the gem traces
    /// 0.35 M photons/s at 256 and at 64 alike on 2 cores).
    pub max_specular_events: u32,
    /// Specular events after which Russian roulette may end a path (unbiased). Default 8
    /// ([`crate::optics::ROULETTE_DEPTH`], shared with the photon map's trace). `u32::MAX`
    /// switches it off. Paths whose flux is not reduced by the chain (clear glass) always
    /// survive it; absorbing media and metals end earlier, which saves their work.
    pub roulette_depth: u32,
}

impl Default for TraceSettings {
    fn default() -> Self {
        Self {
            photons_per_light: 1 << 20,
            seed: 1,
            max_specular_events: 256,
            roulette_depth: optics::ROULETTE_DEPTH,
        }
    }
}

/// What happened to the photons; every guard that fired is counted here.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceStats {
    /// Photons emitted over all lights.
    pub photons_emitted: u64,
    /// Photons that reached a diffuse surface after at least one specular event.
    pub photons_deposited: u64,
    /// Of those, photons that landed in a camera pixel.
    pub photons_in_view: u64,
    /// Photons whose first hit was diffuse (direct light, not caustic).
    pub photons_direct: u64,
    /// Photons that left the scene.
    pub photons_escaped: u64,
    /// Photons dropped at the specular-chain limit.
    pub photons_max_depth: u64,
    /// Photons ended by Russian roulette (their flux lives on in the survivors').
    pub photons_roulette: u64,
    /// Flux emitted towards the casters, per channel (lm or W).
    pub flux_emitted: DVec3,
    /// Flux that reached diffuse surfaces via a specular path, per channel.
    pub flux_deposited: DVec3,
    /// Flux of the photons whose first hit is a caster (mirror or dielectric), at that hit.
    pub flux_on_casters: DVec3,
    /// Flux that left the scene after at least one specular event.
    pub flux_escaped: DVec3,
    /// Flux still in flight when a path reached `max_specular_events` (not deposited).
    pub flux_max_depth: DVec3,
    /// Flux taken inside absorbing media (Beer-Lambert), by a conductor's reflectance and by a
    /// dielectric's transmission tint, per channel.
    pub flux_absorbed: DVec3,
    /// Flux Russian roulette took from the paths it ended less what it added to the survivors
    /// (zero in expectation; either sign in a run), per channel. With it the balance
    /// `flux_on_casters = flux_deposited + flux_escaped + flux_max_depth + flux_absorbed +
    /// flux_roulette` holds to rounding (paths a guard ended aside: `nan_guards`).
    pub flux_roulette: DVec3,
    /// Flux deposited per receiver instance (index into the TLAS).
    pub flux_per_instance: BTreeMap<u32, DVec3>,
    /// Flux deposited per path kind `(reflections, refractions)`.
    pub flux_per_path: BTreeMap<(u32, u32), DVec3>,
    /// Guard: non-finite values replaced by zero.
    pub nan_guards: u64,
    /// Guard: a shading normal sent the ray to the wrong side; the geometric normal was used.
    pub normal_fallbacks: u64,
    /// Guard: footprints clamped at grazing view angles.
    pub grazing_clamps: u64,
    /// Total internal reflections (Fresnel reflectance 1 inside a dielectric).
    pub tir_events: u64,
}

impl TraceStats {
    fn merge(&mut self, o: TraceStats) {
        self.photons_emitted += o.photons_emitted;
        self.photons_deposited += o.photons_deposited;
        self.photons_in_view += o.photons_in_view;
        self.photons_direct += o.photons_direct;
        self.photons_escaped += o.photons_escaped;
        self.photons_max_depth += o.photons_max_depth;
        self.photons_roulette += o.photons_roulette;
        self.flux_emitted += o.flux_emitted;
        self.flux_deposited += o.flux_deposited;
        self.flux_on_casters += o.flux_on_casters;
        self.flux_escaped += o.flux_escaped;
        self.flux_max_depth += o.flux_max_depth;
        self.flux_absorbed += o.flux_absorbed;
        self.flux_roulette += o.flux_roulette;
        for (k, v) in o.flux_per_instance {
            *self.flux_per_instance.entry(k).or_default() += v;
        }
        for (k, v) in o.flux_per_path {
            *self.flux_per_path.entry(k).or_default() += v;
        }
        self.nan_guards += o.nan_guards;
        self.normal_fallbacks += o.normal_fallbacks;
        self.grazing_clamps += o.grazing_clamps;
        self.tir_events += o.tir_events;
    }
}

/// A light prepared for emission: how to draw one photon.
struct Emitter {
    light: TraceLight,
    /// Directional: disc centre, radius and start distance. Point/spot: cone around `axis`.
    center: Vec3,
    radius: f32,
    start: f32,
    axis: Vec3,
    cos_max: f32,
    /// Flux of one photon (before spot falloff).
    flux: Vec3,
}

fn make_emitter(light: &TraceLight, tlas: &Tlas, photons: u64) -> Option<Emitter> {
    let (lo, hi) = tlas.bounds_where(|i| i.surface.is_specular())?;
    let (slo, shi) = tlas.bounds_where(|_| true)?;
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo) * 0.5).length().max(1e-9);
    let scene_radius = ((shi - slo) * 0.5).length() + (center - (slo + shi) * 0.5).length();
    // Guard (stiff suite: "zero photons"): no division by zero; nothing is emitted anyway.
    let n = photons.max(1) as f32;
    Some(match *light {
        TraceLight::Directional {
            direction,
            illuminance,
        } => {
            let d = direction.try_normalize()?;
            Emitter {
                light: *light,
                center,
                radius,
                start: scene_radius * 2.0 + radius,
                axis: d,
                cos_max: 1.0,
                flux: illuminance * core::f32::consts::PI * radius * radius / n,
            }
        }
        TraceLight::Point { position, flux } => {
            let to_c = center - position;
            let dist = to_c.length();
            let (axis, cos_max) = if dist > radius * 1.0001 {
                (to_c / dist, (1.0 - (radius / dist).powi(2)).max(0.0).sqrt())
            } else {
                (Vec3::Z, -1.0)
            };
            let omega = optics::cone_solid_angle(cos_max);
            Emitter {
                light: *light,
                center: position,
                radius,
                start: 0.0,
                axis,
                cos_max,
                flux: flux / (4.0 * core::f32::consts::PI) * omega / n,
            }
        }
        TraceLight::Spot {
            position,
            direction,
            flux,
            outer_angle,
            ..
        } => {
            let axis = direction.try_normalize()?;
            let cos_max = outer_angle.clamp(0.0, core::f32::consts::PI).cos();
            let omega = optics::cone_solid_angle(cos_max);
            Emitter {
                light: *light,
                center: position,
                radius,
                start: 0.0,
                axis,
                cos_max,
                flux: flux / (4.0 * core::f32::consts::PI) * omega / n,
            }
        }
    })
}

impl Emitter {
    /// Origin, direction and flux of one photon.
    fn emit(&self, rng: &mut Pcg32) -> (Vec3, Vec3, Vec3) {
        match self.light {
            TraceLight::Directional { .. } => {
                let p = optics::concentric_disc(rng.next_vec2()) * self.radius;
                let (t, b) = optics::orthonormal_basis(self.axis);
                let o = self.center - self.axis * self.start + t * p.x + b * p.y;
                (o, self.axis, self.flux)
            }
            TraceLight::Point { .. } => {
                let local = optics::uniform_cone(rng.next_vec2(), self.cos_max);
                (self.center, optics::to_world(local, self.axis), self.flux)
            }
            TraceLight::Spot {
                inner_angle,
                outer_angle,
                ..
            } => {
                let local = optics::uniform_cone(rng.next_vec2(), self.cos_max);
                let w = optics::spot_attenuation(local.z, inner_angle, outer_angle);
                (
                    self.center,
                    optics::to_world(local, self.axis),
                    self.flux * w,
                )
            }
        }
    }
}

/// Where the camera puts a world point, and the footprint of that pixel there.
struct CameraMap {
    cam: TraceCamera,
    view_from_world: glam::Affine3A,
    focal: PixelFocal,
    ortho_pixel: f32,
}

impl CameraMap {
    fn new(cam: &TraceCamera) -> Self {
        let (focal, ortho_pixel) = match cam.projection {
            CameraProjection::Perspective { fov_y } => {
                (PixelFocal::from_fov_y(fov_y, cam.width, cam.height), 0.0)
            }
            CameraProjection::Orthographic { height } => (
                PixelFocal { fx: 1.0, fy: 1.0 },
                height / cam.height.max(1) as f32,
            ),
        };
        Self {
            cam: *cam,
            view_from_world: cam.world_from_view.inverse(),
            focal,
            ortho_pixel,
        }
    }

    /// Pixel index and footprint area of world point `p` with unit normal `n`.
    fn pixel(&self, p: Vec3, n: Vec3, stats: &mut TraceStats) -> Option<(u32, f32)> {
        let v = self.view_from_world.transform_point3(p);
        let (w, h) = (self.cam.width as f32, self.cam.height as f32);
        let eye = self.cam.position();
        let (px, py, area_cos);
        match self.cam.projection {
            CameraProjection::Perspective { .. } => {
                if v.z >= -1e-12 {
                    return None;
                }
                let z = -v.z;
                px = 0.5 * w + self.focal.fx * v.x / z;
                py = 0.5 * h - self.focal.fy * v.y / z;
                let to_eye = eye - p;
                let dist = to_eye.length();
                let cos_s = n.dot(to_eye / dist).abs();
                let cos_a = z / v.length();
                area_cos = (
                    optics::pixel_footprint_area(dist, cos_a, cos_s, self.focal),
                    cos_s,
                );
            }
            CameraProjection::Orthographic { .. } => {
                px = 0.5 * w + v.x / self.ortho_pixel;
                py = 0.5 * h - v.y / self.ortho_pixel;
                let fwd = self
                    .cam
                    .world_from_view
                    .transform_vector3(Vec3::NEG_Z)
                    .normalize();
                let cos_s = n.dot(fwd).abs();
                area_cos = (
                    optics::ortho_footprint_area(self.ortho_pixel, self.ortho_pixel, cos_s),
                    cos_s,
                );
            }
        }
        if !(px >= 0.0 && py >= 0.0 && px < w && py < h) {
            return None;
        }
        if area_cos.1 < optics::MIN_SURFACE_COS {
            stats.grazing_clamps += 1;
        }
        let idx = py as u32 * self.cam.width + px as u32;
        Some((idx, area_cos.0))
    }

    /// Unit direction and distance from `p` towards the eye (for the visibility ray).
    fn towards_eye(&self, p: Vec3) -> (Vec3, f32) {
        match self.cam.projection {
            CameraProjection::Perspective { .. } => {
                let d = self.cam.position() - p;
                let l = d.length();
                (d / l, l)
            }
            CameraProjection::Orthographic { .. } => {
                let back = self
                    .cam
                    .world_from_view
                    .transform_vector3(Vec3::Z)
                    .normalize();
                let l = (self.cam.position() - p).dot(back);
                (back, l)
            }
        }
    }
}

/// The result of a reference render.
#[derive(Clone, Debug)]
pub struct TraceOutput {
    /// Caustic irradiance per pixel, lux (or W/m^2), zero where no caustic lands.
    pub image: CausticImage,
    /// Photon accounting and guard counters.
    pub stats: TraceStats,
}

/// Trace `settings.photons_per_light` photons from each light into the camera `cam`.
/// `progress`, if given, is called with (photons done, photons total) from worker threads.
pub fn trace(
    tlas: &Tlas,
    lights: &[TraceLight],
    cam: &TraceCamera,
    settings: &TraceSettings,
    progress: Option<&(dyn Fn(u64, u64) + Sync)>,
) -> TraceOutput {
    let map = CameraMap::new(cam);
    let emitters: Vec<(usize, Emitter)> = lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| make_emitter(l, tlas, settings.photons_per_light).map(|e| (i, e)))
        .collect();
    let scene_scale = tlas
        .bounds_where(|_| true)
        .map_or(1.0, |(lo, hi)| (hi - lo).max_element());
    let n = settings.photons_per_light;
    let chunks_per_light = n.div_ceil(CHUNK);
    let total = n * emitters.len() as u64;
    let done = AtomicU64::new(0);
    let mut acc = vec![DVec3::ZERO; (cam.width * cam.height) as usize];
    let mut stats = TraceStats::default();
    // Chunks in batches of BATCH_CHUNKS, each traced in parallel and added in chunk order, so
    // the image is the same on any thread count and the deposits held at once are bounded
    // (BATCH_CHUNKS · CHUNK photons), whatever the photon count.
    let jobs = emitters.len() as u64 * chunks_per_light;
    for batch in (0..jobs).step_by(BATCH_CHUNKS as usize) {
        let results: Vec<(Vec<(u32, Vec3)>, TraceStats)> = (batch
            ..(batch + BATCH_CHUNKS).min(jobs))
            .into_par_iter()
            .map(|j| {
                let (e, c) = ((j / chunks_per_light) as usize, j % chunks_per_light);
                let (light_index, em) = &emitters[e];
                let begin = c * CHUNK;
                let end = (begin + CHUNK).min(n);
                let mut deposits = Vec::new();
                let mut stats = TraceStats::default();
                for k in begin..end {
                    let mut rng = Pcg32::new(settings.seed, ((*light_index as u64) << 40) ^ k);
                    let (o, d, flux) = em.emit(&mut rng);
                    stats.photons_emitted += 1;
                    stats.flux_emitted += flux.as_dvec3();
                    trace_photon(
                        tlas,
                        &map,
                        o,
                        d,
                        flux,
                        &mut rng,
                        settings,
                        scene_scale,
                        &mut deposits,
                        &mut stats,
                    );
                }
                if let Some(p) = progress {
                    let now = done.fetch_add(end - begin, Ordering::Relaxed) + (end - begin);
                    p(now, total);
                }
                (deposits, stats)
            })
            .collect();
        for (deposits, s) in results {
            for (i, e) in deposits {
                acc[i as usize] += e.as_dvec3();
            }
            stats.merge(s);
        }
    }
    TraceOutput {
        image: CausticImage {
            width: cam.width,
            height: cam.height,
            data: acc.into_iter().map(|v| v.as_vec3()).collect(),
        },
        stats,
    }
}

#[allow(clippy::too_many_arguments)]
fn trace_photon(
    tlas: &Tlas,
    map: &CameraMap,
    mut o: Vec3,
    mut d: Vec3,
    mut flux: Vec3,
    rng: &mut Pcg32,
    settings: &TraceSettings,
    scene_scale: f32,
    deposits: &mut Vec<(u32, Vec3)>,
    stats: &mut TraceStats,
) {
    let mut reflections = 0u32;
    let mut refractions = 0u32;
    // The dielectric instance the photon is inside, if any.
    let mut medium: Option<u32> = None;
    let flux0 = flux.max_element();
    loop {
        let specular = reflections + refractions;
        let Some(hit) = tlas.closest_hit(o, d, 0.0, f32::INFINITY, |_| false) else {
            stats.photons_escaped += 1;
            if reflections + refractions > 0 {
                stats.flux_escaped += optics::finite_or_zero(flux).as_dvec3();
            }
            return;
        };
        if let Some(m) = medium
            && let Surface::Dielectric {
                attenuation_color,
                attenuation_distance,
                ..
            } = tlas.instances[m as usize].surface
        {
            let kept = flux * optics::beer_lambert(attenuation_color, attenuation_distance, hit.t);
            if specular > 0 {
                stats.flux_absorbed += optics::finite_or_zero(flux - kept).as_dvec3();
            }
            flux = kept;
        }
        let p = o + d * hit.t;
        let (ng, ns) = tlas.hit_normals(&hit);
        if !(p.is_finite() && ng.is_finite()) || ng == Vec3::ZERO {
            stats.nan_guards += 1;
            return;
        }
        // Normals facing the side the photon arrives from.
        let ng_f = if d.dot(ng) > 0.0 { -ng } else { ng };
        let ns_f = if d.dot(ns) > 0.0 { -ns } else { ns };
        let surface = tlas.instances[hit.instance as usize].surface;
        if surface.is_specular() {
            if specular == 0 {
                stats.flux_on_casters += optics::finite_or_zero(flux).as_dvec3();
            }
            if specular >= settings.max_specular_events {
                stats.photons_max_depth += 1;
                stats.flux_max_depth += optics::finite_or_zero(flux).as_dvec3();
                return;
            }
            if specular >= settings.roulette_depth {
                let q = optics::roulette_survival(flux, flux0);
                if rng.next_f32() >= q {
                    stats.photons_roulette += 1;
                    stats.flux_roulette += optics::finite_or_zero(flux).as_dvec3();
                    return;
                }
                let boosted = flux / q;
                stats.flux_roulette -= optics::finite_or_zero(boosted - flux).as_dvec3();
                flux = boosted;
            }
        }
        match surface {
            Surface::Diffuse { .. } => {
                if specular == 0 {
                    stats.photons_direct += 1;
                    return;
                }
                let f = optics::finite_or_zero(flux);
                if f != flux {
                    stats.nan_guards += 1;
                }
                stats.photons_deposited += 1;
                stats.flux_deposited += f.as_dvec3();
                *stats.flux_per_instance.entry(hit.instance).or_default() += f.as_dvec3();
                *stats
                    .flux_per_path
                    .entry((reflections, refractions))
                    .or_default() += f.as_dvec3();
                deposit(tlas, map, p, ng_f, f, scene_scale, deposits, stats);
                return;
            }
            Surface::Conductor { f0 } => {
                let kept = flux * optics::fresnel_schlick(-d.dot(ns_f), f0);
                stats.flux_absorbed += optics::finite_or_zero(flux - kept).as_dvec3();
                flux = kept;
                d = reflect_guarded(d, ns_f, ng_f, stats);
                o = optics::offset_ray_origin(p, ng_f, scene_scale);
                reflections += 1;
            }
            Surface::Dielectric {
                ior, thin, tint, ..
            } => {
                let entering = d.dot(ng) < 0.0;
                // A thin wall has air on both sides: 1 / ior from either, never TIR.
                let eta = optics::dielectric_eta(ior, entering, thin);
                let cos_i = -d.dot(ns_f);
                let r = optics::fresnel_dielectric(cos_i, eta);
                if r >= 1.0 {
                    // Stiff suite "total internal reflection paths": counted, then reflected.
                    stats.tir_events += 1;
                }
                if rng.next_f32() < r {
                    d = reflect_guarded(d, ns_f, ng_f, stats);
                    o = optics::offset_ray_origin(p, ng_f, scene_scale);
                    reflections += 1;
                } else {
                    let dt = if thin {
                        Some(d)
                    } else {
                        // Guard (stiff suite: "total internal reflection paths (IOR 2.4 gem)").
                        optics::refract(d, ns_f, eta)
                            .filter(|t| t.dot(ng_f) < 0.0)
                            .or_else(|| {
                                stats.normal_fallbacks += 1;
                                optics::refract(d, ng_f, eta)
                            })
                    };
                    let Some(dt) = dt else {
                        // TIR with R < 1 can only come from a shading/geometric normal
                        // mismatch; reflect about the geometric normal instead.
                        d = optics::reflect(d, ng_f);
                        o = optics::offset_ray_origin(p, ng_f, scene_scale);
                        reflections += 1;
                        continue;
                    };
                    // The boundary's tint on what crosses it (white for clear glass).
                    let kept = flux * tint;
                    stats.flux_absorbed += optics::finite_or_zero(flux - kept).as_dvec3();
                    flux = kept;
                    d = dt;
                    o = optics::offset_ray_origin(p, -ng_f, scene_scale);
                    if !thin {
                        medium = if entering { Some(hit.instance) } else { None };
                    }
                    refractions += 1;
                }
            }
        }
    }
}

/// Mirror reflection about the shading normal `ns_f`, unless that would send the light into
/// the surface (smooth normals on a coarse mesh): then about the geometric normal `ng_f`
/// (both facing the incoming light). Guard (stiff suite: "a million photons in one small
/// region", "total internal reflection paths (IOR 2.4 gem)"): counted in `normal_fallbacks`.
fn reflect_guarded(d: Vec3, ns_f: Vec3, ng_f: Vec3, stats: &mut TraceStats) -> Vec3 {
    let r = optics::reflect(d, ns_f);
    if r.dot(ng_f) > 0.0 {
        return r;
    }
    stats.normal_fallbacks += 1;
    optics::reflect(d, ng_f)
}

#[allow(clippy::too_many_arguments)]
fn deposit(
    tlas: &Tlas,
    map: &CameraMap,
    p: Vec3,
    n_f: Vec3,
    flux: Vec3,
    scene_scale: f32,
    deposits: &mut Vec<(u32, Vec3)>,
    stats: &mut TraceStats,
) {
    let (to_eye, dist) = map.towards_eye(p);
    // The camera must look at the lit side of the surface.
    if dist.is_nan() || dist <= 0.0 || to_eye.dot(n_f) <= 0.0 {
        return;
    }
    let Some((pixel, area)) = map.pixel(p, n_f, stats) else {
        return;
    };
    let o = optics::offset_ray_origin(p, n_f, scene_scale);
    let blocked = tlas
        .closest_hit(o, to_eye, 0.0, dist * (1.0 - 1e-5), |i| {
            matches!(i.surface, Surface::Dielectric { .. })
        })
        .is_some();
    if blocked {
        return;
    }
    let e = optics::irradiance_from_flux(flux, area);
    if e == Vec3::ZERO && flux != Vec3::ZERO {
        stats.nan_guards += 1;
        return;
    }
    stats.photons_in_view += 1;
    deposits.push((pixel, e));
}
