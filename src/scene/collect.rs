//! Gathers casters, receivers and caustic lights from the ECS into a [`CausticsScene`].
//!
//! Runs in `PostUpdate` after transform propagation. Work is done only on change: a BLAS is
//! built once per mesh asset (and again only when that asset is modified), the TLAS is rebuilt
//! when an instance, material or light changed. With no [`CausticLight`] in the world nothing
//! is gathered at all.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use bevy::asset::AssetEvent;
use bevy::light::{DirectionalLight, PointLight, SpotLight};
use bevy::mesh::{Indices, Mesh, Mesh3d, PrimitiveTopology, VertexAttributeValues};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::prelude::*;
use glam::Vec3 as GVec3;

use super::change::{self, CausticReach};
use super::{
    Blas, Instance, MaterialParams, MeshGeometry, Surface, Tlas, TraceLight, classify_material,
};
use crate::components::validate::CausticsWarnings;
use crate::components::{CausticLight, CausticMaterial};

/// The gathered scene, rebuilt on change. Shared with the techniques through `Arc`s.
#[derive(Resource, Default, Clone)]
pub struct CausticsScene {
    /// Instances and TLAS.
    pub tlas: Arc<Tlas>,
    /// Caustic lights with their entity.
    pub lights: Vec<(Entity, TraceLight)>,
    /// Incremented each time the scene changes.
    pub generation: u64,
    /// Incremented when a change can change a caustic (`scene::change`): histories restart
    /// on this one, not on [`Self::generation`].
    pub caustic_generation: u64,
    /// Incremented when a receiver moved, was added or removed (whether or not it is in the
    /// caustic light's reach): pixels whose visible surface moved restart.
    pub receiver_generation: u64,
    /// The lights at the last change of [`Self::caustic_generation`] (light drift is measured
    /// from them, so a slow turn restarts once it adds up).
    pub restart_lights: Vec<(Entity, TraceLight)>,
    /// Number of specular instances (casters).
    pub casters: usize,
    /// Number of diffuse instances (receivers).
    pub receivers: usize,
    /// BLAS builds since startup (the cache makes this count mesh assets, not frames).
    pub blas_builds: u64,
    /// Triangles skipped as degenerate, over all BLAS built.
    pub degenerate_triangles: u64,
    /// BLAS currently cached (one per live mesh asset in use).
    pub cached_blas: usize,
}

impl CausticsScene {
    /// True when something can cast a caustic: at least one light and one caster.
    pub fn is_active(&self) -> bool {
        !self.lights.is_empty() && self.casters > 0
    }
}

#[derive(Default)]
struct BlasCache(HashMap<AssetId<Mesh>, Arc<Blas>>);

/// Plain-Rust geometry of a Bevy mesh: triangle lists only, positions as `Float32x3`.
pub fn mesh_geometry(mesh: &Mesh) -> Option<MeshGeometry> {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return None;
    }
    let Ok(VertexAttributeValues::Float32x3(p)) = mesh.try_attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        return None;
    };
    let positions: Vec<GVec3> = p.iter().map(|v| GVec3::from_array(*v)).collect();
    let normals = match mesh.try_attribute(Mesh::ATTRIBUTE_NORMAL) {
        Ok(VertexAttributeValues::Float32x3(n)) if n.len() == positions.len() => {
            Some(n.iter().map(|v| GVec3::from_array(*v)).collect())
        }
        _ => None,
    };
    let flat: Vec<u32> = match mesh.try_indices() {
        Ok(Indices::U16(i)) => i.iter().map(|&x| x as u32).collect(),
        Ok(Indices::U32(i)) => i.clone(),
        Err(_) => (0..positions.len() as u32).collect(),
    };
    let indices = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Some(MeshGeometry {
        positions,
        normals,
        indices,
    })
}

/// The classifier's view of a `StandardMaterial`.
pub fn material_params(m: &StandardMaterial) -> MaterialParams {
    let c = m.base_color.to_linear();
    let a = m.attenuation_color.to_linear();
    MaterialParams {
        base_color: GVec3::new(c.red, c.green, c.blue),
        metallic: m.metallic,
        perceptual_roughness: m.perceptual_roughness,
        specular_transmission: m.specular_transmission,
        ior: m.ior,
        thickness: m.thickness,
        attenuation_distance: m.attenuation_distance,
        attenuation_color: GVec3::new(a.red, a.green, a.blue),
        coverage: match m.alpha_mode {
            AlphaMode::Blend | AlphaMode::Premultiplied | AlphaMode::Add | AlphaMode::Multiply => {
                m.base_color.alpha()
            }
            _ => 1.0,
        },
    }
}

/// The [`CausticMaterial`] the plugin derives from a `StandardMaterial` when the mesh has none
/// (the inspector shows it, and can insert it as an override to edit).
pub fn derived_caustic_material(m: &StandardMaterial) -> CausticMaterial {
    let color = |v: GVec3| Color::linear_rgb(v.x, v.y, v.z);
    match classify_material(&material_params(m)) {
        Surface::Dielectric {
            ior,
            attenuation_color,
            attenuation_distance,
            thin,
            ..
        } => CausticMaterial::Dielectric {
            ior,
            attenuation_color: color(attenuation_color),
            attenuation_distance,
            thin,
        },
        Surface::Conductor { f0 } => CausticMaterial::Mirror {
            reflectance: color(f0),
        },
        Surface::Diffuse { albedo } => CausticMaterial::Receiver {
            albedo: color(albedo),
        },
    }
}

fn override_surface(m: &CausticMaterial) -> Surface {
    let rgb = |c: &Color| {
        let l = c.to_linear();
        GVec3::new(l.red, l.green, l.blue).clamp(GVec3::ZERO, GVec3::ONE)
    };
    match m {
        CausticMaterial::Dielectric {
            ior,
            attenuation_color,
            attenuation_distance,
            thin,
        } => Surface::Dielectric {
            ior: if ior.is_finite() {
                ior.clamp(1.0, 4.0)
            } else {
                1.0
            },
            attenuation_color: rgb(attenuation_color),
            attenuation_distance: *attenuation_distance,
            thin: *thin,
            // An override is clear glass: its colour is the attenuation's.
            tint: GVec3::ONE,
        },
        CausticMaterial::Mirror { reflectance } => Surface::Conductor {
            f0: rgb(reflectance),
        },
        CausticMaterial::Receiver { albedo } => Surface::Diffuse {
            albedo: rgb(albedo),
        },
    }
}

fn light_rgb(c: Color) -> GVec3 {
    let l = c.to_linear();
    GVec3::new(l.red, l.green, l.blue)
}

type MeshQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Mesh3d,
        Option<&'static MeshMaterial3d<StandardMaterial>>,
        Option<&'static CausticMaterial>,
        &'static GlobalTransform,
        Option<&'static InheritedVisibility>,
        Option<&'static Name>,
    ),
>;

type LightQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static CausticLight,
        &'static GlobalTransform,
        Option<&'static DirectionalLight>,
        Option<&'static PointLight>,
        Option<&'static SpotLight>,
    ),
>;

/// Change detection inputs of [`gather_scene`].
type Dirty<'w, 's> = (
    Query<
        'w,
        's,
        (),
        (
            // Meshes only: a camera that moves changes no caustic.
            With<Mesh3d>,
            Or<(
                Changed<Mesh3d>,
                Changed<MeshMaterial3d<StandardMaterial>>,
                Changed<CausticMaterial>,
                Changed<GlobalTransform>,
                Changed<InheritedVisibility>,
            )>,
        ),
    >,
    Query<
        'w,
        's,
        (),
        (
            With<CausticLight>,
            Or<(
                Changed<CausticLight>,
                Changed<DirectionalLight>,
                Changed<PointLight>,
                Changed<SpotLight>,
                // A light that moves or turns changes its caustics.
                Changed<GlobalTransform>,
            )>,
        ),
    >,
    RemovedComponents<'w, 's, Mesh3d>,
    RemovedComponents<'w, 's, CausticLight>,
    MessageReader<'w, 's, AssetEvent<Mesh>>,
    MessageReader<'w, 's, AssetEvent<StandardMaterial>>,
);

#[allow(clippy::too_many_arguments)]
fn gather_scene(
    mut scene: ResMut<CausticsScene>,
    mut cache: Local<BlasCache>,
    mut warned: Local<HashSet<Entity>>,
    mut reach: Local<Option<(u64, CausticReach)>>,
    mut warnings: ResMut<CausticsWarnings>,
    meshes_q: MeshQuery,
    lights_q: LightQuery,
    (
        dirty_meshes,
        dirty_lights,
        mut removed_meshes,
        mut removed_lights,
        mut mesh_events,
        mut mat_events,
    ): Dirty,
    meshes: Res<Assets<Mesh>>,
    materials: Res<Assets<StandardMaterial>>,
) {
    let mut dirty = false;
    for ev in mesh_events.read() {
        if let AssetEvent::Modified { id }
        | AssetEvent::Removed { id }
        | AssetEvent::Unused { id } = ev
        {
            cache.0.remove(id);
        }
        dirty = true;
    }
    dirty |= mat_events.read().count() > 0;
    dirty |= !dirty_meshes.is_empty() || !dirty_lights.is_empty();
    dirty |= removed_meshes.read().count() > 0 || removed_lights.read().count() > 0;
    if lights_q.is_empty() {
        // No caustic light: nothing to gather, nothing will run.
        if !scene.lights.is_empty() || scene.casters > 0 {
            let builds = (scene.blas_builds, scene.degenerate_triangles);
            *scene = CausticsScene {
                generation: scene.generation + 1,
                caustic_generation: scene.caustic_generation + 1,
                receiver_generation: scene.receiver_generation,
                blas_builds: builds.0,
                degenerate_triangles: builds.1,
                ..default()
            };
        }
        return;
    }
    if !dirty && scene.generation > 0 {
        return;
    }
    let mut instances = Vec::new();
    let (mut casters, mut receivers) = (0, 0);
    for (entity, mesh3d, std_mat, over, gt, vis, name) in &meshes_q {
        if vis.is_some_and(|v| !v.get()) {
            continue;
        }
        let surface = match (over, std_mat.and_then(|m| materials.get(&m.0))) {
            (Some(o), _) => override_surface(o),
            (None, Some(m)) => {
                let params = material_params(m);
                if m.specular_transmission > 0.0
                    && (m.ior.is_nan() || m.ior < 1.0)
                    && warned.insert(entity)
                {
                    warnings.report(
                        entity,
                        name,
                        "StandardMaterial",
                        "ior",
                        &format!(
                            "{} is below 1 for a transmissive material; clamped to 1",
                            m.ior
                        ),
                    );
                }
                classify_material(&params)
            }
            (None, None) => continue,
        };
        let id = mesh3d.0.id();
        let blas = if let Some(b) = cache.0.get(&id) {
            b.clone()
        } else {
            let Some(mesh) = meshes.get(id) else { continue };
            let Some(geo) = mesh_geometry(mesh) else {
                if warned.insert(entity) {
                    warnings.report(entity, name, "Mesh3d", "mesh", "not a triangle list with Float32x3 positions (or its CPU data was dropped); ignored for caustics");
                }
                continue;
            };
            let b = Arc::new(Blas::build(Arc::new(geo)));
            scene.blas_builds += 1;
            scene.degenerate_triangles += b.degenerate_triangles as u64;
            cache.0.insert(id, b.clone());
            b
        };
        if surface.is_specular() {
            casters += 1;
        } else {
            receivers += 1;
        }
        instances.push(Instance::new(blas, gt.affine(), surface, entity.to_bits()));
    }
    let mut lights = Vec::new();
    for (entity, cl, gt, dir, point, spot) in &lights_q {
        let s = cl.intensity_scale;
        let pos = gt.translation();
        let fwd = gt.forward().as_vec3();
        let l = if let Some(d) = dir {
            TraceLight::Directional {
                direction: fwd,
                illuminance: light_rgb(d.color) * d.illuminance * s,
            }
        } else if let Some(sp) = spot {
            TraceLight::Spot {
                position: pos,
                direction: fwd,
                flux: light_rgb(sp.color) * sp.intensity * s,
                inner_angle: sp.inner_angle,
                outer_angle: sp.outer_angle,
            }
        } else if let Some(p) = point {
            TraceLight::Point {
                position: pos,
                flux: light_rgb(p.color) * p.intensity * s,
            }
        } else {
            continue;
        };
        lights.push((entity, l));
    }
    // Guard (stiff suite: "adding and removing casters every frame for 1000 frames"): drop the
    // BLAS of meshes no instance uses any more (their assets may live on), so the cache is bounded.
    let used: HashSet<AssetId<Mesh>> = meshes_q.iter().map(|q| q.1.0.id()).collect();
    cache.0.retain(|id, _| used.contains(id));
    scene.cached_blas = cache.0.len();
    let old = std::mem::replace(&mut scene.tlas, Arc::new(Tlas::build(instances)));
    scene.lights = lights;
    scene.casters = casters;
    scene.receivers = receivers;
    scene.generation += 1;
    count_changes(&mut scene, &old, &mut reach);
}

/// Move [`CausticsScene::caustic_generation`] and [`CausticsScene::receiver_generation`] for
/// what changed from `old` (see `scene::change`). The caustic light's reach is traced with
/// the old TLAS the first time a receiver moves after a caustic restart, then kept.
fn count_changes(scene: &mut CausticsScene, old: &Tlas, reach: &mut Option<(u64, CausticReach)>) {
    let diff = change::changed_instances(old, &scene.tlas);
    let extent = scene
        .tlas
        .bounds_where(|_| true)
        .map_or(1.0, |(lo, hi)| (hi - lo).length());
    let mut caustic =
        diff.casters || change::lights_drifted(&scene.restart_lights, &scene.lights, extent);
    if !diff.receivers.is_empty() {
        scene.receiver_generation += 1;
        if !caustic {
            let g = scene.caustic_generation;
            if reach.as_ref().is_none_or(|(at, _)| *at != g) {
                *reach = Some((g, CausticReach::trace(old, &scene.restart_lights)));
            }
            let r = &reach.as_ref().unwrap().1;
            caustic = diff
                .receivers
                .iter()
                .any(|b| r.share_through(*b) >= change::REACH_SHARE);
        }
    }
    if caustic {
        scene.caustic_generation += 1;
        scene.restart_lights = scene.lights.clone();
    }
}

/// Registers [`CausticsScene`] and its gathering system.
pub struct ScenePlugin;

impl Plugin for ScenePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<CausticsScene>().add_systems(
            PostUpdate,
            (
                gather_scene
                    .in_set(crate::CausticsSystems::Gather)
                    .after(bevy::transform::TransformSystems::Propagate),
                super::forward::warn_forward_receivers
                    .after(bevy::camera::visibility::VisibilitySystems::CheckVisibility),
            ),
        );
    }
}
