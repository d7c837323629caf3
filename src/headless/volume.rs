//! Caustics volumes in the headless renderer: fit one volume per light around the casters when
//! the scene declares none (`--technique volume`), glTF `extras` volumes, and the counters.

use bevy::prelude::*;
use serde::Serialize;

use crate::components::CausticsVolume;
use crate::scene::{CausticsScene, TraceLight};

/// Where the fitting stands.
#[derive(Resource, Default)]
pub(crate) struct VolumesFitted {
    /// Volumes are in place (declared, fitted, or there was nothing to fit).
    pub done: bool,
    /// The scene declared volumes of its own: none is fitted.
    declared: bool,
    /// The lights a volume was fitted for (or that were told none fits).
    lights: Vec<Entity>,
}

/// The settings a fitted volume takes from the job (everything but its box and faces).
pub(crate) fn apply_template(v: &mut CausticsVolume, t: &CausticsVolume) {
    v.slabs = t.slabs;
    v.photons = t.photons;
    v.projector_resolution = t.projector_resolution;
    v.gbuffer_resolution = t.gbuffer_resolution;
    v.tile_size = t.tile_size;
    v.density_photons = t.density_photons;
    v.splat_overlap = t.splat_overlap;
    v.blur_radius = t.blur_radius;
    v.lod_distance = t.lod_distance;
    v.differential = t.differential;
    v.frustum_cull = t.frustum_cull;
    v.progressive = t.progressive;
}

/// A volume the headless renderer fitted, and the casters' bounds it was fitted to.
#[derive(Component)]
pub(crate) struct FittedVolume((Vec3, Vec3));

/// The margin a fitted volume leaves around the casters, a share of each extent.
const FIT_MARGIN: f32 = 0.1;

/// The volume around casters `bounds` for `light` ([`CausticsVolume::fit`] or
/// [`CausticsVolume::fit_point`]); `None` when the light lies inside the bounds.
fn fit_for(bounds: (Vec3, Vec3), light: &TraceLight) -> Option<(CausticsVolume, Transform)> {
    match *light {
        TraceLight::Directional { direction, .. } => {
            Some(CausticsVolume::fit(bounds, direction, FIT_MARGIN))
        }
        TraceLight::Point { position, .. } | TraceLight::Spot { position, .. } => {
            CausticsVolume::fit_point(bounds, position, FIT_MARGIN)
        }
    }
}

/// Fit one volume per caustic light around the casters (their world box), entry face towards
/// the light, once the scene is gathered, unless the scene declares volumes of its own. A light
/// that joins the scene later (a stage's sun gathered a frame after a model's own lights) gets
/// its volume then. A fitted volume follows its casters: when their bounds change (a caster
/// moved), it is fitted again, as a game would parent a volume to a moving caster or size it
/// for the caster's path (a volume left behind lights only the part of the caster still inside
/// it).
pub(crate) fn fit_volumes(
    mut commands: Commands,
    template: Res<VolumeTemplate>,
    scene: Option<Res<CausticsScene>>,
    existing: Query<(), With<CausticsVolume>>,
    cameras: Query<(), With<crate::Caustics>>,
    mut fitted: ResMut<VolumesFitted>,
    mut followers: Query<(&mut CausticsVolume, &mut Transform, &mut FittedVolume)>,
) {
    // After the camera and the job's hook (which may declare volumes) are in.
    if fitted.declared || !template.0 || cameras.is_empty() {
        return;
    }
    if !fitted.done && !existing.is_empty() {
        fitted.declared = true;
        fitted.done = true;
        return;
    }
    // Lights and casters change with the scene only.
    let Some(scene) = scene.filter(|s| !fitted.done || s.is_changed()) else {
        return;
    };
    if scene.lights.is_empty() {
        return;
    }
    let Some(bounds) = scene.tlas.bounds_where(|i| i.surface.is_specular()) else {
        // No caster: nothing to fit, nothing to run.
        fitted.done = true;
        return;
    };
    if fitted.done {
        refit(&scene, &mut followers);
    }
    for (entity, light) in &scene.lights {
        if fitted.lights.contains(entity) {
            continue;
        }
        fitted.lights.push(*entity);
        let Some((mut v, t)) = fit_for(bounds, light) else {
            warn!(
                "caustics volume: light {entity} lies inside the casters' bounds, so no volume \
                 around them can take its light through an entry face; none fitted for it \
                 (AAPS or the photon map follow light from anywhere)"
            );
            continue;
        };
        apply_template(&mut v, &template.1);
        v.light = Some(*entity);
        commands.spawn((
            v,
            t,
            FittedVolume(bounds),
            Name::new("caustics volume (fitted)"),
        ));
    }
    fitted.done = true;
}

/// Fit the fitted volumes again where the casters' bounds changed (their box and pose only).
fn refit(
    scene: &CausticsScene,
    followers: &mut Query<(&mut CausticsVolume, &mut Transform, &mut FittedVolume)>,
) {
    let Some(bounds) = scene.tlas.bounds_where(|i| i.surface.is_specular()) else {
        return;
    };
    for (mut v, mut t, mut fitted) in followers.iter_mut() {
        if fitted.0 == bounds {
            continue;
        }
        let light = scene.lights.iter().find(|(e, _)| Some(*e) == v.light);
        let Some((fit, pose)) = light.and_then(|(_, l)| fit_for(bounds, l)) else {
            continue;
        };
        v.size = fit.size;
        *t = pose;
        fitted.0 = bounds;
    }
}

/// Whether to fit volumes, and the settings they take.
#[derive(Resource, Clone, Default)]
pub(crate) struct VolumeTemplate(pub bool, pub CausticsVolume);

/// The counters of a volume after the render (technique `volume`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct VolumeCounters {
    /// Luminous flux seeded on the entry face, lm.
    pub entered_lm: f64,
    /// Luminous flux of the photons given a receiver (splatted), lm.
    pub splatted_lm: f64,
    /// Photons given a receiver beyond an exit face or inside.
    pub hits: u64,
    /// Of which contributive photons stopped on a diffuse surface inside the volume.
    pub deposits: u64,
    /// Contributive photons whose projector found no diffuse receiver.
    pub missed: u64,
    /// Contributive photons through a culling face.
    pub culled: u64,
    /// Total internal reflections.
    pub tir: u64,
    /// Non-finite states caught.
    pub nan_guards: u64,
    /// Photons that turned back across an inner slab boundary.
    pub backward: u64,
    /// Projector hits on specular receivers (not drawn).
    pub specular_outside: u64,
    /// Marches stopped by the step limit.
    pub step_limit: u64,
    /// Refractions.
    pub refracted: u64,
    /// Reflections (mirrors and Fresnel).
    pub reflected: u64,
    /// Transmissive hits the media rules ignored.
    pub ignored: u64,
    /// Non-contributive photons stopped on diffuse surfaces.
    pub absorbed: u64,
    /// Photons that left the volume still inside a dielectric (no surface let them out).
    pub left_inside: u64,
    /// Their luminous flux, lm.
    pub left_inside_lm: f64,
    /// Luminous flux of the photons still in flight after the most slab hops
    /// (`4 · slabs + 4`), dropped (counted in `step_limit`), lm.
    pub hop_limit_lm: f64,
}

impl VolumeCounters {
    /// From the counter words (`C_*` in common.wgsl).
    pub fn from_words(c: &[u32]) -> Self {
        let u = |i: usize| c.get(i).copied().unwrap_or(0) as u64;
        let f = |i: usize| f32::from_bits(c.get(i).copied().unwrap_or(0)) as f64;
        Self {
            entered_lm: f(0),
            splatted_lm: f(1),
            hits: u(2),
            deposits: u(3),
            missed: u(4),
            culled: u(5),
            tir: u(6),
            nan_guards: u(7),
            backward: u(8),
            specular_outside: u(9),
            step_limit: u(10),
            refracted: u(11),
            reflected: u(12),
            ignored: u(13),
            absorbed: u(14),
            left_inside: u(15),
            left_inside_lm: f(16),
            hop_limit_lm: f(17),
        }
    }
}
