//! The stage (`RenderJob::stage`, the command line's `--stage`): most glTF models come
//! without a light, a camera or a floor. The stage measures the model's world bounds once it
//! has spawned and adds a sun shining down across it, a diffuse floor just below it and a
//! camera framing it, all sized from the bounds, so a model in millimetres and one in
//! kilometres both show their caustic.

use bevy::camera::PerspectiveProjection;
use bevy::light::DirectionalLight;
use bevy::mesh::{Mesh3d, VertexAttributeValues};
use bevy::prelude::*;

/// The sun's illuminance, lux (a clear day, as the test scenes' `scenes::SUN_LUX`).
pub const STAGE_SUN_LUX: f32 = 10_000.0;
/// The exposure the stage's camera takes when the job sets none: a sunlit scene.
pub const STAGE_EV100: f32 = 13.0;
/// The stage camera's vertical field of view, radians (45 degrees).
pub const STAGE_FOV_Y: f32 = std::f32::consts::FRAC_PI_4;
/// The floor's albedo (a light grey, as the test scenes' floors).
pub const STAGE_FLOOR_ALBEDO: f32 = 0.8;

/// The direction the sun's light travels: down, away from the camera and a little to the left,
/// so a model's caustic falls on the floor (and on a backdrop behind it) in front of its shadow
/// rather than under the model. glTF's front is +Z, where the camera stands.
pub fn stage_sun_direction() -> Vec3 {
    Vec3::new(-0.35, -1.0, -0.45).normalize()
}

/// The camera's direction from the model's centre: in front (+Z) and 30 degrees up.
fn camera_direction() -> Vec3 {
    let up = 30f32.to_radians();
    Vec3::new(0.0, up.sin(), up.cos())
}

/// Where the stage puts things, from the model's world bounds.
#[derive(Resource, Clone, Debug)]
pub struct StageLayout {
    /// The model's world bounds (min, max), metres.
    pub bounds: (Vec3, Vec3),
    /// The camera's transform, looking at the bounds' centre.
    pub camera: Transform,
    /// The camera's projection (its aspect ratio is set from the job's target).
    pub projection: PerspectiveProjection,
    /// The floor's centre (just below the bounds) and half its side.
    pub floor: (Vec3, f32),
}

impl StageLayout {
    /// The layout around `bounds` for a target of `aspect` (width / height): the camera at a
    /// distance where the bounding sphere fits the narrower field of view with 10 % margin;
    /// the floor four bounding radii wide, a thousandth of the radius below the lowest point
    /// (below the model's own bottom faces, so the two never fight for depth).
    pub fn new(bounds: (Vec3, Vec3), aspect: f32) -> Self {
        let (min, max) = bounds;
        let centre = (min + max) * 0.5;
        // A flat or point-like model still gets a finite stage.
        let radius = ((max - min).length() * 0.5).max(1e-4);
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let half_fov = 0.5 * STAGE_FOV_Y;
        // The narrower of the vertical and horizontal half-angles.
        let half = half_fov.min((half_fov.tan() * aspect).atan());
        let distance = 1.1 * radius / half.sin();
        let eye = centre + camera_direction() * distance;
        let camera = Transform::from_translation(eye).looking_at(centre, Vec3::Y);
        let projection = PerspectiveProjection {
            fov: STAGE_FOV_Y,
            aspect_ratio: aspect,
            near: (distance - radius).max(distance * 1e-3) * 0.5,
            far: (distance + radius * 4.0) * 2.0,
            ..default()
        };
        let floor = (
            Vec3::new(centre.x, min.y - radius * 1e-3, centre.z),
            2.0 * radius,
        );
        Self {
            bounds,
            camera,
            projection,
            floor,
        }
    }
}

/// The world bounds of every mesh in the world (its vertices through its `GlobalTransform`),
/// or None when there is no mesh with positions.
pub fn world_bounds<'a>(
    meshes: impl Iterator<Item = (&'a Mesh3d, &'a GlobalTransform)>,
    assets: &Assets<Mesh>,
) -> Option<(Vec3, Vec3)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for (mesh, gt) in meshes {
        let Some(Ok(VertexAttributeValues::Float32x3(p))) = assets
            .get(&mesh.0)
            .map(|m| m.try_attribute(Mesh::ATTRIBUTE_POSITION))
        else {
            continue;
        };
        let affine = gt.affine();
        for v in p {
            let w = affine.transform_point3(Vec3::from_array(*v));
            if w.is_finite() {
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The stage's own entities (sun, floor), so the bounds of a second measure leave them out.
#[derive(Component)]
pub struct StagePart;

/// Measure the spawned model and add the stage: a sun ([`STAGE_SUN_LUX`], shadows on), the
/// floor and the [`StageLayout`] resource the job's camera takes its view from. Returns an
/// error line when the model has no mesh to frame. The glTF viewer stages a model that brings
/// no light of its own the same way.
pub fn build_stage(
    commands: &mut Commands,
    meshes: &Query<(&Mesh3d, &GlobalTransform), Without<StagePart>>,
    mesh_assets: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    aspect: f32,
) -> Result<StageLayout, String> {
    let bounds = world_bounds(meshes.iter(), mesh_assets)
        .ok_or_else(|| "the model has no mesh to put on the stage".to_string())?;
    let layout = StageLayout::new(bounds, aspect);
    let (centre, half) = layout.floor;
    commands.spawn((
        StagePart,
        Name::new("stage floor"),
        Mesh3d(mesh_assets.add(Plane3d::new(Vec3::Y, Vec2::splat(half)))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::linear_rgb(
                STAGE_FLOOR_ALBEDO,
                STAGE_FLOOR_ALBEDO,
                STAGE_FLOOR_ALBEDO,
            ),
            perceptual_roughness: 1.0,
            reflectance: 0.0,
            ..default()
        })),
        Transform::from_translation(centre),
    ));
    let target = layout.floor.0;
    commands.spawn((
        StagePart,
        Name::new("stage sun"),
        DirectionalLight {
            illuminance: STAGE_SUN_LUX,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_translation(target - stage_sun_direction())
            .looking_to(stage_sun_direction(), Vec3::Y),
    ));
    commands.insert_resource(layout.clone());
    Ok(layout)
}

/// Stage `Spawned(2)` of a job with `stage`: measure the model and build the stage (once);
/// a model with no mesh fails the job.
pub(super) fn stage(
    mut commands: Commands,
    (job, phase, shared): (
        Res<super::job::Job>,
        Res<super::job::Phase>,
        Res<super::job::Shared>,
    ),
    built: Option<Res<StageLayout>>,
    meshes: Query<(&Mesh3d, &GlobalTransform), Without<StagePart>>,
    (mut mesh_assets, mut materials): (ResMut<Assets<Mesh>>, ResMut<Assets<StandardMaterial>>),
    mut exit: MessageWriter<AppExit>,
) {
    if !job.0.stage || built.is_some() || *phase != super::job::Phase::Spawned(2) {
        return;
    }
    let aspect = job.0.width as f32 / job.0.height.max(1) as f32;
    if let Err(e) = build_stage(
        &mut commands,
        &meshes,
        &mut mesh_assets,
        &mut materials,
        aspect,
    ) {
        if let Ok(mut o) = shared.0.lock() {
            o.error
                .get_or_insert(format!("{}: {e}", job.0.scene.display()));
        }
        exit.write(AppExit::error());
    }
}

/// The job's camera exposure: its EV100, else the stage's sunlit one on a stage, else Bevy's
/// default.
pub(super) fn job_exposure(job: &super::RenderJob) -> bevy::camera::Exposure {
    let stage = job.stage.then_some(STAGE_EV100);
    job.ev100
        .or(stage)
        .map_or_else(bevy::camera::Exposure::default, |ev100| {
            bevy::camera::Exposure { ev100 }
        })
}
