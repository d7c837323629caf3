use bevy::prelude::*;

/// Marks a `DirectionalLight`, `PointLight` or `SpotLight` as a source of caustics.
///
/// Caustic irradiance is computed in the light's own units: lux for Bevy lights (a
/// directional light's `illuminance`, a point or spot light's `intensity` in lumens).
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default, Clone)]
pub struct CausticLight {
    /// Multiplier on the caustic light of this light source only. Default 1 (physically
    /// calibrated). Range [0, 1000]; negative or non-finite values are clamped to 0 with a
    /// warning. No cost.
    #[reflect(@0.0_f32..=1000.0_f32)]
    pub intensity_scale: f32,
}

impl Default for CausticLight {
    fn default() -> Self {
        Self {
            intensity_scale: 1.0,
        }
    }
}
