//! Receivers the composite cannot reach: those rendered forward.
//!
//! The composite adds caustic light where the deferred G-buffer has a diffuse albedo. A
//! receiver rendered forward (its material's `opaque_render_method`, or `Auto` with a forward
//! [`DefaultOpaqueRendererMethod`], or a blended `alpha_mode`) is not in the G-buffer, so its
//! caustic is lost; every such receiver a caustics camera sees is named once in a `warn!`.

use bevy::material::OpaqueRendererMethod;
use bevy::pbr::{DefaultOpaqueRendererMethod, Material};
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy::reflect::tuple_struct::TupleStruct;

use super::collect::material_params;
use super::model::classify_material;
use crate::components::validate::CausticsWarnings;
use crate::{CausticMaterial, Caustics};

/// The app-wide default is forward (Bevy's own default).
pub fn is_forward_default(method: &DefaultOpaqueRendererMethod) -> bool {
    method
        .field(0)
        .and_then(|f| f.try_downcast_ref::<OpaqueRendererMethod>())
        .is_some_and(|m| *m == OpaqueRendererMethod::Forward)
}

/// Whether a mesh with `material` is drawn by the forward pass (not into the G-buffer) when
/// the app's default opaque method is forward (`default_forward`).
pub fn renders_forward(material: &StandardMaterial, default_forward: bool) -> bool {
    let blended = !matches!(material.alpha_mode, AlphaMode::Opaque | AlphaMode::Mask(_));
    blended
        || match material.opaque_render_method() {
            OpaqueRendererMethod::Forward => true,
            OpaqueRendererMethod::Deferred => false,
            OpaqueRendererMethod::Auto => default_forward,
        }
}

/// The receivers (diffuse surfaces, not casters) that a caustics camera sees and that are
/// rendered forward: one warning each, naming the entity.
#[allow(clippy::type_complexity)]
pub(crate) fn warn_forward_receivers(
    cameras: Query<&Camera, With<Caustics>>,
    meshes: Query<(
        Entity,
        &MeshMaterial3d<StandardMaterial>,
        Option<&CausticMaterial>,
        &ViewVisibility,
        Option<&Name>,
    )>,
    materials: Res<Assets<StandardMaterial>>,
    default_method: Option<Res<DefaultOpaqueRendererMethod>>,
    mut warned: Local<HashSet<Entity>>,
    mut warnings: ResMut<CausticsWarnings>,
) {
    if !cameras.iter().any(|c| c.is_active) {
        return;
    }
    let default_forward = default_method.is_none_or(|m| is_forward_default(&m));
    for (entity, handle, over, visibility, name) in &meshes {
        if !visibility.get() || warned.contains(&entity) {
            continue;
        }
        let Some(material) = materials.get(&handle.0) else {
            continue;
        };
        let receiver = match over {
            Some(CausticMaterial::Receiver { .. }) => true,
            Some(_) => false,
            None => !classify_material(&material_params(material)).is_specular(),
        };
        if receiver && renders_forward(material, default_forward) {
            warned.insert(entity);
            warnings.report(
                entity,
                name,
                "StandardMaterial",
                "opaque_render_method",
                "this receiver is rendered forward (its material's opaque_render_method or \
                 alpha_mode, or DefaultOpaqueRendererMethod::forward()), so it is not in the \
                 deferred G-buffer and gets no caustic; render it deferred",
            );
        }
    }
}
