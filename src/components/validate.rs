//! Validation of the user-facing components: invalid values are clamped in place, with one
//! `warn!` per entity and field (the component is only re-checked when it changes, and a
//! clamped value is valid).

use bevy::prelude::*;

use super::{AapsSettings, CausticLight, CausticMaterial, CausticsVolume};

/// Every invalid-input warning the plugin has logged, in order (the same text as the log
/// line). Lets tools and tests see exactly what was clamped.
#[derive(Resource, Default, Debug, Clone)]
pub struct CausticsWarnings {
    /// The messages.
    pub messages: Vec<String>,
}

impl CausticsWarnings {
    /// Log `detail` about `component.field` of `entity` and record it.
    pub fn report(
        &mut self,
        entity: Entity,
        name: Option<&Name>,
        component: &str,
        field: &str,
        detail: &str,
    ) {
        let who = match name {
            Some(n) => format!("entity {entity} ({n})"),
            None => format!("entity {entity}"),
        };
        let msg = format!("bevy_caustics: {component}.{field} on {who}: {detail}");
        warn!("{msg}");
        self.messages.push(msg);
    }
}

/// A fixed field: (field name, what was wrong and what it became).
pub type Fix = (&'static str, String);

/// Clamp a volume's fields into range; returns what was fixed.
pub fn sanitize_volume(v: &mut CausticsVolume) -> Vec<Fix> {
    let mut fixes = Vec::new();
    let size = Vec3::new(fix_size(v.size.x), fix_size(v.size.y), fix_size(v.size.z));
    if size != v.size {
        fixes.push((
            "size",
            format!(
                "{} has a zero, negative or non-finite extent; clamped to {size}",
                v.size
            ),
        ));
        v.size = size;
    }
    let slabs = v.slabs.clamp(1, 64);
    if slabs != v.slabs {
        fixes.push((
            "slabs",
            format!("{} is outside [1, 64]; clamped to {slabs}", v.slabs),
        ));
        v.slabs = slabs;
    }
    let photons = v.photons.clamp(0, 1 << 24);
    if photons != v.photons {
        fixes.push((
            "photons",
            format!(
                "{} is outside [0, 16777216]; clamped to {photons}",
                v.photons
            ),
        ));
        v.photons = photons;
    }
    let res = v.projector_resolution.clamp(16, 4096);
    if res != v.projector_resolution {
        fixes.push((
            "projector_resolution",
            format!(
                "{} is outside [16, 4096]; clamped to {res}",
                v.projector_resolution
            ),
        ));
        v.projector_resolution = res;
    }
    let g = v.gbuffer_resolution.clamp(16, 4096);
    if g != v.gbuffer_resolution {
        fixes.push((
            "gbuffer_resolution",
            format!(
                "{} is outside [16, 4096]; clamped to {g}",
                v.gbuffer_resolution
            ),
        ));
        v.gbuffer_resolution = g;
    }
    let t = v.tile_size.clamp(1, 64);
    if t != v.tile_size {
        fixes.push((
            "tile_size",
            format!("{} is outside [1, 64]; clamped to {t}", v.tile_size),
        ));
        v.tile_size = t;
    }
    let o = if v.splat_overlap.is_finite() {
        v.splat_overlap.clamp(0.25, 64.0)
    } else {
        4.0
    };
    if o != v.splat_overlap {
        fixes.push((
            "splat_overlap",
            format!("{} is outside [0.25, 64]; clamped to {o}", v.splat_overlap),
        ));
        v.splat_overlap = o;
    }
    let b = v.blur_radius.min(8);
    if b != v.blur_radius {
        fixes.push((
            "blur_radius",
            format!("{} is above 8; clamped to {b}", v.blur_radius),
        ));
        v.blur_radius = b;
    }
    let l = if v.lod_distance.is_finite() {
        v.lod_distance.max(0.0)
    } else {
        0.0
    };
    if l != v.lod_distance {
        fixes.push((
            "lod_distance",
            format!(
                "{} is negative or non-finite; clamped to {l}",
                v.lod_distance
            ),
        ));
        v.lod_distance = l;
    }
    fixes
}

fn fix_size(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 {
        x.max(1e-3)
    } else {
        1e-3
    }
}

/// Clamp a light's fields into range; returns what was fixed.
pub fn sanitize_light(l: &mut CausticLight) -> Vec<Fix> {
    let mut fixes = Vec::new();
    let s = if l.intensity_scale.is_finite() {
        l.intensity_scale.clamp(0.0, 1000.0)
    } else {
        0.0
    };
    if s != l.intensity_scale {
        fixes.push((
            "intensity_scale",
            format!("{} is outside [0, 1000]; clamped to {s}", l.intensity_scale),
        ));
        l.intensity_scale = s;
    }
    fixes
}

/// Clamp a material override into range; returns what was fixed.
pub fn sanitize_material(m: &mut CausticMaterial) -> Vec<Fix> {
    let mut fixes = Vec::new();
    if let CausticMaterial::Dielectric {
        ior,
        attenuation_distance,
        ..
    } = m
    {
        let i = if ior.is_finite() {
            ior.clamp(1.0, 4.0)
        } else {
            1.0
        };
        if i != *ior {
            fixes.push(("ior", format!("{ior} is outside [1, 4]; clamped to {i}")));
            *ior = i;
        }
        let d = if attenuation_distance.is_nan() || *attenuation_distance <= 0.0 {
            f32::INFINITY
        } else {
            *attenuation_distance
        };
        if d != *attenuation_distance {
            fixes.push((
                "attenuation_distance",
                format!("{attenuation_distance} is not > 0; set to infinity (clear)"),
            ));
            *attenuation_distance = d;
        }
    }
    fixes
}

/// Clamp AAPS settings into range (see [`AapsSettings::sanitized`]); returns what was fixed,
/// one entry per field that changed.
pub fn sanitize_aaps(a: &mut AapsSettings) -> Vec<Fix> {
    let fixed = a.sanitized();
    let mut fixes = Vec::new();
    macro_rules! check {
        ($($f:ident),*) => {$(
            if fixed.$f != a.$f {
                fixes.push((
                    stringify!($f),
                    format!("{:?} is out of range; clamped to {:?}", a.$f, fixed.$f),
                ));
            }
        )*};
    }
    check!(
        atlas_resolution,
        target_area,
        variance_gain,
        temporal_weight,
        min_density,
        max_density,
        cull_solid_angle,
        msaa_threshold,
        splat_scale,
        max_anisotropy,
        max_bounces,
        splat_capacity
    );
    *a = fixed;
    fixes
}

/// The query a validation system runs over.
type Checked<'w, 's, C> =
    Query<'w, 's, (Entity, &'static mut C, Option<&'static Name>), Changed<C>>;

fn validate<C: Component<Mutability = bevy::ecs::component::Mutable> + Clone>(
    name: &'static str,
    sanitize: fn(&mut C) -> Vec<Fix>,
) -> impl FnMut(Checked<C>, ResMut<CausticsWarnings>) {
    move |mut q, mut warnings| {
        for (entity, mut c, n) in &mut q {
            let mut fixed = c.clone();
            let fixes = sanitize(&mut fixed);
            if fixes.is_empty() {
                continue;
            }
            for (field, detail) in fixes {
                warnings.report(entity, n, name, field, &detail);
            }
            *c = fixed;
        }
    }
}

/// Registers the validation systems (in `PostUpdate`, before the scene is gathered).
pub(crate) fn plugin(app: &mut App) {
    app.init_resource::<CausticsWarnings>().add_systems(
        PostUpdate,
        (
            validate::<CausticsVolume>("CausticsVolume", sanitize_volume),
            validate::<CausticLight>("CausticLight", sanitize_light),
            validate::<CausticMaterial>("CausticMaterial", sanitize_material),
            validate::<AapsSettings>("AapsSettings", sanitize_aaps),
        )
            .in_set(crate::CausticsSystems::Validate),
    );
}
