//! Which changes of the gathered scene can change its caustics (issue 28 item 3: "changes
//! stay local").
//!
//! Histories (image space's SVGF, the photon map's progressive mean) restart on
//! [`CausticsScene::caustic_generation`](super::CausticsScene::caustic_generation), which
//! moves only when a caustic can change:
//! - a caster (a specular instance) is added, removed, moved, reshaped or changes material;
//! - a light is added or removed, or has drifted beyond the tolerances below since the last
//!   restart (a sun jittering by 1e-5 rad does not restart anything, a sun turning steadily
//!   restarts every few frames);
//! - a receiver (a diffuse instance) moved and its old or new bounds lie in the caustic
//!   light's reach ([`CausticReach`]): at least [`REACH_SHARE`] of some light's caustic flux
//!   crosses them.
//!
//! Every other change still re-traces with the new state; the shared temporal stage
//! (`render::temporal`) rejects, per pixel, the history that disagrees with it, and the
//! photon map restarts single pixels whose visible surface moved.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::{Instance, Surface, Tlas, TraceLight};
use crate::optics;

/// A light's direction may turn this far (radians) from its direction at the last restart
/// before its caustics restart.
pub const LIGHT_TURN_TOLERANCE: f32 = 1e-4;
/// A light may move this far, as a fraction of the scene's extent, before its caustics restart.
pub const LIGHT_MOVE_TOLERANCE: f32 = 1e-4;
/// A light's power (per channel, relative) may change this much before its caustics restart.
pub const LIGHT_POWER_TOLERANCE: f32 = 1e-3;
/// A moved receiver restarts the caustics when at least this share of some light's caustic
/// flux crosses its old or new bounds.
pub const REACH_SHARE: f32 = 0.01;
/// Paths per light of [`CausticReach::trace`].
pub const REACH_PATHS: u32 = 512;
/// Specular events a reach path follows.
const REACH_EVENTS: u32 = 8;
/// Branches carrying less than this share of a path are not followed.
const REACH_MIN_SHARE: f32 = 1e-3;

/// The angle between two directions, radians, accurate for tiny angles (where `acos` of the
/// dot product rounds to 0 in f32). Zero or non-finite input gives π (always "turned").
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    let (c, d) = (a.cross(b).length(), a.dot(b));
    let angle = c.atan2(d);
    if angle.is_finite() && a != Vec3::ZERO && b != Vec3::ZERO {
        angle
    } else {
        core::f32::consts::PI
    }
}

/// `x` above `tolerance`, or not a number (a non-finite input counts as a change).
fn beyond(x: f32, tolerance: f32) -> bool {
    x.is_nan() || x > tolerance
}

fn power_changed(a: Vec3, b: Vec3) -> bool {
    let scale = a.abs().max(b.abs()).max_element();
    beyond((a - b).abs().max_element(), LIGHT_POWER_TOLERANCE * scale)
}

/// Whether `new` differs from `old` beyond the tolerances; `extent` is the scene's size, metres.
pub fn light_drifted(old: &TraceLight, new: &TraceLight, extent: f32) -> bool {
    let moved = |a: Vec3, b: Vec3| beyond(a.distance(b), LIGHT_MOVE_TOLERANCE * extent);
    let turned = |a: Vec3, b: Vec3| angle_between(a, b) > LIGHT_TURN_TOLERANCE;
    match (*old, *new) {
        (
            TraceLight::Directional {
                direction: d0,
                illuminance: e0,
            },
            TraceLight::Directional {
                direction: d1,
                illuminance: e1,
            },
        ) => turned(d0, d1) || power_changed(e0, e1),
        (
            TraceLight::Point {
                position: p0,
                flux: f0,
            },
            TraceLight::Point {
                position: p1,
                flux: f1,
            },
        ) => moved(p0, p1) || power_changed(f0, f1),
        (
            TraceLight::Spot {
                position: p0,
                direction: d0,
                flux: f0,
                inner_angle: i0,
                outer_angle: o0,
            },
            TraceLight::Spot {
                position: p1,
                direction: d1,
                flux: f1,
                inner_angle: i1,
                outer_angle: o1,
            },
        ) => {
            moved(p0, p1)
                || turned(d0, d1)
                || power_changed(f0, f1)
                || beyond((i0 - i1).abs(), LIGHT_TURN_TOLERANCE)
                || beyond((o0 - o1).abs(), LIGHT_TURN_TOLERANCE)
        }
        _ => true,
    }
}

/// Whether the lights (matched by their key, the entity in the ECS path) differ beyond the
/// tolerances: one added, removed, or drifted.
pub fn lights_drifted<K: PartialEq>(
    old: &[(K, TraceLight)],
    new: &[(K, TraceLight)],
    extent: f32,
) -> bool {
    old.len() != new.len()
        || new.iter().any(|(k, l)| {
            old.iter()
                .find(|(o, _)| o == k)
                .is_none_or(|(_, o)| light_drifted(o, l, extent))
        })
}

/// What changed between two TLAS, matched by instance id.
#[derive(Debug, Default, PartialEq)]
pub struct InstanceChanges {
    /// A caster was added, removed or changed.
    pub casters: bool,
    /// World bounds (old and new) of every receiver added, removed or changed.
    pub receivers: Vec<(Vec3, Vec3)>,
}

fn same(a: &Instance, b: &Instance) -> bool {
    std::sync::Arc::ptr_eq(&a.blas, &b.blas)
        && a.world_from_local == b.world_from_local
        && a.surface == b.surface
}

/// The instances that differ between `old` and `new`.
pub fn changed_instances(old: &Tlas, new: &Tlas) -> InstanceChanges {
    let before: HashMap<u64, &Instance> = old.instances.iter().map(|i| (i.id, i)).collect();
    let mut out = InstanceChanges::default();
    let note = |i: &Instance, out: &mut InstanceChanges| {
        if i.surface.is_specular() {
            out.casters = true;
        } else {
            out.receivers.push(i.world_bounds());
        }
    };
    let mut seen = 0;
    for i in &new.instances {
        match before.get(&i.id) {
            Some(o) => {
                seen += 1;
                if !same(o, i) {
                    note(o, &mut out);
                    note(i, &mut out);
                }
            }
            None => note(i, &mut out),
        }
    }
    if seen < before.len() {
        let now: std::collections::HashSet<u64> = new.instances.iter().map(|i| i.id).collect();
        for o in old.instances.iter().filter(|o| !now.contains(&o.id)) {
            note(o, &mut out);
        }
    }
    out
}

/// Where each light's caustic light goes: segments of paths from the light through the
/// casters (both Fresnel branches, up to 8 specular events) to the receiver they end on, or
/// out of the scene, each with its share of the light's caustic flux.
#[derive(Clone, Debug, Default)]
pub struct CausticReach {
    /// Start, end, light index and share of that light's flux.
    segments: Vec<(Vec3, Vec3, usize, f32)>,
    /// Per light: the share of its paths that hit a caster first.
    caustic: Vec<f32>,
}

struct Walk<'a> {
    tlas: &'a Tlas,
    scale: f32,
    far: f32,
    light: usize,
}

impl CausticReach {
    /// Trace [`REACH_PATHS`] paths per light, aimed at the casters' bounding sphere.
    pub fn trace<K>(tlas: &Tlas, lights: &[(K, TraceLight)]) -> Self {
        let mut out = Self::default();
        let (Some((lo, hi)), Some((slo, shi))) = (
            tlas.bounds_where(|i| i.surface.is_specular()),
            tlas.bounds_where(|_| true),
        ) else {
            return out;
        };
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo) * 0.5).length().max(1e-9);
        let extent = (shi - slo).length().max(radius);
        for (light, (_, l)) in lights.iter().enumerate() {
            let walk = Walk {
                tlas,
                scale: extent,
                far: 4.0 * extent,
                light,
            };
            out.caustic.push(0.0);
            for n in 0..REACH_PATHS {
                let u = optics::r2_point(n, [0, 0]);
                let Some((o, d, w)) = emit(l, u, centre, radius, 2.0 * extent) else {
                    continue;
                };
                let w = w / REACH_PATHS as f32;
                out.follow(&walk, o, d, w, 0);
            }
        }
        out
    }

    fn follow(&mut self, walk: &Walk, o: Vec3, d: Vec3, w: f32, events: u32) {
        let Some(hit) = walk.tlas.closest_hit(o, d, 0.0, f32::INFINITY, |_| false) else {
            if events > 0 {
                self.segments.push((o, o + d * walk.far, walk.light, w));
            }
            return;
        };
        let p = o + d * hit.t;
        let surface = walk.tlas.instances[hit.instance as usize].surface;
        if events == 0 {
            if !surface.is_specular() {
                // Direct light, no caustic.
                return;
            }
            self.caustic[walk.light] += w;
        }
        self.segments.push((o, p, walk.light, w));
        let (ng, ns) = walk.tlas.hit_normals(&hit);
        if events >= REACH_EVENTS || !(p.is_finite() && ng.is_finite()) || ng == Vec3::ZERO {
            return;
        }
        let ng_f = if d.dot(ng) > 0.0 { -ng } else { ng };
        let ns_f = if d.dot(ns) > 0.0 { -ns } else { ns };
        let out_o = optics::offset_ray_origin(p, ng_f, walk.scale);
        let in_o = optics::offset_ray_origin(p, -ng_f, walk.scale);
        let reflected = optics::reflect(d, ns_f);
        match surface {
            Surface::Diffuse { .. } => {}
            Surface::Conductor { .. } => self.follow(walk, out_o, reflected, w, events + 1),
            Surface::Dielectric { ior, thin, .. } => {
                let eta = optics::dielectric_eta(ior, d.dot(ng) < 0.0, thin);
                let r = optics::fresnel_dielectric(-d.dot(ns_f), eta).clamp(0.0, 1.0);
                let refracted = if thin {
                    Some(d)
                } else {
                    optics::refract(d, ns_f, eta).filter(|t| t.is_finite())
                };
                let r = if refracted.is_some() { r } else { 1.0 };
                if w * r >= REACH_MIN_SHARE / REACH_PATHS as f32 {
                    self.follow(walk, out_o, reflected, w * r, events + 1);
                }
                if let Some(t) = refracted
                    && w * (1.0 - r) >= REACH_MIN_SHARE / REACH_PATHS as f32
                {
                    self.follow(walk, in_o, t, w * (1.0 - r), events + 1);
                }
            }
        }
    }

    /// The largest share, over the lights, of a light's caustic flux that crosses the box
    /// `(lo, hi)` (summed over segments, so light crossing twice counts twice; at most 1); 0
    /// when no light reaches a caster or the box is empty.
    pub fn share_through(&self, (lo, hi): (Vec3, Vec3)) -> f32 {
        if !lo.cmple(hi).all() {
            return 0.0;
        }
        let mut through = vec![0.0f32; self.caustic.len()];
        for &(a, b, light, w) in &self.segments {
            if segment_hits_box(a, b, lo, hi) {
                through[light] += w;
            }
        }
        through
            .iter()
            .zip(&self.caustic)
            .map(|(t, c)| if *c > 0.0 { t / c } else { 0.0 })
            .fold(0.0, f32::max)
            .min(1.0)
    }

    /// Segments traced (cost).
    pub fn segment_count(&self) -> usize {
        self.segments.len()
    }
}

/// One path from `light` (origin, unit direction, weight relative to an unweighted path),
/// aimed at the sphere `(centre, radius)`; `start` is how far back a directional light's
/// paths begin. `None` for a degenerate light.
fn emit(
    light: &TraceLight,
    u: Vec2,
    centre: Vec3,
    radius: f32,
    start: f32,
) -> Option<(Vec3, Vec3, f32)> {
    match *light {
        TraceLight::Directional { direction, .. } => {
            let d = direction.try_normalize()?;
            let p = optics::concentric_disc(u) * radius;
            let (t, b) = optics::orthonormal_basis(d);
            Some((centre - d * (start + radius) + t * p.x + b * p.y, d, 1.0))
        }
        TraceLight::Point { position, .. } => {
            let (axis, cos_max) = cone_to(position, centre, radius);
            let d = optics::to_world(optics::uniform_cone(u, cos_max), axis);
            Some((position, d, 1.0))
        }
        TraceLight::Spot {
            position,
            direction,
            inner_angle,
            outer_angle,
            ..
        } => {
            let axis_light = direction.try_normalize()?;
            let (axis, cos_max) = cone_to(position, centre, radius);
            let d = optics::to_world(optics::uniform_cone(u, cos_max), axis);
            let w = optics::spot_attenuation(d.dot(axis_light), inner_angle, outer_angle);
            (w > 0.0).then_some((position, d, w))
        }
    }
}

/// The cone from `p` around the sphere `(c, r)`: axis and cosine of its half angle (the whole
/// sphere of directions when `p` is inside).
fn cone_to(p: Vec3, c: Vec3, r: f32) -> (Vec3, f32) {
    let to = c - p;
    let dist = to.length();
    if dist > r * 1.0001 {
        (to / dist, (1.0 - (r / dist).powi(2)).max(0.0).sqrt())
    } else {
        (Vec3::Z, -1.0)
    }
}

/// Whether the segment `a`–`b` meets the box `(lo, hi)` (slab test).
fn segment_hits_box(a: Vec3, b: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for k in 0..3 {
        if d[k].abs() < 1e-30 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (mut n, mut f) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
        if t0 > t1 {
            return false;
        }
    }
    true
}
