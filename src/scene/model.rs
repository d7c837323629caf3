//! The plain-Rust scene every CPU algorithm reads: surfaces, lights, camera.
//!
//! Built from the ECS by [`super::collect`] and, in tests, directly from a
//! `scenes::SceneDesc` (the `tools` feature). No Bevy render types.

use glam::{Affine3A, Vec3};

/// Roughness at or below which a metal counts as a mirror (a caster). Above it the surface is
/// glossy and treated as a diffuse receiver: its caustics would be blurred beyond what the
/// techniques here model.
pub const MIRROR_ROUGHNESS_CUTOFF: f32 = 0.2;
/// Metallic at or above which a surface is a conductor.
pub const METALLIC_CUTOFF: f32 = 0.9;

/// How light interacts with a surface, as the tracers see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// A Lambertian receiver with linear diffuse albedo (`base_color (1 - metallic)`).
    Diffuse {
        /// Linear RGB albedo in [0, 1].
        albedo: Vec3,
    },
    /// A dielectric interface (glass, water): Fresnel reflection and Snell refraction.
    Dielectric {
        /// Index of refraction relative to air, >= 1.
        ior: f32,
        /// Colour left after `attenuation_distance` metres inside (Beer-Lambert).
        attenuation_color: Vec3,
        /// Metres; infinity for a clear medium.
        attenuation_distance: f32,
        /// Thin-walled (a sheet: transmission without bending), as glTF's `thickness = 0`.
        thin: bool,
        /// What each crossing of the interface lets through, per channel, in [0, 1]: glTF's
        /// base colour times `transmissionFactor` ("a coloured, transparent foil" on the
        /// boundary, KHR_materials_volume), blended towards white by a blended material's
        /// alpha coverage. Fresnel reflection is not tinted. White for clear glass.
        tint: Vec3,
    },
    /// A conductor mirror, reflectance by Schlick from the normal-incidence colour.
    Conductor {
        /// Normal-incidence reflectance per channel.
        f0: Vec3,
    },
}

impl Surface {
    /// True for surfaces that redirect light specularly (casters).
    pub fn is_specular(&self) -> bool {
        !matches!(self, Surface::Diffuse { .. })
    }
}

/// The material parameters the classifier reads: the subset of Bevy's `StandardMaterial` (and
/// of glTF's PBR + transmission/ior/volume extensions) that matters for caustics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialParams {
    /// Linear base colour.
    pub base_color: Vec3,
    /// Metallic in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0, 1].
    pub perceptual_roughness: f32,
    /// `specular_transmission` in [0, 1] (KHR_materials_transmission).
    pub specular_transmission: f32,
    /// Index of refraction (KHR_materials_ior), default 1.5.
    pub ior: f32,
    /// Thickness in metres (KHR_materials_volume); 0 means thin-walled.
    pub thickness: f32,
    /// Attenuation distance in metres, infinity for none.
    pub attenuation_distance: f32,
    /// Attenuation colour.
    pub attenuation_color: Vec3,
    /// Coverage of a blended material (its base colour's alpha, `AlphaMode::Blend`): the
    /// part of the light that meets the surface at all; 1 for opaque and masked materials.
    pub coverage: f32,
}

impl Default for MaterialParams {
    fn default() -> Self {
        Self {
            base_color: Vec3::ONE,
            metallic: 0.0,
            perceptual_roughness: 0.5,
            specular_transmission: 0.0,
            ior: 1.5,
            thickness: 0.0,
            attenuation_distance: f32::INFINITY,
            attenuation_color: Vec3::ONE,
            coverage: 1.0,
        }
    }
}

/// The automatic guess of the architecture: `specular_transmission > 0` is a dielectric;
/// `metallic >= METALLIC_CUTOFF` with roughness `<= MIRROR_ROUGHNESS_CUTOFF` is a mirror;
/// anything else is a diffuse receiver with albedo `base_color (1 - metallic)`.
pub fn classify_material(m: &MaterialParams) -> Surface {
    if m.specular_transmission > 0.0 {
        Surface::Dielectric {
            ior: if m.ior.is_finite() {
                m.ior.max(1.0)
            } else {
                1.5
            },
            attenuation_color: m.attenuation_color.clamp(Vec3::ZERO, Vec3::ONE),
            attenuation_distance: if m.attenuation_distance > 0.0 {
                m.attenuation_distance
            } else {
                f32::INFINITY
            },
            thin: m.thickness <= 0.0,
            tint: transmission_tint(m),
        }
    } else if m.metallic >= METALLIC_CUTOFF && m.perceptual_roughness <= MIRROR_ROUGHNESS_CUTOFF {
        Surface::Conductor {
            f0: m.base_color.clamp(Vec3::ZERO, Vec3::ONE),
        }
    } else {
        Surface::Diffuse {
            albedo: (m.base_color * (1.0 - m.metallic.clamp(0.0, 1.0)))
                .clamp(Vec3::ZERO, Vec3::ONE),
        }
    }
}

/// [`Surface::Dielectric::tint`] of a transmissive material: `base_color` times
/// `specular_transmission` (the rest of the light that is not reflected is glTF's diffuse
/// base, no caustic), mixed with white by `1 - coverage` (the uncovered part of a blended
/// surface passes untouched), each channel clamped to [0, 1]; non-finite inputs count as 1.
pub fn transmission_tint(m: &MaterialParams) -> Vec3 {
    let unit = |x: f32| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            1.0
        }
    };
    let base = Vec3::new(
        unit(m.base_color.x),
        unit(m.base_color.y),
        unit(m.base_color.z),
    );
    let covered = base * unit(m.specular_transmission);
    let c = unit(m.coverage);
    Vec3::ONE * (1.0 - c) + covered * c
}

/// A light that casts caustics, in the light's own units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TraceLight {
    /// Parallel light travelling along `direction`; `illuminance` is lux on a surface
    /// perpendicular to it (Bevy `DirectionalLight::illuminance` times the linear colour).
    Directional {
        /// Unit travel direction.
        direction: Vec3,
        /// Perpendicular illuminance per channel, lux.
        illuminance: Vec3,
    },
    /// Isotropic point light; `flux` is Bevy's `PointLight::intensity` (lumens) times colour.
    Point {
        /// World position.
        position: Vec3,
        /// Total luminous flux per channel, lm.
        flux: Vec3,
    },
    /// Spot light with Bevy's falloff: `flux / 4π` candela on the axis.
    Spot {
        /// World position.
        position: Vec3,
        /// Unit axis direction.
        direction: Vec3,
        /// `intensity` (lm) times colour, as Bevy defines it (no cone normalisation).
        flux: Vec3,
        /// Inner cone angle, radians.
        inner_angle: f32,
        /// Outer cone angle, radians.
        outer_angle: f32,
    },
}

/// Projection of the camera the caustics buffer is rendered for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraProjection {
    /// Perspective with vertical field of view in radians.
    Perspective {
        /// Vertical field of view, radians.
        fov_y: f32,
    },
    /// Orthographic with the view's height in metres.
    Orthographic {
        /// Visible height, metres.
        height: f32,
    },
}

/// The camera a caustics buffer belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceCamera {
    /// Camera to world (Bevy convention: looks along local -Z, +Y up).
    pub world_from_view: Affine3A,
    /// Projection.
    pub projection: CameraProjection,
    /// Target width in pixels.
    pub width: u32,
    /// Target height in pixels.
    pub height: u32,
}

impl TraceCamera {
    /// World position of the eye.
    pub fn position(&self) -> Vec3 {
        self.world_from_view.translation.into()
    }
}
