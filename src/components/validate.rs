//! Validation of the user-facing components: invalid values are clamped in place, with one
//! `warn!` per entity and field (the component is only re-checked when it changes, and a
//! clamped value is valid).

use bevy::prelude::*;

use super::{
    AapsSettings, CausticLight, CausticMaterial, Caustics, CausticsQuality, CausticsTechnique,
    CausticsVolume, ImageSpaceSettings, PhotonMapSettings,
};
use crate::limits::CausticsLimits;

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

/// Clamp a volume's fields into range (the sizes within `limits`); returns what was fixed.
pub fn sanitize_volume(v: &mut CausticsVolume, limits: &CausticsLimits) -> Vec<Fix> {
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
    let max_slabs = limits.max_volume_slabs;
    let slabs = v.slabs.clamp(1, max_slabs);
    if slabs != v.slabs {
        fixes.push((
            "slabs",
            format!(
                "{} is outside [1, {max_slabs}]; clamped to {slabs}",
                v.slabs
            ),
        ));
        v.slabs = slabs;
    }
    let max_photons = limits.volume_photons(v.slabs) as i32;
    let photons = v.photons.clamp(0, max_photons);
    if photons != v.photons {
        fixes.push((
            "photons",
            format!(
                "{} is outside [0, {max_photons}] (this GPU at {} slabs); clamped to {photons}",
                v.photons, v.slabs
            ),
        ));
        v.photons = photons;
    }
    let max_res = limits.volume_projector_side(u32::MAX);
    let res = v.projector_resolution.clamp(16, max_res);
    if res != v.projector_resolution {
        fixes.push((
            "projector_resolution",
            format!(
                "{} is outside [16, {max_res}] (this GPU); clamped to {res}",
                v.projector_resolution
            ),
        ));
        v.projector_resolution = res;
    }
    let max_g = limits.volume_gbuffer_side(u32::MAX, v.slabs);
    let g = v.gbuffer_resolution.clamp(16, max_g);
    if g != v.gbuffer_resolution {
        fixes.push((
            "gbuffer_resolution",
            format!(
                "{} is outside [16, {max_g}] (this GPU at {} slabs); clamped to {g}",
                v.gbuffer_resolution, v.slabs
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
    let k = v.density_photons.clamp(1, 65_536);
    if k != v.density_photons {
        fixes.push((
            "density_photons",
            format!(
                "{} is outside [1, 65536]; clamped to {k}",
                v.density_photons
            ),
        ));
        v.density_photons = k;
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
            f32::MAX
        } else {
            *attenuation_distance
        };
        if d != *attenuation_distance {
            fixes.push((
                "attenuation_distance",
                format!("{attenuation_distance} is not > 0; set to f32::MAX (clear)"),
            ));
            *attenuation_distance = d;
        }
    }
    fixes
}

/// One [`Fix`] per listed field where `fixed` differs from `old`.
macro_rules! field_fixes {
    ($old:expr, $fixed:expr, $($f:ident),* $(,)?) => {{
        let mut fixes: Vec<Fix> = Vec::new();
        $(
            if $fixed.$f != $old.$f {
                fixes.push((
                    stringify!($f),
                    format!("{:?} is out of range; clamped to {:?}", $old.$f, $fixed.$f),
                ));
            }
        )*
        fixes
    }};
}

/// Clamp AAPS settings into range (see [`AapsSettings::sanitized_for`]); returns what was
/// fixed, one entry per field that changed.
pub fn sanitize_aaps(a: &mut AapsSettings, limits: &CausticsLimits) -> Vec<Fix> {
    let fixed = a.sanitized_for(limits);
    let fixes = field_fixes!(
        a,
        fixed,
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
        splat_capacity,
        budget_floor_share,
        point_splat_area,
        bounce_budget,
        history_frames,
        history_clamp
    );
    *a = fixed;
    fixes
}

/// Clamp image-space settings into range (see [`ImageSpaceSettings::sanitized_for`]);
/// returns what was fixed, one entry per field that changed.
pub fn sanitize_image_space(a: &mut ImageSpaceSettings, limits: &CausticsLimits) -> Vec<Fix> {
    let fixed = a.sanitized_for(limits);
    let fixes = field_fixes!(
        a,
        fixed,
        rsm_resolution,
        luminance_cutoff,
        stride,
        thickness,
        alpha_color,
        alpha_moments,
        history_cap,
        atrous_iterations,
        sigma_depth,
        sigma_normal,
        sigma_luminance
    );
    *a = fixed;
    fixes
}

/// Clamp photon-map settings into range (see [`PhotonMapSettings::sanitized`]); returns what
/// was fixed, one entry per field that changed.
pub fn sanitize_photon_map(a: &mut PhotonMapSettings, _limits: &CausticsLimits) -> Vec<Fix> {
    let fixed = a.sanitized();
    let fixes = field_fixes!(
        a,
        fixed,
        radius,
        max_bounces,
        max_grid_cells,
        alpha,
        max_frames,
        normal_threshold,
        bounce_budget,
        gather_photons
    );
    *a = fixed;
    fixes
}

/// Replace the `Reference` technique by AAPS when the `tools` feature (which holds the CPU
/// reference) is off, and clamp a camera's photon count (a `CausticsQuality::Custom` above what its technique
/// allows on this device, [`CausticsLimits::max_photons`]); returns what was fixed.
pub fn sanitize_caustics(c: &mut Caustics, limits: &CausticsLimits) -> Vec<Fix> {
    let mut fixes = Vec::new();
    if cfg!(not(feature = "tools")) && c.technique == CausticsTechnique::Reference {
        fixes.push((
            "technique",
            "Reference (the CPU ground truth) needs bevy_caustics's `tools` feature; using Aaps"
                .to_string(),
        ));
        c.technique = CausticsTechnique::Aaps;
    }
    let max = limits.max_photons(c.technique);
    if let CausticsQuality::Custom { photons } = &mut c.quality
        && *photons > max
    {
        fixes.push((
            "quality",
            format!(
                "Custom {{ photons: {photons} }} is above the {} technique's maximum on this GPU, {max}; clamped to {max}",
                c.technique.name()
            ),
        ));
        *photons = max;
    }
    fixes
}

/// The query a validation system runs over.
type Checked<'w, 's, C> =
    Query<'w, 's, (Entity, &'static mut C, Option<&'static Name>), Changed<C>>;

fn validate<C: Component<Mutability = bevy::ecs::component::Mutable> + Clone>(
    name: &'static str,
    sanitize: fn(&mut C, &CausticsLimits) -> Vec<Fix>,
) -> impl FnMut(Checked<C>, Res<CausticsLimits>, ResMut<CausticsWarnings>) {
    move |mut q, limits, mut warnings| {
        for (entity, mut c, n) in &mut q {
            let mut fixed = c.clone();
            let fixes = sanitize(&mut fixed, &limits);
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
    app.init_resource::<CausticsWarnings>()
        .init_resource::<CausticsLimits>()
        .add_systems(
            PostUpdate,
            (
                validate::<Caustics>("Caustics", sanitize_caustics),
                validate::<CausticsVolume>("CausticsVolume", sanitize_volume),
                validate::<CausticLight>("CausticLight", |l, _| sanitize_light(l)),
                validate::<CausticMaterial>("CausticMaterial", |m, _| sanitize_material(m)),
                validate::<AapsSettings>("AapsSettings", sanitize_aaps),
                validate::<ImageSpaceSettings>("ImageSpaceSettings", sanitize_image_space),
                validate::<PhotonMapSettings>("PhotonMapSettings", sanitize_photon_map),
            )
                .in_set(crate::CausticsSystems::Validate),
        );
}
