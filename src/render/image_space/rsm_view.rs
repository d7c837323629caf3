//! Each caustic light's reflective-shadow-map views (render world): one map, or the six faces
//! of a cube when the casters surround the light, fitted to the casters' bounding sphere, and
//! the uniforms the RSM raster and the trace read of them.

use bevy::prelude::*;

use super::view::{LIGHT_STRIDE, SMALL_STRIDE, SpaceView, push};
use crate::optics::{cone_around_sphere, photon_flux_scale};
use crate::render::trace::scene::GpuLight;

/// One caustic light's RSM view and photon parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct RsmLight {
    /// The light's view: orthographic (directional) or a perspective cone (point, spot).
    pub view: SpaceView,
    /// Viewing direction.
    pub axis: Vec3,
    /// The GPU light it came from.
    pub light: GpuLight,
    /// Its face of a cube (+X, −X, +Y, −Y, +Z, −Z), if the light has six maps.
    pub face: Option<u8>,
}

/// Widest cone a point or spot light's single RSM covers; a light that needs more (the
/// casters around it) gets a cube of six 90-degree maps.
pub const MAX_CONE_HALF_ANGLE: f32 = 60.0 * std::f32::consts::PI / 180.0;

/// The RSMs of each light: `None` for one map, `Some(face)` for face `face` of a cube
/// (+X, −X, +Y, −Y, +Z, −Z). A point or spot light whose casters' bounding sphere
/// (`centre`, `radius`) is wider than [`MAX_CONE_HALF_ANGLE`] from it (or holds it) gets
/// the six faces of a cube, which tile every direction once.
pub fn rsm_sources(
    lights: &[GpuLight],
    (centre, radius): (Vec3, f32),
) -> Vec<(GpuLight, Option<u8>)> {
    let mut out = Vec::new();
    for l in lights {
        let needed = if l.kind == 0 {
            0.0
        } else {
            let dist = (centre - l.position).length();
            let cone = if dist <= radius {
                std::f32::consts::PI
            } else {
                (radius / dist).clamp(0.0, 1.0).asin()
            };
            let outer = if l.kind == 2 {
                l.cos_outer.clamp(-1.0, 1.0).acos()
            } else {
                std::f32::consts::PI
            };
            cone.min(outer)
        };
        if needed > MAX_CONE_HALF_ANGLE {
            out.extend((0..6).map(|f| (*l, Some(f))));
        } else {
            out.push((*l, None));
        }
    }
    out
}

/// The RSM view of `light` (or of its cube face `face`) over the casters' bounding sphere
/// (`centre`, `radius`) in a scene of bounding radius `scene_radius` around `scene_centre`,
/// at `res`² texels.
///
/// Directional: an orthographic square of side `2 · radius` around the casters, from the
/// AAPS light's origin grid (placed before the whole scene). Point: the cone from the light
/// that holds the casters' sphere ([`cone_around_sphere`]); spot: the same, at most its outer
/// angle; a cube face: 90 degrees around its axis.
pub fn rsm_light(
    light: &GpuLight,
    face: Option<u8>,
    (centre, radius): (Vec3, f32),
    (scene_centre, scene_radius): (Vec3, f32),
    res: u32,
) -> RsmLight {
    let res_f = res as f32;
    let up_for = |d: Vec3| {
        if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X }
    };
    if light.kind == 0 {
        let d = light.axis.normalize_or(Vec3::NEG_Y);
        let eye = light.position + 0.5 * (light.side_u + light.side_v);
        let r = 0.5 * light.side_u.length().max(1e-6);
        let far = (eye - scene_centre).length() + 2.0 * scene_radius + r;
        let view_from_world = Mat4::look_to_rh(eye, d, up_for(d));
        let clip_from_view = Mat4::orthographic_rh(-r, r, -r, r, 0.0, far.max(1e-3));
        return RsmLight {
            view: SpaceView {
                clip_from_view,
                view_from_world,
                size: Vec4::new(res_f, res_f, 0.0, 0.0),
                eye: eye.extend(0.0),
            },
            axis: d,
            light: *light,
            face: None,
        };
    }
    let cap = if light.kind == 2 {
        light.cos_outer.clamp(-1.0, 1.0).acos()
    } else {
        std::f32::consts::PI
    };
    let (axis, half) = match face {
        Some(f) => {
            let axes = [
                Vec3::X,
                Vec3::NEG_X,
                Vec3::Y,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::NEG_Z,
            ];
            (axes[f as usize % 6], std::f32::consts::FRAC_PI_4)
        }
        None => cone_around_sphere(light.position, centre, radius, cap, light.axis),
    };
    let dist = (centre - light.position).length();
    let scale = scene_radius.max(1e-3);
    let near = ((dist - radius) * 0.5).max(scale * 1e-4);
    let far = (dist + 2.0 * scene_radius + radius).max(near * 2.0);
    let view_from_world = Mat4::look_to_rh(light.position, axis, up_for(axis));
    let clip_from_view = Mat4::perspective_rh(2.0 * half, 1.0, near, far);
    let f = 0.5 * res_f * clip_from_view.x_axis.x;
    RsmLight {
        view: SpaceView {
            clip_from_view,
            view_from_world,
            size: Vec4::new(res_f, res_f, f, f),
            eye: light.position.extend(near),
        },
        axis,
        light: *light,
        face,
    }
}

impl RsmLight {
    /// The `IsLight` uniform for `photons` photons at `res`² texels, the light's RSM layers
    /// starting at `first_layer`. The flux of a photon is the texel's flux times
    /// `texels / photons` ([`photon_flux_scale`]): directional `E · (2r)² / photons`; point
    /// and spot `I · cos³α / f² · texels / photons` with `I = Φ / 4π` (the shader applies
    /// `cos³α` and the spot cone).
    pub fn uniform(&self, photons: u32, res: u32, first_layer: u32) -> Vec<u8> {
        let texels = (res as f32) * (res as f32);
        let scale = photon_flux_scale(texels, photons as f32);
        let flux = if self.light.kind == 0 {
            // power = E (2r)² over the square: per texel power / texels.
            self.light.power / texels * scale
        } else {
            let f = self.view.size.z.max(1e-6);
            self.light.power / (4.0 * std::f32::consts::PI) / (f * f) * scale
        };
        let mut b = self.view.bytes();
        push(&mut b, &[flux.x, flux.y, flux.z, photons as f32]);
        let a = self.light.axis.normalize_or(Vec3::NEG_Y);
        push(&mut b, &[a.x, a.y, a.z, self.light.cos_inner]);
        push(
            &mut b,
            &[
                self.light.cos_outer,
                self.light.kind as f32,
                res as f32,
                first_layer as f32,
            ],
        );
        // A cube face: its face and the entry of face 0 (each entry has three layers).
        let cube = self.face.map_or([-1.0, 0.0], |f| {
            [
                f32::from(f),
                (first_layer / 3).saturating_sub(u32::from(f)) as f32,
            ]
        });
        push(&mut b, &[cube[0], cube[1], 0.0, 0.0]);
        b.resize(LIGHT_STRIDE as usize, 0);
        b
    }

    /// The `RsmView` uniform of the raster passes.
    pub fn raster_uniform(&self) -> Vec<u8> {
        let mut b = Vec::new();
        push(
            &mut b,
            &(self.view.clip_from_view * self.view.view_from_world).to_cols_array(),
        );
        push(&mut b, &self.view.view_from_world.to_cols_array());
        let persp = if self.view.eye.w > 0.0 { 1.0 } else { 0.0 };
        push(
            &mut b,
            &[self.view.eye.x, self.view.eye.y, self.view.eye.z, persp],
        );
        push(&mut b, &[self.axis.x, self.axis.y, self.axis.z, 0.0]);
        b.resize(SMALL_STRIDE as usize, 0);
        b
    }
}
