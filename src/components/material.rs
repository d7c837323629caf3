use bevy::prelude::*;

/// Overrides how a mesh takes part in caustics. Without it the plugin derives the behaviour
/// from the mesh's `StandardMaterial`: `specular_transmission > 0` is a dielectric (its `ior`,
/// `thickness`, `attenuation_*`), `metallic >= 0.9` with `perceptual_roughness <= 0.2` is a
/// mirror with reflectance `base_color`, anything else is a diffuse receiver.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
pub enum CausticMaterial {
    /// Glass, water, gems: Fresnel reflection and Snell refraction.
    Dielectric {
        /// Index of refraction. Range [1, 4] (1 gives no caustic); values below 1 or
        /// non-finite are clamped to 1 with a warning, above 4 to 4.
        #[reflect(@1.0_f32..=4.0_f32)]
        ior: f32,
        /// Colour left after `attenuation_distance` metres inside. Default white.
        attenuation_color: Color,
        /// Metres; `f32::MAX` (default: JSON, as Bevy Remote Protocol speaks it, has no
        /// infinity) or anything from 3e38 up, `f32::INFINITY` included, for a clear medium.
        /// Must be > 0.
        #[reflect(@1.0e-4_f32..=f32::MAX)]
        attenuation_distance: f32,
        /// A thin sheet (light passes without bending), like glTF's `thickness = 0`.
        thin: bool,
    },
    /// A polished conductor.
    Mirror {
        /// Normal-incidence reflectance (Schlick F0) per channel. Default 0.95 grey.
        reflectance: Color,
    },
    /// Never a caster: a diffuse receiver with this linear albedo.
    Receiver {
        /// Diffuse albedo.
        albedo: Color,
    },
}

/// Clear glass of IOR 1.5 (what a reflection-driven editor adds).
impl Default for CausticMaterial {
    fn default() -> Self {
        Self::glass(1.5)
    }
}

impl CausticMaterial {
    /// Clear glass of the given IOR.
    pub fn glass(ior: f32) -> Self {
        Self::Dielectric {
            ior,
            attenuation_color: Color::WHITE,
            attenuation_distance: f32::MAX,
            thin: false,
        }
    }
}
