//! The showcase: a sunlit courtyard with a pool of animated water over a tiled floor, a glass
//! ball, a block of coloured (absorbing) glass, a mirror ring and a gem, with the sun moving
//! slowly. Caustics by AAPS (the default technique), the inspector open. A sky made at
//! start-up (no downloaded asset) lights the scene and is reflected by the water, the glass
//! and the ring; bloom and the AgX filmic tone map; the camera drifts round the courtyard
//! until the mouse takes it.
//!
//! `cargo run --release --example showcase` (without a display it writes showcase.png)

mod common;

use std::f32::consts::{FRAC_PI_2, PI};

use bevy::asset::RenderAssetUsages;
use bevy::camera::Exposure;
use bevy::core_pipeline::Skybox;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::GeneratedEnvironmentMapLight;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::post_process::bloom::Bloom;
use bevy::prelude::*;
use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureViewDescriptor, TextureViewDimension,
};
use bevy_caustics::CausticsInspectorPlugin;
use bevy_caustics::prelude::*;
use common::{Controls, DefaultPlugins, OrbitCamera};

fn main() -> AppExit {
    App::new()
        .add_plugins((DefaultPlugins, CausticsPlugin, CausticsInspectorPlugin))
        .add_plugins(Controls::new("the sun moves; the water waves"))
        .insert_resource(ClearColor(Color::srgb(0.45, 0.62, 0.85)))
        .add_systems(Startup, setup)
        .add_systems(Update, (move_sun, wave_water, turn_gem, drift_camera))
        .run()
}

/// The water's mesh, re-shaped every frame.
#[derive(Component)]
struct Water;

#[derive(Component)]
struct Sun;

#[derive(Component)]
struct Gem;

/// Water: a square height field, `N` quads a side.
const WATER_SIDE: f32 = 2.6;
const N: usize = 64;
const WATER_LEVEL: f32 = 0.45;

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
    let sky = images.add(sky_cubemap(64));
    commands.spawn((
        Camera3d::default(),
        Caustics::default(),
        // Over 0.05 sr (seen from the last bounce) a splat is dropped: on glass_sphere that is
        // 0.5 % of the caustic's energy, and it keeps a software rasteriser's fill rate in check.
        AapsSettings {
            drop_large_splats: true,
            ..default()
        },
        Msaa::Off,
        Exposure { ev100: 13.0 },
        Tonemapping::AgX,
        Bloom::NATURAL,
        Skybox {
            image: Some(sky.clone()),
            brightness: SKY_LUMINANCE,
            ..default()
        },
        GeneratedEnvironmentMapLight {
            environment_map: sky,
            intensity: AMBIENT_LUMINANCE,
            ..default()
        },
        OrbitCamera::looking_at(Vec3::new(2.4, 2.2, 4.3), Vec3::new(0.8, 0.2, -0.1)),
        Name::new("camera"),
    ));
    commands.spawn((
        Sun,
        DirectionalLight {
            illuminance: 10_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        CausticLight::default(),
        Transform::default(),
        Name::new("sun"),
    ));

    // Ground: pale tiles with grout, 12 m square; the pool's walls stand on it.
    let tiles = materials.add(StandardMaterial {
        base_color_texture: Some(images.add(tile_texture())),
        perceptual_roughness: 0.8,
        ..default()
    });
    commands.spawn((
        Mesh3d(meshes.add(tiled_plane(12.0, 24.0))),
        MeshMaterial3d(tiles),
        Name::new("tiled floor"),
    ));
    let stone = materials.add(Color::srgb(0.75, 0.72, 0.68));
    let wall = meshes.add(Cuboid::new(WATER_SIDE + 0.2, 0.55, 0.1));
    for (i, (x, z)) in [(0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (-1.0, 0.0)]
        .into_iter()
        .enumerate()
    {
        let at = Vec3::new(
            -1.6 + x * (WATER_SIDE / 2.0 + 0.05),
            0.275,
            z * (WATER_SIDE / 2.0 + 0.05),
        );
        commands.spawn((
            Mesh3d(wall.clone()),
            MeshMaterial3d(stone.clone()),
            Transform::from_translation(at).with_rotation(Quat::from_rotation_y(if i >= 2 {
                FRAC_PI_2
            } else {
                0.0
            })),
            Name::new("pool wall"),
        ));
    }
    // Water: IOR 1.33, slightly blue (KHR_materials_volume attenuation).
    commands.spawn((
        Water,
        Mesh3d(meshes.add(water_mesh(0.0))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.9, 0.97, 1.0),
            specular_transmission: 1.0,
            ior: 1.33,
            thickness: 0.5,
            attenuation_color: Color::srgb(0.8, 0.93, 1.0),
            attenuation_distance: 2.0,
            perceptual_roughness: 0.02,
            ..default()
        })),
        Transform::from_xyz(-1.6, WATER_LEVEL, 0.0),
        Name::new("water"),
    ));

    let glass = |materials: &mut Assets<StandardMaterial>, ior: f32, tint: Color, distance: f32| {
        materials.add(StandardMaterial {
            base_color: Color::WHITE,
            specular_transmission: 1.0,
            ior,
            thickness: 0.5,
            attenuation_color: tint,
            attenuation_distance: distance,
            perceptual_roughness: 0.02,
            ..default()
        })
    };
    // A glass ball, low enough that its focus lands on the floor: a ball of radius r and IOR
    // n focuses parallel light n r / (2 (n - 1)) from its centre (0.525 m here), and the sun
    // stands 50 degrees high, so the centre sits 0.525 sin 50 = 0.40 m above the floor.
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(BALL_RADIUS).mesh().uv(64, 32))),
        MeshMaterial3d(glass(&mut materials, 1.5, Color::WHITE, f32::INFINITY)),
        Transform::from_xyz(0.7, BALL_HEIGHT, -0.5),
        Name::new("glass ball"),
    ));
    // A block of amber glass: 15 cm of it keeps 40 % of the blue, 90 % of the red.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.7, 0.15, 0.7))),
        MeshMaterial3d(glass(
            &mut materials,
            1.5,
            Color::linear_rgb(0.9, 0.6, 0.2),
            0.15,
        )),
        Transform::from_xyz(2.0, 0.8, -1.0).with_rotation(Quat::from_rotation_z(0.25)),
        Name::new("amber glass block"),
    ));
    // A polished ring on the floor: its inside focuses a cardioid.
    commands.spawn((
        Mesh3d(meshes.add(Extrusion::new(Annulus::new(0.42, 0.45), 0.22))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.95, 0.9, 0.75),
            metallic: 1.0,
            perceptual_roughness: 0.05,
            ..default()
        })),
        Transform::from_xyz(2.5, 0.11, 1.2).with_rotation(Quat::from_rotation_x(-FRAC_PI_2)),
        Name::new("mirror ring"),
    ));
    // A gem (diamond, IOR 2.42), faceted, turning slowly.
    commands.spawn((
        Gem,
        Mesh3d(
            meshes.add(
                Sphere::new(0.25)
                    .mesh()
                    .ico(1)
                    .unwrap()
                    .with_duplicated_vertices()
                    .with_computed_flat_normals(),
            ),
        ),
        MeshMaterial3d(glass(&mut materials, 2.42, Color::WHITE, f32::INFINITY)),
        Transform::from_xyz(1.3, 0.8, 0.4).with_scale(Vec3::new(1.0, 0.6, 1.0)),
        Name::new("gem"),
    ));
}

/// The glass ball's radius, metres.
const BALL_RADIUS: f32 = 0.35;
/// The ball's centre above the floor: its paraxial focus, 1.5 r / (2 x 0.5) from the centre
/// along the sun's rays (50 degrees high), on the floor.
const BALL_HEIGHT: f32 = 1.5 * BALL_RADIUS * 0.766;
/// The sky's luminance at the zenith, cd/m² (a clear blue sky is a few thousand).
const SKY_LUMINANCE: f32 = 2500.0;
/// The environment light's luminance, cd/m²: lower than the sky seen, so the sky adds
/// about a fifth of the sun's 10 000 lux on the floor and the caustics keep their contrast.
const AMBIENT_LUMINANCE: f32 = 700.0;
/// The sun's elevation, radians.
const SUN_ELEVATION: f32 = 50.0 * PI / 180.0;

/// The sun circles slowly, 50° above the horizon.
fn move_sun(time: Res<Time>, mut sun: Query<&mut Transform, With<Sun>>) {
    // Starting behind the objects (seen from the camera), so shadows and caustics fall
    // towards the viewer.
    let a = -1.3 + time.elapsed_secs() * 0.05;
    let (elevation, azimuth) = (SUN_ELEVATION, a % (2.0 * PI));
    let towards_sun = Vec3::new(
        elevation.cos() * azimuth.cos(),
        elevation.sin(),
        elevation.cos() * azimuth.sin(),
    );
    for mut t in &mut sun {
        *t = Transform::from_translation(towards_sun * 5.0).looking_at(Vec3::ZERO, Vec3::Y);
    }
}

/// With nobody at the mouse for 3 s, the camera drifts round the courtyard, 0.05 rad/s.
fn drift_camera(
    time: Res<Time>,
    buttons: Res<ButtonInput<MouseButton>>,
    mut idle: Local<f32>,
    mut cameras: Query<&mut OrbitCamera>,
) {
    if buttons.get_pressed().next().is_some() {
        *idle = 0.0;
        return;
    }
    *idle += time.delta_secs();
    if *idle < 3.0 {
        return;
    }
    for mut c in &mut cameras {
        c.yaw += 0.05 * time.delta_secs();
    }
}

fn wave_water(
    time: Res<Time>,
    water: Query<&Mesh3d, With<Water>>,
    mut meshes: ResMut<Assets<Mesh>>,
) {
    for m in &water {
        if let Some(mut mesh) = meshes.get_mut(&m.0) {
            *mesh = water_mesh(time.elapsed_secs());
        }
    }
}

fn turn_gem(time: Res<Time>, mut gems: Query<&mut Transform, With<Gem>>) {
    for mut t in &mut gems {
        t.rotation = Quat::from_rotation_y(time.elapsed_secs() * 0.3);
    }
}

/// Two crossing swells: height and its gradient at (x, z), metres, at time `t`.
fn swell(x: f32, z: f32, t: f32) -> (f32, Vec2) {
    let (k1, k2, amp) = (Vec2::new(9.1, 5.7), Vec2::new(-6.3, 8.6), 0.02);
    let (p1, p2) = (k1.x * x + k1.y * z + 1.3 * t, k2.x * x + k2.y * z + 1.1 * t);
    (
        amp * (p1.sin() + p2.sin()),
        amp * (k1 * p1.cos() + k2 * p2.cos()),
    )
}

fn water_mesh(t: f32) -> Mesh {
    let n = N + 1;
    let mut positions = Vec::with_capacity(n * n);
    let mut normals = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let x = (i as f32 / N as f32 - 0.5) * WATER_SIDE;
            let z = (j as f32 / N as f32 - 0.5) * WATER_SIDE;
            let (h, g) = swell(x, z, t);
            positions.push([x, h, z]);
            normals.push(Vec3::new(-g.x, 1.0, -g.y).normalize().to_array());
        }
    }
    let mut indices = Vec::with_capacity(N * N * 6);
    for j in 0..N {
        for i in 0..N {
            let a = (j * n + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
            indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_POSITION,
        VertexAttributeValues::Float32x3(positions),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_indices(Indices::U32(indices))
}

/// A plane of side `size` whose UVs repeat `repeat` times.
fn tiled_plane(size: f32, repeat: f32) -> Mesh {
    let mut mesh = Plane3d::default().mesh().size(size, size).build();
    if let Some(VertexAttributeValues::Float32x2(uv)) = mesh.attribute_mut(Mesh::ATTRIBUTE_UV_0) {
        for v in uv.iter_mut() {
            *v = [v[0] * repeat, v[1] * repeat];
        }
    }
    mesh
}

/// One tile: pale blue-white with a grey grout line, repeating.
fn tile_texture() -> Image {
    let side = 64u32;
    let mut data = Vec::with_capacity((side * side * 4) as usize);
    for y in 0..side {
        for x in 0..side {
            let grout = x < 3 || y < 3;
            let c: [u8; 4] = if grout {
                [150, 150, 145, 255]
            } else {
                [215, 225, 232, 255]
            };
            data.extend_from_slice(&c);
        }
    }
    let mut image = Image::new(
        bevy::render::render_resource::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: 1,
        },
        bevy::render::render_resource::TextureDimension::D2,
        data,
        bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::default(),
    );
    image.sampler = bevy::image::ImageSampler::Descriptor(bevy::image::ImageSamplerDescriptor {
        address_mode_u: bevy::image::ImageAddressMode::Repeat,
        address_mode_v: bevy::image::ImageAddressMode::Repeat,
        ..bevy::image::ImageSamplerDescriptor::linear()
    });
    image
}

/// A clear sky as a cubemap of `side`² faces (+X, -X, +Y, -Y, +Z, -Z), relative luminance: a
/// blue zenith, a pale horizon, a grey-brown ground (the sun itself is the directional light).
/// Made at start-up, so the showcase downloads nothing; Bevy filters it into the diffuse and
/// specular environment light (`GeneratedEnvironmentMapLight`).
fn sky_cubemap(side: u32) -> Image {
    let mut data = Vec::with_capacity((side * side * 6 * 8) as usize);
    for face in 0..6 {
        for y in 0..side {
            for x in 0..side {
                let u = 2.0 * (x as f32 + 0.5) / side as f32 - 1.0;
                let v = 2.0 * (y as f32 + 0.5) / side as f32 - 1.0;
                let d = cube_direction(face, u, v).normalize();
                for c in sky_radiance(d).extend(1.0).to_array() {
                    data.extend_from_slice(&f16_bits(c).to_le_bytes());
                }
            }
        }
    }
    let mut image = Image::new(
        Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: 6,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba16Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_view_descriptor = Some(TextureViewDescriptor {
        dimension: Some(TextureViewDimension::Cube),
        ..default()
    });
    image
}

/// The direction through (u, v) in [-1, 1]² of a cube face, in wgpu's face order and
/// orientation.
fn cube_direction(face: u32, u: f32, v: f32) -> Vec3 {
    match face {
        0 => Vec3::new(1.0, -v, -u),
        1 => Vec3::new(-1.0, -v, u),
        2 => Vec3::new(u, 1.0, v),
        3 => Vec3::new(u, -1.0, -v),
        4 => Vec3::new(u, -v, 1.0),
        _ => Vec3::new(-u, -v, -1.0),
    }
}

/// Relative sky luminance towards `d` (1 at the zenith's blue).
fn sky_radiance(d: Vec3) -> Vec3 {
    let zenith = Vec3::new(0.18, 0.38, 1.00);
    let horizon = Vec3::new(0.85, 0.92, 1.05);
    let ground = Vec3::new(0.50, 0.48, 0.44);
    if d.y < 0.0 {
        return horizon.lerp(ground, (-d.y * 6.0).min(1.0));
    }
    horizon.lerp(zenith, d.y.powf(0.6))
}

/// An f32 as IEEE half-precision bits (round to nearest; the sky's values are small and
/// positive, so no NaN and no overflow handling beyond clamping to the largest half).
fn f16_bits(x: f32) -> u16 {
    let x = x.clamp(0.0, 65504.0);
    if x < 6.1e-5 {
        // Subnormal halves: x / 2^-24.
        return (x / 5.960_464_5e-8).round() as u16;
    }
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    let mantissa = (bits >> 13) & 0x3ff;
    let round = (bits >> 12) & 1;
    (((exponent as u32) << 10 | mantissa) + round) as u16
}
