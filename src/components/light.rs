use bevy::light::{DirectionalLight, PointLight, SpotLight};
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

/// A system that makes every directional, point and spot light without a [`CausticLight`] a
/// caustic light, with shadow maps on: the shadow of a caster removes the light it redirects
/// from direct lighting, and the caustic adds it back where it lands, so the frame does not
/// count that light twice. For scenes loaded whole (a glTF viewer, the headless renderer):
/// `app.add_systems(Update, mark_every_light)`.
#[allow(clippy::type_complexity)]
pub fn mark_every_light(
    mut commands: Commands,
    mut lights: Query<
        (
            Entity,
            Option<&mut DirectionalLight>,
            Option<&mut PointLight>,
            Option<&mut SpotLight>,
        ),
        (
            Or<(With<DirectionalLight>, With<PointLight>, With<SpotLight>)>,
            Without<CausticLight>,
        ),
    >,
) {
    for (e, d, p, s) in &mut lights {
        if let Some(mut d) = d {
            d.shadow_maps_enabled = true;
        }
        if let Some(mut p) = p {
            p.shadow_maps_enabled = true;
        }
        if let Some(mut s) = s {
            s.shadow_maps_enabled = true;
        }
        commands.entity(e).insert(CausticLight::default());
    }
}
