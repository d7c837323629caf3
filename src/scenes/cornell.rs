//! The seed's test scenes (seed 000 section 4): Cornell-box variants with a diamond, a ring,
//! a glass ball and floating blocks, lit by a point light under the ceiling, each with a
//! caustics volume declared on a node's glTF `extras` around its casters.

use glam::{Quat, Vec3};
use serde_json::json;

use super::{
    CameraDesc, LightDesc, LightKind, SceneDesc, VolumeNode, diffuse, geometry, glass, look_at,
    mirror,
};
use crate::scene::MeshGeometry;

/// A 2 m Cornell box (open at the front): white floor, ceiling and back wall, red left and
/// green right walls, a 300 cd point light 0.1 m under the ceiling, the camera in front.
fn cornell(name: &str) -> SceneDesc {
    let eye = Vec3::new(0.0, 1.0, 3.6);
    let mut s = SceneDesc::new(
        name,
        CameraDesc {
            translation: eye,
            rotation: look_at(eye, Vec3::new(0.0, 0.8, 0.0)),
            fov_y: 45f32.to_radians(),
        },
    );
    let white = s.material("white", diffuse(0.75), false);
    let mut red = diffuse(0.75);
    red.base_color = Vec3::new(0.75, 0.1, 0.1);
    let red = s.material("red", red, false);
    let mut green = diffuse(0.75);
    green.base_color = Vec3::new(0.1, 0.6, 0.1);
    let green = s.material("green", green, false);
    use core::f32::consts::{FRAC_PI_2, PI};
    let walls = [
        ("floor", white, Vec3::ZERO, Quat::IDENTITY),
        (
            "ceiling",
            white,
            Vec3::new(0.0, 2.0, 0.0),
            Quat::from_rotation_x(PI),
        ),
        (
            "back",
            white,
            Vec3::new(0.0, 1.0, -1.0),
            Quat::from_rotation_x(FRAC_PI_2),
        ),
        (
            "left",
            red,
            Vec3::new(-1.0, 1.0, 0.0),
            Quat::from_rotation_z(-FRAC_PI_2),
        ),
        (
            "right",
            green,
            Vec3::new(1.0, 1.0, 0.0),
            Quat::from_rotation_z(FRAC_PI_2),
        ),
    ];
    for (n, m, at, rot) in walls {
        let i = s.add(n, geometry::quad(2.0, 2.0), m, at);
        s.nodes[i].rotation = rot;
    }
    s.lights.push(LightDesc {
        name: "lamp".into(),
        kind: LightKind::Point { candela: 300.0 },
        color: Vec3::ONE,
        translation: Vec3::new(0.0, 1.9, 0.0),
        rotation: Quat::IDENTITY,
    });
    s
}

/// A volume node around a box of `size` centred at `centre`, entry face up (towards the
/// lamp), every other face an exit.
fn volume(s: &mut SceneDesc, centre: Vec3, size: Vec3) {
    s.volumes.push(VolumeNode {
        name: "caustics_volume".into(),
        translation: centre,
        extras: json!({
            "size": size.to_array(),
            "slabs": 3,
            "photons": 20000,
            "entry": "PosY",
            "exit": ["NegY", "PosX", "NegX", "PosZ", "NegZ"],
            "projector_resolution": 200,
            "gbuffer_resolution": 200
        }),
    });
}

/// A brilliant-like gem: a flat table, a crown ring and a pointed pavilion, `facets` sides,
/// flat-shaded (no vertex normals).
pub fn gem(radius: f32, facets: u32) -> MeshGeometry {
    let n = facets.max(3);
    let mut positions = vec![Vec3::new(0.0, 0.25 * radius, 0.0)];
    for i in 0..n {
        let a = i as f32 / n as f32 * core::f32::consts::TAU;
        positions.push(Vec3::new(radius * a.cos(), 0.0, radius * a.sin()));
    }
    positions.push(Vec3::new(0.0, -0.9 * radius, 0.0));
    let culet = n + 1;
    let mut indices = Vec::new();
    for i in 0..n {
        let (a, b) = (1 + i, 1 + (i + 1) % n);
        indices.push([0, b, a]);
        indices.push([culet, a, b]);
    }
    MeshGeometry {
        positions,
        normals: None,
        indices,
    }
}

/// A diamond (IOR 2.42) on a pedestal of air, 0.5 m up.
pub fn cornell_diamond() -> SceneDesc {
    let mut s = cornell("cornell_diamond");
    let m = s.material("diamond", glass(2.42, 0.3), false);
    s.add("diamond", gem(0.3, 16), m, Vec3::new(0.0, 0.6, 0.0));
    volume(&mut s, Vec3::new(0.0, 0.6, 0.0), Vec3::new(0.8, 0.6, 0.8));
    s
}

/// A polished ring floating 0.5 m up, tilted 40 degrees. (Upright under an overhead lamp its
/// walls would be edge-on to the slab probes, which cannot see surfaces parallel to their
/// axis: a limitation of rasterised slabs.)
pub fn cornell_ring() -> SceneDesc {
    let mut s = cornell("cornell_ring");
    let m = s.material("ring", mirror(0.95), true);
    let n = s.add(
        "ring",
        geometry::ring(0.4, 0.15, 128),
        m,
        Vec3::new(0.0, 0.5, 0.0),
    );
    s.nodes[n].rotation = Quat::from_rotation_z(40f32.to_radians());
    volume(&mut s, Vec3::new(0.0, 0.5, 0.0), Vec3::new(1.1, 0.9, 1.1));
    s
}

/// A glass ball (IOR 1.5, radius 0.3 m) 0.6 m up.
pub fn cornell_ball() -> SceneDesc {
    let mut s = cornell("cornell_ball");
    let m = s.material("glass", glass(1.5, 0.6), false);
    s.add(
        "ball",
        geometry::uv_sphere(0.3, 64, 32),
        m,
        Vec3::new(0.0, 0.6, 0.0),
    );
    volume(&mut s, Vec3::new(0.0, 0.6, 0.0), Vec3::splat(0.8));
    s
}

/// Three glass blocks floating at different heights and angles.
pub fn cornell_blocks() -> SceneDesc {
    let mut s = cornell("cornell_blocks");
    let m = s.material("glass", glass(1.5, 0.2), false);
    for (i, (at, angle)) in [
        (Vec3::new(-0.4, 1.1, -0.2), 0.3f32),
        (Vec3::new(0.1, 0.8, 0.1), -0.5),
        (Vec3::new(0.45, 0.5, -0.1), 0.9),
    ]
    .into_iter()
    .enumerate()
    {
        let n = s.add(
            &format!("block{i}"),
            geometry::cuboid(Vec3::new(0.35, 0.15, 0.35)),
            m,
            at,
        );
        s.nodes[n].rotation = Quat::from_euler(glam::EulerRot::YXZ, angle, 0.3 * angle, 0.2);
    }
    volume(&mut s, Vec3::new(0.0, 0.8, -0.05), Vec3::new(1.6, 1.0, 1.0));
    s
}
