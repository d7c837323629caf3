//! Photon seeding over a caustics volume's entry face (seed 000 section 3.4: "Photons are
//! distributed evenly over the F_entry surface of the caustics volume and seeded with the
//! current direction of the light ... the photon pool is divided equally between all the
//! contributing lights").

use glam::{Affine3A, Vec3};

use crate::components::VolumeFace;
use crate::optics;
use crate::scene::TraceLight;

/// A photon's state, the seed's table 2 plus the two flags of section 3.2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumePhoton {
    /// `P_rad`: flux per channel (lm).
    pub flux: Vec3,
    /// `P_pos`: world position.
    pub position: Vec3,
    /// `P_dir`: unit travel direction.
    pub direction: Vec3,
    /// `P_nrm`: normal of the last surface hit (zero before any hit).
    pub normal: Vec3,
    /// `P_len`: path length travelled inside the volume, metres.
    pub path_length: f32,
    /// `P_grid`: density-grid tile index (assigned by the projectors; `u32::MAX` before).
    pub tile: u32,
    /// `P_med`: inside a dielectric.
    pub in_medium: bool,
    /// Changed direction at a specular surface: its caustic will be drawn.
    pub contributive: bool,
    /// Stopped (diffuse hit, culling face, or no flux).
    pub terminated: bool,
}

/// The entry face of a volume in world space: centre, outward unit normal, and the two edge
/// vectors spanning it (full lengths).
pub fn face_frame(
    world_from_volume: &Affine3A,
    size: Vec3,
    face: VolumeFace,
) -> (Vec3, Vec3, Vec3, Vec3) {
    let n = face.normal();
    let (a, b) = if n.x != 0.0 {
        (Vec3::Y, Vec3::Z)
    } else if n.y != 0.0 {
        (Vec3::Z, Vec3::X)
    } else {
        (Vec3::X, Vec3::Y)
    };
    let half = size * 0.5;
    let centre = world_from_volume.transform_point3(n * half);
    let eu = world_from_volume.transform_vector3(a * size);
    let ev = world_from_volume.transform_vector3(b * size);
    let nw = eu.cross(ev).try_normalize().unwrap_or(Vec3::Y);
    let nw = if nw.dot(world_from_volume.transform_vector3(n)) < 0.0 {
        -nw
    } else {
        nw
    };
    (centre, nw, eu, ev)
}

/// Seed `photons` photons evenly over the entry face for `lights` (the pool split equally,
/// each light's share on a grid of cell centres matched to the face's aspect). A photon's
/// flux is the light's irradiance on the face at its cell times the cell's area: directional
/// `E⊥ cos θ`, point and spot `I cos θ / r²` with `I = Φ / 4π` (times Bevy's spot falloff).
/// Light arriving from behind the entry face gives photons with zero flux, marked terminated.
/// Guards: zero photons or lights give nothing; a degenerate face gives nothing.
pub fn seed_photons(
    world_from_volume: &Affine3A,
    size: Vec3,
    entry: VolumeFace,
    lights: &[TraceLight],
    photons: u32,
) -> Vec<VolumePhoton> {
    let (centre, n, eu, ev) = face_frame(world_from_volume, size, entry);
    let (lu, lv) = (eu.length(), ev.length());
    if lights.is_empty() || photons == 0 || !(lu > 0.0 && lv > 0.0) || !centre.is_finite() {
        return Vec::new();
    }
    let per_light = (photons / lights.len() as u32).max(1);
    // nu / nv ≈ lu / lv and nu nv ≈ per_light.
    let nu = ((per_light as f32 * lu / lv).sqrt().round() as u32).clamp(1, per_light);
    let nv = (per_light / nu).max(1);
    let cell_area = lu * lv / (nu * nv) as f32;
    let corner = centre - eu * 0.5 - ev * 0.5;
    let mut out = Vec::with_capacity((nu * nv) as usize * lights.len());
    for light in lights {
        for j in 0..nv {
            for i in 0..nu {
                let p = corner
                    + eu * ((i as f32 + 0.5) / nu as f32)
                    + ev * ((j as f32 + 0.5) / nv as f32);
                let (dir, irradiance) = match *light {
                    TraceLight::Directional {
                        direction,
                        illuminance,
                    } => {
                        let d = direction.try_normalize().unwrap_or(Vec3::NEG_Y);
                        (d, illuminance * (-d.dot(n)).max(0.0))
                    }
                    TraceLight::Point { position, flux } => {
                        point_irradiance(p, n, position, flux, 1.0)
                    }
                    TraceLight::Spot {
                        position,
                        direction,
                        flux,
                        inner_angle,
                        outer_angle,
                    } => {
                        let axis = direction.try_normalize().unwrap_or(Vec3::NEG_Y);
                        let d = (p - position).try_normalize().unwrap_or(-n);
                        let fall = optics::spot_attenuation(d.dot(axis), inner_angle, outer_angle);
                        point_irradiance(p, n, position, flux, fall)
                    }
                };
                let flux = optics::finite_or_zero(irradiance * cell_area);
                out.push(VolumePhoton {
                    flux,
                    position: p,
                    direction: dir,
                    normal: Vec3::ZERO,
                    path_length: 0.0,
                    tile: u32::MAX,
                    in_medium: false,
                    contributive: false,
                    terminated: flux == Vec3::ZERO,
                });
            }
        }
    }
    out
}

/// The lights (indices into `lights`) that shine but none of whose light enters through the
/// entry face: all their photons of `seed_photons(.., lights, ..)` carry zero flux (a point or
/// spot light behind the face's plane, inside the box; a spot turned away; a sun travelling
/// out of the face).
pub fn lights_shut_out(photons: &[VolumePhoton], lights: &[TraceLight]) -> Vec<usize> {
    if lights.is_empty() || photons.is_empty() {
        return Vec::new();
    }
    let per_light = photons.len() / lights.len();
    lights
        .iter()
        .enumerate()
        .filter(|(i, light)| {
            let power = match **light {
                TraceLight::Directional { illuminance, .. } => illuminance,
                TraceLight::Point { flux, .. } | TraceLight::Spot { flux, .. } => flux,
            };
            let own = &photons[i * per_light..(i + 1) * per_light];
            power.max_element() > 0.0 && own.iter().all(|p| p.flux == Vec3::ZERO)
        })
        .map(|(i, _)| i)
        .collect()
}

/// Direction from a point or spot light at `position` to `p`, and the irradiance it gives the
/// face of normal `n` there: `Φ / 4π · falloff · cos θ / r²`.
fn point_irradiance(p: Vec3, n: Vec3, position: Vec3, flux: Vec3, falloff: f32) -> (Vec3, Vec3) {
    let to = p - position;
    let r2 = to.length_squared().max(1e-12);
    let d = to.try_normalize().unwrap_or(-n);
    (
        d,
        flux / (4.0 * core::f32::consts::PI) * falloff * (-d.dot(n)).max(0.0) / r2,
    )
}
